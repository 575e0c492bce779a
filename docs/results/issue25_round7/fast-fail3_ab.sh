#!/bin/bash
# A/B: base_s7 and this worktree alternating, R rounds; raw outputs into the results folder
OUT=/work/h-fast-fail3/docs/results/issue25_round7
R=${1:-3}; START=${2:-1}; ORDER=${3:-"/tmp/base_s7 /work/h-fast-fail3"}
cd /work/main
for r in $(seq $START $R); do
  for s in $ORDER; do
    tag=$( [ $s = /tmp/base_s7 ] && echo base || echo ff3 )
    echo "round $r $tag $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> $OUT/fast-fail3_when.txt
    OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $s \
        --only good,whitman2020_g5o5,bpo2024 --feasible 20 --failing 30 --tasks 1 > $OUT/fast-fail3_profile_${tag}_r$r.txt 2>&1
    OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $s \
        --budget 200evals --tasks 2 > $OUT/fast-fail3_ga_${tag}_r$r.txt 2>&1
  done
done
echo finished >> $OUT/fast-fail3_when.txt
