#!/bin/bash
cd /work/main
export OPENBLAS_NUM_THREADS=1
OUT=docs/results/issue25_round7
for r in 1 2 3 4 5 6 7 8; do
  for s in base_s7 main; do
    src=/tmp/$s; [ $s = main ] && src=/tmp/main_final7
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $src --only whitman2020_g5o5,bpo2024 --failing 30 --tasks 1 > $OUT/fail_r${r}_$s.md 2>&1
  done
done
echo "fail extra end $(date +%T)" >> $OUT/when.txt
