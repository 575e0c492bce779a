#!/bin/bash
# A/B of branch fast-collide against the session start (issue 25, round 6): alternating A (base) and B (branch),
# every run under the benchmark lock with OPENBLAS_NUM_THREADS=1; CPU seconds compared.
# usage: bash fast-collide_ab.sh BASE BRANCH ROUNDS OUTDIR [PREFIX]   (files OUTDIR/PREFIX{front_ga,ik_replay,profile_evaluator}.txt)
set -u
A=$1; B=$2; R=$3; OUT=$4; P=${5:-fast-collide_}
cd /work/main
export OPENBLAS_NUM_THREADS=1
PY=/work/main/.venv/bin/python
for r in $(seq 1 $R); do
  for s in $A $B; do
    echo "### round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> $OUT/${P}front_ga.txt
    flock /tmp/robodesign-bench.lock $PY experiments/bench_front_ga.py --src $s --budget 200evals --tasks 2 >> $OUT/${P}front_ga.txt 2>&1
    echo "### round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> $OUT/${P}ik_replay.txt
    flock /tmp/robodesign-bench.lock $PY experiments/bench_ik_replay.py --src $s --task oven_hard --rounds 3 >> $OUT/${P}ik_replay.txt 2>&1
    echo "### round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> $OUT/${P}profile_evaluator.txt
    flock /tmp/robodesign-bench.lock $PY experiments/profile_evaluator.py --src $s --only good,whitman2020_g5o5,bpo2024 --feasible 20 --failing 30 --tasks 1 >> $OUT/${P}profile_evaluator.txt 2>&1
  done
done
echo done >> $OUT/${P}done.txt
