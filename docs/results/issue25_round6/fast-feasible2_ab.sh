#!/bin/bash
# A/B alternating: base_s6 vs fast-feasible2, profile_evaluator good x20 and bench_plan, N rounds
OUT=$1; N=${2:-3}
cd /work/main
for r in $(seq 1 $N); do for s in /tmp/base_s6 /work/h-fast-feasible2; do
  echo "## round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)"
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock /work/main/.venv/bin/python -W ignore experiments/profile_evaluator.py --src $s --only good --feasible 20 2>&1 | tail -1
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock /work/main/.venv/bin/python -W ignore docs/results/issue25_round6/fast-feasible2_bench_plan.py $s 2>&1 | tail -1
done; done > $OUT 2>&1
