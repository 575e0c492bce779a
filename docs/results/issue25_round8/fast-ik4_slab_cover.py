import sys, collections
sys.path.insert(0, sys.argv[1] + '/src')
NS = int(sys.argv[2])
exec(open(__import__('os').path.join(__import__('os').path.dirname(__file__), 'fast-ik4_micro_head.py')).read())
from robodesign.model import collision_cull as cc
from scipy.spatial import ConvexHull
import pinocchio as pin
def slab_cover(shape, S):
    P = np.asarray(shape.points(), dtype=float).reshape(-1, 3)
    h = ConvexHull(P); V = P[h.vertices]
    edges = set()
    for s in h.simplices:
        for a, b in ((s[0], s[1]), (s[1], s[2]), (s[0], s[2])): edges.add((min(a, b), max(a, b)))
    lo, hi = P.min(0), P.max(0); ax = int(np.argmax(hi - lo))
    cuts = np.linspace(lo[ax], hi[ax], S + 1)
    out = []
    for i in range(S):
        a, b = cuts[i], cuts[i + 1]
        pts = [v for v in V if a <= v[ax] <= b]
        for e0, e1 in edges:
            p0, p1 = P[e0], P[e1]
            for c in (a, b):
                if (p0[ax] - c) * (p1[ax] - c) < 0:
                    t = (c - p0[ax]) / (p1[ax] - p0[ax]); pts.append(p0 + t * (p1 - p0))
        pts = np.array(pts)
        if len(pts) == 0: continue
        ctr = 0.5 * (pts.min(0) + pts.max(0))
        out.append((ctr, np.sqrt(((pts - ctr) ** 2).sum(1)).max()))
    return out
cache = {}
def cover(shape):
    if id(shape) not in cache: cache[id(shape)] = (shape, slab_cover(shape, NS))
    return cache[id(shape)][1]
stats = collections.Counter()
orig_col = cc.CollisionCuller.collides
gds = {}
def col(self, q, pairs):
    ks = list(pairs)
    robot = self.robot; gm = robot.geom_model
    gd = gds.setdefault(id(gm), pin.GeometryData(gm))
    pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
    for k in ks:
        cp = gm.collisionPairs[k]
        A, B = gm.geometryObjects[cp.first].geometry, gm.geometryObjects[cp.second].geometry
        if cp.second >= robot.n_collision_geometries or not type(A).__name__.startswith('Convex') or not type(B).__name__.startswith('Convex'):
            continue
        MA, MB = gd.oMg[cp.first], gd.oMg[cp.second]
        clear = all(np.linalg.norm(MA.act(ca) - MB.act(cb)) > ra + rb + 1e-4 for ca, ra in cover(A) for cb, rb in cover(B))
        stats['convex asks'] += 1; stats['cleared'] += clear
    return orig_col(self, q, ks)
cc.CollisionCuller.collides = col
for s in range(10):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
print("slabs", NS, stats)
