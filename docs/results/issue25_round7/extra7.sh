#!/bin/bash
cd /work/main
export OPENBLAS_NUM_THREADS=1
OUT=docs/results/issue25_round7
for r in 1 2 3 4 5 6; do
  for s in base_9d main; do
    src=/tmp/$s; [ $s = main ] && src=/tmp/main_final7
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 --only bpo2024 > $OUT/ga_bpo_r${r}_$s.txt 2>&1
  done
done
echo "bpo extra end $(date +%T)" >> $OUT/when.txt
flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_checker.py --ab /tmp/base_s7/src /tmp/main_final7/src --rounds 5 --samples 350 --repeat 7 > $OUT/check350_ab.txt 2>&1
echo "check350 end $(date +%T)" >> $OUT/when.txt
