"""Counts the distance-field cells the judge's sweep fills over PTP_3's 22 fresh feasible arms, and how many of them
sit at samples whose two steps the box bound plus the known cells already certify."""
import sys, pickle
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.model import sweep_clearance as sc
from robodesign.model.sweep_bounds import BOUND_SLACK, _kernel
ik_kernel.warm_up(); warm_up()
stats = {"all": 0, "needed": 0, "calls": 0}
orig = sc.open_steps
def cells(robot, TG, geo, ob, spheres):
    o = robot.geom_model.geometryObjects[ob]
    f = sc.distance_field(o.geometry, o.placement.homogeneous)
    cen = spheres[0][geo]
    T = TG[:, geo]; C = np.einsum("kgij,gj->kgi", T[..., :3, :3], cen) + T[..., :3, 3]
    fa = np.floor(C / f.cell)
    inside = ((fa >= f.grid_lo) & (fa < f.grid_lo + f.grid_dim)).all(axis=2)
    la = (fa - f.grid_lo).astype(np.int64)
    flat = (la[..., 0] * f.grid_dim[1] + la[..., 1]) * f.grid_dim[2] + la[..., 2]
    unknown = inside & np.isnan(f.values[np.where(inside, flat, 0)])
    return flat, unknown
def patched(checker, TG, sched, dQ, ext):
    spheres = getattr(checker, "_spheres", None)
    if TG is not None and spheres is not None and len(TG) >= 2:
        obst = np.array(checker._obst); mov = np.array(checker._mov)
        for ob in np.unique(obst[obst >= 0]).tolist():
            c = np.flatnonzero(obst == ob)
            flat, unk = cells(checker.robot, TG, mov[c], ob, spheres)
            if not unk.any():
                continue
            # the bounds without the unknown cells: fill nothing
            o = checker.robot.geom_model.geometryObjects[ob]
            f = sc.distance_field(o.geometry, o.placement.homogeneous)
            saved = f.fill
            f.fill = lambda flat_, v=f.values: v[flat_]
            F = sc.clearance_bounds(checker.robot, TG, mov[c], ob, spheres) - checker.margins[c]
            f.fill = saved
            n = len(TG)
            fastest = dQ.max(axis=1) * (1 + 1e-9)
            keep = np.maximum(ext, fastest[:, None] * (checker.W.sum(axis=0)[c] / sc.ADVANCE_SHARE))
            cert = ((F[:-1] + F[1:]) - sched[:, c] * BOUND_SLACK) * 0.5 - 1e-12 > keep
            need = np.zeros((n, len(c)), bool)
            need[:-1] |= ~cert; need[1:] |= ~cert
            stats["all"] += len(np.unique(flat[unk])); stats["needed"] += len(np.unique(flat[unk & need]))
            stats["calls"] += 1
    return orig(checker, TG, sched, dQ, ext)
import robodesign.model.sweep as sw
sw.open_steps = patched
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for c in feas:
    ev.evaluate(c)
print(stats)
