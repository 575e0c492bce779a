#!/bin/bash
# The final A/B of issue 25 round 5 (fast-ikfail): main (/tmp/hi_base) vs the branch (/tmp/hi_new), alternately,
# every run under the bench lock with OPENBLAS_NUM_THREADS=1.
D=/work/h-ikfail/docs/results/issue25_round5
cd /work/h-ikfail
export OPENBLAS_NUM_THREADS=1
PY=/work/main/.venv/bin/python
for i in 1 2 3; do for src in /tmp/hi_base /tmp/hi_new; do
  echo "## alternation $i src $src" >> $D/ik_replay_oven_hard.txt
  flock /tmp/robodesign-bench.lock $PY experiments/bench_ik_replay.py --src $src --task oven_hard --rounds 3 >> $D/ik_replay_oven_hard.txt 2>/dev/null
done; done
for i in 1 2 3; do for src in /tmp/hi_base /tmp/hi_new; do
  echo "## alternation $i src $src" >> $D/ik_replay_whitman_0001.txt
  flock /tmp/robodesign-bench.lock $PY experiments/bench_ik_replay.py --src $src --task whitman2020_g5o5_xyz_any_rot_s0_0001 --rounds 3 >> $D/ik_replay_whitman_0001.txt 2>/dev/null
done; done
for i in 1 2 3; do for src in /tmp/hi_base /tmp/hi_new; do
  echo "## alternation $i src $src" >> $D/front_ga.txt
  flock /tmp/robodesign-bench.lock $PY experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 >> $D/front_ga.txt 2>/dev/null
done; done
for i in 1 2; do for src in /tmp/hi_base /tmp/hi_new; do
  echo "## alternation $i src $src" >> $D/profile_evaluator.txt
  flock /tmp/robodesign-bench.lock $PY experiments/profile_evaluator.py --src $src --only whitman2020_g5o5,bpo2024 --failing 30 --tasks 1 >> $D/profile_evaluator.txt 2>/dev/null
done; done
echo finished >> $D/final_ab.done
