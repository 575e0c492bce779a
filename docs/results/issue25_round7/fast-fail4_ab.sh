#!/bin/bash
# fast-fail4's A/B: rounds $1..$2 (default 1..3), alternating the session start (/tmp/base_s7) and this branch
# (order: $3, default "/tmp/base_s7 /work/h-fast-fail4"); run from /work/main. Outputs next to this script.
OUT=/work/h-fast-fail4/docs/results/issue25_round7
for r in $(seq ${1:-1} ${2:-3}); do for s in ${3:-/tmp/base_s7 /work/h-fast-fail4}; do
  tag=$([ "$s" = /tmp/base_s7 ] && echo base || echo ff4)
  echo "round $r $tag $(date -u +%H:%M:%S) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/fast-fail4_when.txt
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $s \
      --only whitman2020_g5o5,bpo2024 --failing 30 --tasks 1 > $OUT/fast-fail4_profile_${tag}_r$r.txt 2>&1
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $s \
      --budget 200evals --tasks 2 > $OUT/fast-fail4_ga_${tag}_r$r.txt 2>&1
done; done
