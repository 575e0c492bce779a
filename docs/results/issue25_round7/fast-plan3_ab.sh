#!/bin/bash
# fast-plan3's A/B, alternating /tmp/base_s7 (this session's start, 1b535a2) and the branch's checkout, ROUNDS
# rounds, under the benchmark lock: profile_evaluator (the good PTP_3 arm, 20 seeds) and bench_front_ga (200
# evaluations on two whitman2020 and two bpo2024 tasks). Usage: bash fast-plan3_ab.sh BRANCH OUT_PREFIX ROUNDS
B=$1; OUT=$2; N=${3:-3}
cd /work/main
for r in $(seq 1 $N); do for s in /tmp/base_s7 $B; do
  echo "## round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" | tee -a ${OUT}_profile.txt >> ${OUT}_ga.txt
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $s \
      --only good --feasible 20 --failing 30 --tasks 1 2>&1 | grep "^| feasible" >> ${OUT}_profile.txt
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $s \
      --budget 200evals --tasks 2 2>&1 | grep "^{" >> ${OUT}_ga.txt
done; done
