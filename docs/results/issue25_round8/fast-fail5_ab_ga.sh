#!/bin/bash
# alternating A/B of the genetic search: base_s8 and fast-fail5, rounds given as args
cd /work/main
for r in "$@"; do
  for s in /tmp/base_s8 /tmp/ff5/snap1; do
    n=$(basename $s)
    echo "# round $r $n $(date -u +%T) load $(cut -d' ' -f1 /proc/loadavg)" >> /tmp/ff5/ga_ab_$n.txt
    OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $s --budget 200evals --tasks 2 >> /tmp/ff5/ga_ab_$n.txt 2>&1
  done
done
