#!/bin/bash
# final measurement of issue 25, thirteenth round: paired A/Bs of the final src against the session start (71594ba)
# on fresh PTP_3 arms and the known-good arm, and on the IK failures of the family tasks; against the issue's code
# (9d75d57); the feasible stage shares of fresh arms (profile rounds); the 350-sample check; the genetic search
# against 9d75d57. MAIN, START: checkouts (their kernels compiled); ROOT: the worktree whose experiments/ run and
# which receives the outputs; PY: its Python.
cd ${ROOT:-/work/main}
PY=${PY:-.venv/bin/python}
export OPENBLAS_NUM_THREADS=1
OUT=docs/results/issue25_round13/final
M=${MAIN:-/tmp/main_final13}
S=${START:-/tmp/main_s13a}
mkdir -p $OUT/ptp3
L="flock /tmp/robodesign-bench.lock"
echo "start $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in 1 2; do
  $L $PY experiments/bench_paired.py --a $S --b $M --only ptp3,good --feasible 20 --ptp3-candidates 900 \
      > $OUT/paired_fresh_vs_start_r$r.txt 2>&1
  echo "paired fresh r$r done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
done
$L $PY experiments/bench_paired.py --a $S --b $M --feasible 20 --candidates 300 > $OUT/paired_fail_vs_start.txt 2>&1
$L $PY experiments/bench_paired.py --a /tmp/base_9d --b $M --only ptp3,good --feasible 20 --ptp3-candidates 900 \
    > $OUT/paired_fresh_vs_9d.txt 2>&1
echo "paired done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in 1 2 3; do
  for s in start main; do
    src=$S; [ $s = main ] && src=$M
    $L $PY experiments/bench_fresh_stream.py --src $src > $OUT/ptp3/stream_r${r}_$s.txt 2>&1
  done
done
echo "streams done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
$L $PY experiments/bench_checker.py --ab $S/src $M/src --rounds 7 --samples 350 > $OUT/check350_ab.txt 2>&1
echo "check done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in 1 2; do
  for s in base_9d main; do
    src=/tmp/$s; [ $s = main ] && src=$M
    $L $PY experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 > $OUT/ga_r${r}_$s.txt 2>&1
  done
done
echo "end $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in 1 2; do
  for s in start main; do
    src=$S; [ $s = main ] && src=$M
    $L $PY experiments/bench_fresh_stream.py --src $src --ga 600 > $OUT/ga_ptp3_600_r${r}_$s.txt 2>&1
  done
done
echo "ga ptp3 done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
