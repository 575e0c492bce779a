#!/bin/bash
# A/B of fast-fail2 against the session-start checkout, alternating: bash fast-fail2_ab.sh ROUNDS NEW_CHECKOUT OUT_PREFIX
# (run from anywhere; the scripts and tasks are main's; every run under the benchmark lock, one BLAS thread)
set -u
ROUNDS=$1; NEW=$2; OUT=$3
cd /work/main
export OPENBLAS_NUM_THREADS=1
for r in $(seq 1 $ROUNDS); do
  for s in /tmp/base_s6 $NEW; do
    echo "## round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" | tee -a ${OUT}_profile.txt ${OUT}_ga.txt > /dev/null
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $s \
        --only whitman2020_g5o5,bpo2024 --failing 30 --tasks 1 >> ${OUT}_profile.txt 2>&1
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $s --budget 200evals --tasks 2 \
        >> ${OUT}_ga.txt 2>&1
  done
done
