#!/bin/bash
# A/B: base_s7 vs fast-check3, alternating; per-stage medians of the feasible PTP_3 evaluation and the GA search
R=/work/h-fast-check3/docs/results/issue25_round7
cd /work/main
export OPENBLAS_NUM_THREADS=1
for r in 1 2 3 4 5; do
  for s in base:/tmp/base_s7 fc3:/work/h-fast-check3; do
    name=${s%%:*}; src=${s#*:}
    [ "$r$name" = "1base" ] && continue  # (round 1's base run made by hand)
    echo "$(date -u +%T) round $r $name load $(cut -d' ' -f1 /proc/loadavg)" >> $R/fast-check3_when.txt
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/profile_evaluator.py --src $src --only good --feasible 20 > $R/fast-check3_profile_r${r}_$name.txt 2>/dev/null
  done
done
for r in 1 2 3; do
  for s in base:/tmp/base_s7 fc3:/work/h-fast-check3; do
    name=${s%%:*}; src=${s#*:}
    echo "$(date -u +%T) ga round $r $name load $(cut -d' ' -f1 /proc/loadavg)" >> $R/fast-check3_when.txt
    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_front_ga.py --src $src --budget 200evals --tasks 2 2>/dev/null > $R/fast-check3_ga_r${r}_$name.txt
  done
done
echo done >> $R/fast-check3_when.txt
