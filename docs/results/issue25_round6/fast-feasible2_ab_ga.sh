#!/bin/bash
cd /work/main
for r in 1 2 3; do for s in /tmp/base_s6 /work/h-fast-feasible2; do
  echo "## round $r src $s $(date -u +%H:%M:%S) load $(cut -d' ' -f1 /proc/loadavg)"
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock /work/main/.venv/bin/python -W ignore experiments/bench_front_ga.py --src $s --budget 200evals --tasks 2 2>&1 | grep '^{'
done; done
