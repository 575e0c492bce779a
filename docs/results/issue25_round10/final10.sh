#!/bin/bash
# final measurement of issue 25, tenth round: paired A/Bs of main's final src against the session start (616c4e9)
# and the issue's code (9d75d57); ten alternating sequential profile rounds (steady state: 200 IK failures per
# family task, and the first 30); the 350-sample check; the genetic search against 9d75d57
cd /work/main
export OPENBLAS_NUM_THREADS=1
OUT=docs/results/issue25_round10
M=${MAIN:-/tmp/main_final10}
S=${START:-/tmp/main_final9}
mkdir -p $OUT/p200 $OUT/p30
L="flock /tmp/robodesign-bench.lock"
echo "start $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg) main=$(git rev-parse --short HEAD)" >> $OUT/when.txt
for r in 1 2; do
  $L .venv/bin/python experiments/bench_paired.py --a $S --b $M --feasible 20 --candidates 300 > $OUT/paired_final_vs_start_r$r.txt 2>&1
  echo "paired start r$r done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
done
$L .venv/bin/python experiments/bench_paired.py --a /tmp/base_9d --b $M --feasible 20 --candidates 300 > $OUT/paired_final_vs_9d.txt 2>&1
echo "paired 9d done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in $(seq 1 ${ROUNDS:-8}); do
  for s in start main; do
    src=$S; [ $s = main ] && src=$M
    $L .venv/bin/python experiments/profile_evaluator.py --src $src --only good,whitman2020_g5o5,bpo2024 --feasible 20 --failing 200 --tasks 1 --max 2000 > $OUT/p200/profile_r${r}_$s.md 2>&1
    $L .venv/bin/python experiments/profile_evaluator.py --src $src --only whitman2020_g5o5,bpo2024 --failing 30 --tasks 1 > $OUT/p30/profile_r${r}_$s.md 2>&1
  done
done
mkdir -p $OUT/ptp3
for r in 1 2 3; do   # random feasible PTP_3 candidates (new assemblies, not the one known-good arm again and again)
  for s in start main; do
    src=$S; [ $s = main ] && src=$M
    $L .venv/bin/python experiments/profile_evaluator.py --src $src --only ptp3 --feasible 20 --failing 30 > $OUT/ptp3/profile_r${r}_$s.md 2>&1
  done
done
echo "profiles done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
$L .venv/bin/python experiments/bench_checker.py --ab $S/src $M/src --rounds 7 --samples 350 > $OUT/check350_ab.txt 2>&1
echo "check done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in 1 2; do
  for s in base_9d main; do
    src=/tmp/$s; [ $s = main ] && src=$M
    $L .venv/bin/python experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 > $OUT/ga_r${r}_$s.txt 2>&1
  done
done
echo "end $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
