#!/bin/bash
# final measurement of issue 25, ninth round: paired A/Bs of main's final src against the session start (67dfe23)
# and the issue's code (9d75d57); the 350-sample check; the genetic search against 9d75d57
cd /work/main
export OPENBLAS_NUM_THREADS=1
OUT=docs/results/issue25_round9
M=${MAIN:-/tmp/main_final9}
mkdir -p $OUT
echo "start $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg) main=$(git rev-parse --short HEAD)" >> $OUT/when.txt
for r in 1 2; do
  flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_paired.py --a /tmp/base_s9 --b $M --feasible 20 --candidates 300 > $OUT/paired_final_vs_s9_r$r.txt 2>&1
  echo "paired s9 r$r done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
done
flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_paired.py --a /tmp/base_9d --b $M --feasible 20 --candidates 300 > $OUT/paired_final_vs_9d.txt 2>&1
echo "paired 9d done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_checker.py --ab /tmp/base_s9/src $M/src --rounds 7 --samples 350 > $OUT/check350_ab.txt 2>&1
echo "check done $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
for r in 1 2; do
  for s in base_9d main; do
    src=/tmp/$s; [ $s = main ] && src=$M
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 > $OUT/ga_r${r}_$s.txt 2>&1
  done
done
echo "end $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
