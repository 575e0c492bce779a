#!/bin/bash
# A/B of /tmp/base_s7 (1b535a2) and /tmp/fp_head2 (31c01b9), alternating, under the bench lock
OUT=/work/h-fast-pairs/docs/results/issue25_round7
cd /work/main
export OPENBLAS_NUM_THREADS=1
for r in 1 2 3; do for s in base_s7 fp_head2; do
  name=$s; [ $s = fp_head2 ] && name=head2
  echo "r$r $name good start $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/fast-pairs_ab2_when.txt
  flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src /tmp/$s --only good --feasible 20 --tasks 1 > $OUT/fast-pairs_good2_r${r}_$name.txt 2>&1
  echo "r$r $name ga start $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> $OUT/fast-pairs_ab2_when.txt
  flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src /tmp/$s --budget 200evals --tasks 2 > $OUT/fast-pairs_ga2_r${r}_$name.txt 2>&1
done; done
echo "end $(date -u +%T)" >> $OUT/fast-pairs_ab2_when.txt
