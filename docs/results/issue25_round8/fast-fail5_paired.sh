#!/bin/bash
cd /work/main
while pgrep -f /tmp/ff5/ab_ga.sh > /dev/null; do sleep 5; done
for spec in "kin2 /tmp/ff5/snap_kin" "4 /tmp/ff5/snap1"; do
  set -- $spec
  echo "# $1 $(date -u +%T) load $(cut -d' ' -f1 /proc/loadavg)" > /tmp/ff5/paired_$1.txt
  OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_paired.py --a /tmp/base_s8 --b $2 --only whitman2020_g5o5,bpo2024 --candidates 300 >> /tmp/ff5/paired_$1.txt 2>&1
done
