import sys, collections
sys.path.insert(0, sys.argv[1] + '/src')
exec(open(__import__('os').path.join(__import__('os').path.dirname(__file__), 'fast-ik4_micro_head.py')).read())
from robodesign.model import collision_cull as cc
import pinocchio as pin
stats = collections.Counter(); hitpos = collections.Counter(); pairs_asked = collections.Counter(); pairs_hit = collections.Counter()
orig_col = cc.CollisionCuller.collides
names = {}
def col(self, q, pairs):
    ks = list(pairs)
    r = orig_col(self, q, ks)
    gm = self.robot.geom_model
    for k in ks:
        cp = gm.collisionPairs[k]; a, b = gm.geometryObjects[cp.first], gm.geometryObjects[cp.second]
        names[k] = (a.name, type(a.geometry).__name__, b.name, type(b.geometry).__name__)
        pairs_asked[k] += 1
    stats['calls'] += 1; stats['hit'] += r; stats['npairs'] += len(ks)
    if r: pairs_hit[self._last_hit] += 1
    return r
cc.CollisionCuller.collides = col
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
print(stats)
for k, n in pairs_asked.most_common(30):
    print(k, n, pairs_hit[k], names[k])
