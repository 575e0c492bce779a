import sys, collections, pickle
sys.path.insert(0, sys.argv[1] + "/src")
from pathlib import Path
import numpy as np
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.model.collision_cull as C
import robodesign.model.inner_spheres as I
import pinocchio as pin
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
rec = []
oa = C.CollisionCuller._ask
def ask(self, q, ks):
    r = oa(self, q, ks)
    rec.append((self, np.array(q, float).copy(), r, self._last_hit if r else -1, list(ks)))
    return r
C.CollisionCuller._ask = ask
for s in range(5):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
C.CollisionCuller._ask = oa
cul = rec[0][0]
objs = cul.robot.geom_model.geometryObjects
for g in (8, 10, 17):
    o = objs[g]; print(g, o.name, type(o.geometry).__name__, getattr(o.geometry, "num_points", None), "parent", o.parentJoint)
hits = [(c, q) for c, q, r, k, ks in rec if r and k >= 0 and (int(c.first[k]), int(c.second[k])) == (10, 17)]
print("hits (10,17):", len(hits), "asks", len(rec))
def proven(c, q, a, b, spheres):
    r = c.robot
    pin.forwardKinematics(r.kinematic_model, r.data, q)
    k = [i for i in range(c.n_pairs) if (c.first[i], c.second[i]) == (a, b)][0]
    lim = c.margin[k] - C.SLACK
    W = []
    for g in (a, b):
        o = objs[g]
        M = r.data.oMi[o.parentJoint] * o.placement
        cen, rad = spheres[g]
        W.append(((M.rotation @ cen.T).T + M.translation, rad))
    (ca, ra), (cb, rb) = W
    d = np.linalg.norm(ca[:, None] - cb[None], axis=2)
    return bool((d < ra[:, None] + rb[None] + lim).any())
for ms, grid in ((4, 16), (8, 16), (16, 24), (32, 32), (64, 32)):
    I.MAX_SPHERES, I.GRID = ms, grid
    sp = {g: I._inner_spheres(objs[g].geometry) for g in (10, 17)}
    n = sum(proven(c, q, 10, 17, sp) for c, q in hits)
    print("MAX_SPHERES", ms, "GRID", grid, "spheres", len(sp[10][1]), len(sp[17][1]), "proven", n, "of", len(hits))
import coal
k = [i for i in range(cul.n_pairs) if (cul.first[i], cul.second[i]) == (10, 17)][0]
print("margin", cul.margin[k], "SLACK", C.SLACK)
ds, vv = [], []
for c, q in hits[:200]:
    r = c.robot
    pin.forwardKinematics(r.kinematic_model, r.data, q)
    Ms = [r.data.oMi[objs[g].parentJoint] * objs[g].placement for g in (10, 17)]
    req = coal.DistanceRequest(); res = coal.DistanceResult()
    d = coal.distance(objs[10].geometry, coal.Transform3s(Ms[0].rotation, Ms[0].translation), objs[17].geometry, coal.Transform3s(Ms[1].rotation, Ms[1].translation), req, res)
    P = [(M.rotation @ np.asarray(objs[g].geometry.points()).reshape(-1, 3).T).T + M.translation for M, g in zip(Ms, (10, 17))]
    ds.append(d); vv.append(np.linalg.norm(P[0][:, None] - P[1][None], axis=2).min())
ds, vv = np.array(ds), np.array(vv)
print("coal distance quantiles", np.quantile(ds, [0, .1, .5, .9, 1]))
print("vertex-vertex min quantiles", np.quantile(vv, [0, .1, .5, .9, 1]))
print("vertex proof (vv < margin - slack):", (vv < cul.margin[k] - C.SLACK).sum(), "of", len(vv))
from scipy.spatial import ConvexHull
def hull(g):
    pts = np.asarray(objs[g].geometry.points()).reshape(-1, 3)
    return pts, ConvexHull(pts).equations
H = {g: hull(g) for g in (10, 17)}
print("faces", len(H[10][1]), len(H[17][1]))
cnt = 0; depth = []
for c, q in hits:
    r = c.robot
    pin.forwardKinematics(r.kinematic_model, r.data, q)
    Ms = {g: r.data.oMi[objs[g].parentJoint] * objs[g].placement for g in (10, 17)}
    ok = False; best = 1.0
    for a, b in ((10, 17), (17, 10)):
        Rab = Ms[b].inverse() * Ms[a]   # a's frame to b's frame
        Pa = (Rab.rotation @ H[a][0].T).T + Rab.translation
        s = (Pa @ H[b][1][:, :3].T + H[b][1][:, 3]).max(axis=1)   # max face distance per vertex (<0 inside)
        best = min(best, s.min())
        ok |= bool((s < -C.SLACK).any())
    cnt += ok; depth.append(best)
print("vertex-in-hull proof:", cnt, "of", len(hits), "depth quantiles", np.quantile(depth, [0, .1, .5, .9, 1]))
