#!/bin/bash
# fast-plan3's A/B: profile_evaluator (the good PTP_3 arm, 20 seeds) alternating /tmp/base_s7 and the branch's
# checkout, ROUNDS rounds, under the benchmark lock. Usage: bash fast-plan3_ab.sh BRANCH_CHECKOUT OUT_FILE ROUNDS
B=$1; OUT=$2; N=${3:-3}
cd /work/main
for r in $(seq 1 $N); do for s in /tmp/base_s7 $B; do
  echo "## round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)" >> $OUT
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $s \
      --only good --feasible 20 --failing 30 --tasks 1 2>&1 | grep "^| feasible" >> $OUT
done; done
