#!/bin/bash
# final alternating measurement of issue 25, seventh round: 9d75d57, 1b535a2 (session start) and main's final src
cd /work/main
export OPENBLAS_NUM_THREADS=1
OUT=docs/results/issue25_round7
mkdir -p $OUT
R=${ROUNDS:-5}
echo "start $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg) main=$(git rev-parse --short HEAD)" >> $OUT/when.txt
for r in $(seq 1 $R); do
  for s in base_9d base_s7 main; do
    src=/tmp/$s; [ $s = main ] && src=/tmp/main_final7
    echo "round $r $s profile $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $src --only good,whitman2020_g5o5,bpo2024 --feasible 20 --failing 30 --tasks 1 > $OUT/profile_r${r}_$s.md 2>&1
    echo "round $r $s ga $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 > $OUT/ga_r${r}_$s.txt 2>&1
  done
done
echo "end $(date +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/when.txt
