"""Capture the lm_batch / lm_repair calls of the PTP_3 replay (pickled args) for kernel micro-benchmarks."""
import sys, copy, pickle
sys.path.insert(0, sys.argv[1] + '/src')
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from pathlib import Path
import numpy as np
S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
B, D = [], []
ob, od = ik_kernel.lm_batch, ik_kernel.lm_repair
def rb(*a):
    B.append(copy.deepcopy(a)); return ob(*a)
def rd(*a):
    D.append(copy.deepcopy(a)); return od(*a)
ik_kernel.lm_batch, ik_kernel.lm_repair = rb, rd
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
print(len(B), len(D))
pickle.dump((B, D), open('/tmp/ik7/lmcalls.pkl', 'wb'))
a = B[0]
print('chain', a[6].shape, 'kind', a[7], 'sign', a[8], 'iq', a[9], 'tkind', a[12], 'tvec', a[13], 'E', a[14].shape)
