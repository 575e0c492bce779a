import sys
import os; exec(open(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'ik7_innerexp.py')).read().split("for ms, grid in")[0])
from scipy.spatial import ConvexHull
import robodesign.model.collision_cull as C
def hullE(g):
    pts = np.asarray(objs[g].geometry.points()).reshape(-1, 3)
    h = ConvexHull(pts)
    E = set()
    for s in h.simplices:
        for i in range(3):
            a, b = sorted((int(s[i]), int(s[(i + 1) % 3])))
            E.add((a, b))
    return pts, h.equations, sorted(E)
H = {g: hullE(g) for g in (10, 17)}
print("edges", len(H[10][2]), len(H[17][2]))
tau = C.SLACK
vert = edge = 0
for c, q in hits:
    r = c.robot
    pin.forwardKinematics(r.kinematic_model, r.data, q)
    Ms = {g: r.data.oMi[objs[g].parentJoint] * objs[g].placement for g in (10, 17)}
    v_ok = e_ok = False
    for a, b in ((10, 17), (17, 10)):
        Rab = Ms[b].inverse() * Ms[a]
        P = (Rab.rotation @ H[a][0].T).T + Rab.translation
        eq = H[b][1]
        s = P @ eq[:, :3].T + eq[:, 3]
        v_ok |= bool((s.max(axis=1) < -tau).any())
        for i, j in H[a][2]:
            a0 = s[i] + tau; b0 = s[j] - s[i]   # plane value along t: a0 + b0 t < 0
            lo, hi = 0.0, 1.0
            for aa, bb in zip(a0, b0):
                if bb > 0: hi = min(hi, -aa / bb)
                elif bb < 0: lo = max(lo, -aa / bb)
                elif aa >= 0: hi = -1
            if lo < hi:
                e_ok = True; break
    vert += v_ok; edge += e_ok
print("hits", len(hits), "vertex proofs", vert, "edge proofs", edge)
