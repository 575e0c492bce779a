"""Build every robot of an orders pickle with the robodesign on PYTHONPATH and dump bit-level data."""
import pickle, sys, hashlib
import numpy as np
import pinocchio as pin
import robodesign
from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.model.robot import Robot
from robodesign.model.cell import RobotPool, build_robot

print("robodesign from", robodesign.__file__, file=sys.stderr)
orders = pickle.load(open(sys.argv[1], "rb"))
probs, pools = {}, {}

def se3(P):
    return np.array(P.homogeneous, copy=True)

def inertia(Y):
    return (np.array(Y.lever, copy=True), float(Y.mass), np.array(Y.inertia, copy=True))

def robot_data(r, q):
    m = r.model
    d = {}
    d["name"] = m.name
    d["njoints"], d["nq"], d["nframes0"] = m.njoints, m.nq, m.nframes
    d["joint_names"] = list(m.names)
    d["parents"] = list(m.parents)
    d["joint_types"] = [j.shortname() for j in m.joints]
    d["jointPlacements"] = [se3(P) for P in m.jointPlacements]
    d["inertias"] = [inertia(Y) for Y in m.inertias]
    for k in ("armature", "lowerPositionLimit", "upperPositionLimit", "velocityLimit", "effortLimit"):
        d[k] = np.array(getattr(m, k), copy=True)
    d["gravity"] = np.array(m.gravity.vector, copy=True)
    for k in ("q_lower", "q_upper", "dq_max", "ddq_max", "tau_max", "gear_ratio", "motor_inertia",
              "friction_coulomb", "friction_viscous", "base_pose"):
        d[k] = np.array(getattr(r, k), copy=True)
    d["dof"], d["mass"], d["tcp_frame"] = r.dof, r.mass, r.tcp_frame
    d["instance_labels"] = r.instance_labels
    d["joint_infos"] = [tuple(vars(j).values()) for j in r.joint_infos]
    d["frames0"] = [(f.name, f.parentJoint, f.parentFrame, se3(f.placement), str(f.type), inertia(f.inertia))
                    for f in m.frames]
    d["root_items0"] = [(k, i, np.array(M, copy=True)) for k, i, M in r._root_items]
    d["n_geom"], d["n_self"] = r.n_collision_geometries, r.n_self_collision_pairs
    d["geom_body"] = list(r._geom_body)
    d["direct"] = sorted(tuple(sorted(p)) for p in r._direct_joint_pairs)
    o, R = r.reach_bound()
    d["reach"] = (o, R)
    d["rank"] = r.generic_rank()
    d["fk"] = np.array(r.fk(q), copy=True)
    d["rnea"] = np.array(r.rnea(q, q, q), copy=True)
    d["mm"] = r.mass_matrix(q)
    gm = r.geom_model
    d["geoms"] = [(g.name, g.parentJoint, g.parentFrame, se3(g.placement), type(g.geometry).__name__,
                   g.geometry.computeLocalAABB() or (np.array(g.geometry.aabb_local.min_), np.array(g.geometry.aabb_local.max_)))
                  for g in gm.geometryObjects]
    d["pairs"] = [(cp.first, cp.second) for cp in gm.collisionPairs]
    d["self_coll"] = r.in_self_collision(q)
    d["model_ser0"] = hashlib.md5(r.model.saveToString().encode()).hexdigest()
    r.add_frames()
    d["model_ser"] = hashlib.md5(r.model.saveToString().encode()).hexdigest()
    d["frames"] = [(f.name, f.parentJoint, f.parentFrame, se3(f.placement), str(f.type), inertia(f.inertia))
                   for f in r.model.frames]
    d["inertias_after"] = [inertia(Y) for Y in r.model.inertias]
    d["root_items"] = [(k, i, np.array(M, copy=True)) for k, i, M in r._root_items]
    return d

out = []
rng = np.random.default_rng(1)
for n, (task, mods, order, T) in enumerate(orders):
    key = (task, mods)
    if key not in probs:
        probs[key] = Problem.build(task, mods, "cyc")
        pools[key] = RobotPool(probs[key].task)
    p = probs[key]
    ms = p.module_set
    asm = Assembly.from_order(ms, order)
    r = Robot(ms, asm, base_pose=T)
    q = rng.uniform(-2, 2, r.dof)
    d = robot_data(r, q)
    if T is not None:
        r2 = build_robot(p.task, ms, asm, T)
        d["base_coll"] = r2.base_collisions()
        d["coll"] = r2.in_collision(q)
        rp = pools[key].take(ms, asm, T)
        d["pool_base_coll"] = rp.base_collisions()
        d["pool_coll"] = rp.in_collision(q)
        d["pool_jp"] = [se3(P) for P in rp.model.jointPlacements]
        pools[key].give_back(rp)
        rp = pools[key].take(ms, asm, np.eye(4))
        d["pool2"] = robot_data(rp, q)
        pools[key].give_back(rp)
        r.set_base_pose(np.eye(4))
        r.set_base_pose(T)
        d["again_jp"] = [se3(P) for P in r.model.jointPlacements]
        d["again_frames"] = [se3(f.placement) for f in r.model.frames]
        d["again_geoms"] = [se3(g.placement) for g in r.geom_model.geometryObjects]
    out.append(d)
pickle.dump(out, open(sys.argv[2], "wb"))
print(len(out), "robots dumped", file=sys.stderr)
