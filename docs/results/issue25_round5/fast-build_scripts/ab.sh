#!/bin/bash
# usage: ab.sh rounds   — alternate base / new, each one process
R=${1:-3}
for i in $(seq 1 $R); do
  for s in /tmp/hb_base /work/h-build; do
    echo -n "$s round $i: "
    flock /tmp/robodesign-bench.lock env OPENBLAS_NUM_THREADS=1 PYTHONPATH=$s/src /work/main/.venv/bin/python -W ignore /tmp/hb/bench.py /tmp/hb/orders1000.pkl 5
  done
done
