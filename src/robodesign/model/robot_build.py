"""How :class:`robodesign.model.robot.Robot` builds its pinocchio model from an assembly (its ``_build``).

What a module contributes to every robot it is part of does not depend on the assembly: its bodies' inertias,
the coal shapes of their collision geometry, its joints' pinocchio joint models, the inverses of the poses of a
joint entered backwards, its connectors' entry poses, the suffixes of the names. Those are made once per module
spec (:func:`module_table`, remembered per module object, which is immutable) and the breadth-first walk over
the assembly's bodies (:func:`walk`) only places them: every matrix product is the one the walk always made, in
the same order with the same operands, so the numbers are bit for bit those of a walk that makes everything
itself (the tests check it against such a walk). The products themselves are remembered too (:func:`_products`,
:func:`_placed`): a search builds the same module pairs again and again.
"""
from __future__ import annotations

import math
from collections import deque
from itertools import count
from typing import Dict, List, Optional, Tuple

import numpy as np
import pinocchio as pin

from robodesign.core.errors import AssemblyError
from robodesign.core.spatial import inv
from robodesign.formats.geometry import coal_shapes


def vector_norm(t: np.ndarray) -> float:
    """``float(np.linalg.norm(t))`` of a vector of floats: the square root of ``t.dot(t)`` (numpy's norm of a
    1-D float array is exactly that)."""
    t = t.ravel(order="K")
    return math.sqrt(t.dot(t))


_MEMO: Dict[int, Tuple[object, object]] = {}  # id(spec) → (spec, what _build derives from it alone)


def _memo(spec, make):
    hit = _MEMO.get(id(spec))
    if hit is None or hit[0] is not spec:
        hit = _MEMO[id(spec)] = (spec, make(spec))
    return hit[1]


_SHAPES: Dict[Tuple[int, bool], Tuple[object, Tuple[object, ...]]] = {}   # (id(spec), flag) → (spec, its shapes)


def _coal_shapes(spec, convex_meshes: bool) -> Tuple[object, ...]:
    """:func:`coal_shapes` of a geometry spec, made once per spec and flag (shared by every robot: coal shapes are
    never mutated)."""
    hit = _SHAPES.get((id(spec), convex_meshes))
    if hit is None or hit[0] is not spec:   # (the spec is held: its id is not reused while the entry lives)
        hit = _SHAPES[(id(spec), convex_meshes)] = (spec, coal_shapes(spec, convex_meshes))
    return hit[1]


def _inertia(body) -> "pin.Inertia":
    """The body's inertia (made once per body spec)."""
    hit = _MEMO.get(id(body))
    if hit is None or hit[0] is not body:
        Y = pin.Inertia(body.mass, np.asarray(body.com, float), np.asarray(body.inertia, float))
        hit = _MEMO[id(body)] = (body, Y)
    return hit[1]


_ZERO_INERTIA = pin.Inertia.Zero()
_OP_FRAME = pin.FrameType.OP_FRAME
_EPS = float(np.finfo(float).eps)   # Eigen's epsilon, as in pinocchio's sum of inertias


def _zero_inertias(model: "pin.Model", pending: Dict[int, int], mass: Dict[int, float], j: int) -> None:
    """The zero inertias that adding ``pending[j]`` frames to joint ``j`` adds to it (``addFrame`` adds each frame's
    inertia, zero, at the frame). pinocchio's sum (``InertiaTpl::__pequ__``) then multiplies the joint's centre of
    mass by ``m·(1/m)`` (m: the joint's mass, ``mass[j]``) and changes nothing else: nothing at all where that
    factor is 1, the usual case; else the same operation is made here on pinocchio's zero inertia. The frames
    themselves are added later without it (``Robot.add_frames``)."""
    k = pending.pop(j, 0)
    m = mass.get(j, 0.0)
    if k and m * (1.0 / max(m, _EPS)) != 1.0:
        _add_zeros(model, j, k)


def _add_zeros(model: "pin.Model", j: int, k: int) -> None:
    """Pinocchio's zero inertia added ``k`` times to joint ``j``'s."""
    Y = model.inertias[j]
    for _ in range(k):
        Y += _ZERO_INERTIA
    model.inertias[j] = Y


class ModuleTable:
    """What a module brings to every robot (one per module spec and ``convex_meshes`` flag).

    ``bodies[k]``: (k, body id, its name suffix ``.<body id>``, mass, inertia or None for a massless body, the number
    of its frames (the body's and its connectors'), connectors, collision geometry, joints, the stack of the poses of
    its connectors and collision geometries (None where one is not a C-ordered 4×4 array of floats), those poses) with
    * connectors: (connector id, pose, the Connector, name suffix) per connector of the body;
    * collision geometry: (index in the poses, name suffix, coal shape) per shape of each geometry spec;
    * joints: (the other body's index, its id, reversed, n, Q, joint model or None for a fixed joint, name suffix,
      (module id, joint id, type, reversed), its limits and drivetrain row, P) per joint at the body, in the
      module's order: the joint's frame is at ``M @ P`` (M: the body's placement; P is pose ``n`` of the body's
      products), the other body at ``@ Q``.

    ``connectors``: connector id → (its body's record, its entry pose)."""

    __slots__ = ("module", "bodies", "connectors")

    def __init__(self, module, convex_meshes: bool):
        self.module = module
        index = {b.id: k for k, b in enumerate(module.bodies)}
        self.bodies = tuple((k,) + _body_record(module, b, index, convex_meshes) for k, b in enumerate(module.bodies))
        self.connectors = {c.id: (self.bodies[index[c.body_id]], c.entry_pose)
                           for b in module.bodies for c in b.connectors}


def _body_record(module, body, index: Dict[str, int], convex_meshes: bool) -> tuple:
    conns = tuple((c.id, c.pose, c, f".{c.id}") for c in body.connectors)
    geoms = tuple((g.pose, tuple((f".c{gi}" + (f".{si}" if si else ""), shape)
                                 for si, shape in enumerate(_coal_shapes(g, convex_meshes))))
                  for gi, g in enumerate(body.collision))
    joints: List[tuple] = []
    for jt in module.joints:
        if jt.parent == body.id:
            other, rev = jt.child, False
            P, Q = jt.pose_parent, jt.pose_child
        elif jt.child == body.id:
            other, rev = jt.parent, True
            P, Q = _memo(jt, lambda j: (inv(j.pose_child), inv(j.pose_parent)))
        else:
            continue
        if jt.type == "fixed":
            jm = None
        elif jt.type == "revolute":
            jm = pin.JointModel(pin.JointModelRZ() if not rev else pin.JointModelRevoluteUnaligned(0.0, 0.0, -1.0))
        else:   # (pinocchio copies the joint model into the model it is added to: one serves every robot)
            jm = pin.JointModel(pin.JointModelPZ() if not rev else pin.JointModelPrismaticUnaligned(0.0, 0.0, -1.0))
        L = jt.limits
        row = (L.lower, L.upper, L.velocity, L.acceleration, L.torque, jt.gear_ratio, jt.motor_inertia,
               jt.friction_coulomb, jt.friction_viscous)
        n = len(body.connectors) + len(geoms) + len(joints)   # (M @ P: the body's products, at n)
        joints.append((index[other], other, rev, n, Q, jm, f".{jt.id}", (module.id, jt.id, jt.type, rev), row, P))
    Y = _inertia(body) if body.mass > 0 else None
    poses = tuple([c[1] for c in conns] + [g[0] for g in geoms] + [j[-1] for j in joints])
    stack = np.stack(poses) if poses and all(_plain(P) for P in poses) else None
    flat = tuple((len(conns) + gi, suffix, shape) for gi, (_, shapes) in enumerate(geoms) for suffix, shape in shapes)
    return (body.id, f".{body.id}", body.mass, Y, 1 + len(body.connectors), conns, flat, tuple(joints), stack, poses)


def _plain(P) -> bool:
    """Whether ``M @ P`` is the product that ``(M @ stack)[k]`` makes for ``P`` at ``stack[k]`` (numpy multiplies a
    stack matrix by matrix with the BLAS call it makes for one pair with the same strides): a C-ordered 4×4 array of
    floats."""
    return isinstance(P, np.ndarray) and P.dtype == np.float64 and P.shape == (4, 4) and P.flags.c_contiguous


_TABLES: Dict[Tuple[int, bool], ModuleTable] = {}   # (id(module), flag) → its table (which holds the module)


def module_table(module, convex_meshes: bool) -> ModuleTable:
    """The module's :class:`ModuleTable` (made once per module object and flag)."""
    t = _TABLES.get((id(module), convex_meshes))
    if t is None or t.module is not module:
        t = _TABLES[(id(module), convex_meshes)] = ModuleTable(module, convex_meshes)
    return t


def _tables(ms, module_ids, convex_meshes: bool) -> List[ModuleTable]:
    """:func:`module_table` of each instance's module."""
    modules, out = ms.modules, []
    for mid in module_ids:
        mod = modules.get(mid) or ms[mid]
        t = _TABLES.get((id(mod), convex_meshes))
        out.append(t if t is not None and t.module is mod else module_table(mod, convex_meshes))
    return out


class Walk:
    """What the walk over an assembly's bodies made: the model (joints, bodies, their zero-inertia sums) and the
    robot's lists (see :meth:`robodesign.model.robot.Robot._build`)."""

    def __init__(self, model: "pin.Model", labels: Tuple[str, ...]):
        self.model, self.labels = model, labels
        # per body in walk order: (name, joint, joint's frame, placement, connectors, inertia or None for a massless
        # body, mass, number of its frames): what add_frames places and what add_bodies adds to the joints
        self.bodies: List[tuple] = []
        # per body with collision geometry, in walk order: (name, joint, joint's frame, its products, its table's
        # (n, name suffix, shape) per shape, instance, body id); the objects' specs are made of them on first use
        # (geometry_specs)
        self.geoms: List[tuple] = []
        self.n_geoms = 0
        self.root_geoms: List[Tuple[int, np.ndarray, object]] = []   # (index, placement, shape) on joint 0
        # (token of its placement, id of its record) per body with those objects: they decide the objects' placements
        # and shapes (the products' memory; module tables are never dropped, so the ids are not reused)
        self.root_key: List[Tuple[int, int]] = []
        # (kind, index, base-frame placement) of the joints and objects on joint 0: the remembered products themselves
        # (read-only, shared by robots: the base pose multiplies them, nothing writes them)
        self.root_items: List[Tuple[str, int, np.ndarray]] = []
        self.joints: List[tuple] = []   # (name, instance, module id, joint id, type, reversed) per joint
        self.rows: List[tuple] = []     # their limits and drivetrains
        self.free: List[tuple] = []   # free connectors: (connector, joint, body placement, connector placement)
        self.direct_joint_pairs: List[tuple] = []   # ((instance, body), (instance, body)) per joint met
        self.joint_frame: Dict[int, int] = {0: 0}
        self.joint_ops: List[tuple] = []   # (parent, joint model, placement as an SE3, name) per joint, in joint order
        # per joint, in joint order: vector_norm of its placement's translation (a joint on the world is placed again
        # by the base pose: its entry holds the walk's placement); of the TCP frame's (finish)
        self.joint_norms: List[float] = []
        self.tcp_norm = 0.0
        self.mass = 0.0
        self.bodies_added = False   # (add_bodies: once per model, also for shallow copies of its robot)


_LABELS: Dict[Tuple[str, ...], Tuple[str, ...]] = {}   # module ids → their instance_labels

# The walk's products, remembered. A body's placement M is made of table objects alone (module tables live as long
# as their modules, so their ids are not reused): the base connector's entry pose, or a joint's Q, times the
# products of the bodies since then. Such a placement is named by a token: the id of its table object, or a number
# below zero given to ``Ps[n] @ T`` of the body named (token, id(rec)). The same operands give the same BLAS
# product, so a remembered product is bit for bit the one the walk would make. They are read-only: robots share them.
_PRODUCTS: Dict[Tuple[int, int], tuple] = {}        # (token of M, id(rec)) → (M @ each of the body's poses)
_PLACED: Dict[tuple, Tuple[np.ndarray, int]] = {}   # (token of M, id(rec), n, id(T)) → (Ps[n] @ T, its token)
_JOINT_SE3: Dict[tuple, Tuple["pin.SE3", float]] = {}   # (token of M, id(rec), n) → (a joint's placement
#                                                           pin.SE3(Ps[n]), vector_norm of its translation)
_PRODUCTS_MAX = 1 << 16
_TOKENS = count(-1, -1)   # (never reused, also after a clear)


def _make_room(memo: dict) -> None:
    """All three memories of the walk's products forgotten where ``memo`` holds ``_PRODUCTS_MAX`` entries (the
    tokens are never reused, so a walk under way only makes its products again)."""
    if len(memo) >= _PRODUCTS_MAX:
        _PRODUCTS.clear()
        _PLACED.clear()
        _JOINT_SE3.clear()


def _products(token: int, rec: tuple, M: np.ndarray):
    """``M @`` each pose of the body ``rec`` (its connectors', then its collision geometries', then its joints'):
    one stacked product where the poses are a stack, else one per pose; remembered per token."""
    Ps = _PRODUCTS.get((token, id(rec)))
    if Ps is None:
        stack = rec[9]
        Ps = M @ stack if stack is not None else tuple(M @ P for P in rec[10])
        for P in (Ps,) if stack is not None else Ps:
            P.setflags(write=False)
        _make_room(_PRODUCTS)
        _PRODUCTS[(token, id(rec))] = Ps
    return Ps


def _placed(token: int, rec: tuple, Ps, n: int, T: np.ndarray) -> Tuple[np.ndarray, int]:
    """``Ps[n] @ T`` (Ps: the products of the body ``rec`` placed at the token's M) and its token; remembered."""
    key = (token, id(rec), n, id(T))
    hit = _PLACED.get(key)
    if hit is None:
        M = Ps[n] @ T
        M.setflags(write=False)
        _make_room(_PLACED)
        hit = _PLACED[key] = (M, next(_TOKENS))
    return hit


def _joint_se3(token: int, rec: tuple, Ps, n: int) -> Tuple["pin.SE3", float]:
    """(``pin.SE3(Ps[n])``, the placement of a joint of the body ``rec`` placed at the token's M, and
    :func:`vector_norm` of its translation, the joint's term of ``Robot.reach_bound``); remembered (pinocchio copies
    the SE3 into the model it is added to, so robots share it; the model's copy has the same translation)."""
    key = (token, id(rec), n)
    hit = _JOINT_SE3.get(key)
    if hit is None:
        _make_room(_JOINT_SE3)
        X = pin.SE3(Ps[n])
        hit = _JOINT_SE3[key] = (X, vector_norm(X.translation))
    return hit


def instance_labels(module_ids) -> Tuple[str, ...]:
    """Each instance's label: its module id, with ``-k`` for the k-th repetition of the id (remembered per tuple of
    ids: a search builds each order again at its base poses, and in its ask)."""
    key = tuple(module_ids)
    labels = _LABELS.get(key)
    if labels is None:
        counts: Dict[str, int] = {}
        out = []
        for mid in key:
            k = counts.get(mid, 0)
            out.append(mid if k == 0 else f"{mid}-{k}")
            counts[mid] = k + 1
        if len(_LABELS) >= 4096:
            _LABELS.clear()
        labels = _LABELS[key] = tuple(out)
    return labels


def walk(ms, asm, convex_meshes: bool) -> Walk:
    """The breadth-first walk from the base connector over the bodies of ``asm``: each joint added when first met,
    each body recorded in walk order (:func:`add_bodies` appends them to their joints when the model is asked for)."""
    tabs = _tables(ms, asm.module_ids, convex_meshes)
    model = pin.Model()
    model.name = "robodesign:" + ",".join(asm.module_ids)
    w = Walk(model, instance_labels(asm.module_ids))
    links: List[Dict[str, Tuple[int, str]]] = [{} for _ in tabs]   # per instance: connector → the one mated to it
    for a, ca, b, cb in asm.connections:
        links[a][ca] = (b, cb)
        links[b][cb] = (a, ca)
    off = [0]
    for t in tabs:
        off.append(off[-1] + len(t.bodies))
    seen = [False] * off[-1]
    bi, bcon = asm.base
    brec, entry = tabs[bi].connectors[bcon]   # the base body in the base frame: the base connector flipped about x
    queue = deque([(bi, brec, 0, entry, id(entry))])
    pop, push = queue.popleft, queue.append
    labels, joint_frame = w.labels, w.joint_frame
    bodies, placed, root, free = w.bodies, w.geoms, w.root_items, w.free
    total_mass, n_geoms = 0.0, 0
    while queue:
        i, rec, jid, M, token = pop()
        k, bid, bsuffix, mass, Y, nframes, conns, geoms, joints = rec[:9]
        s = off[i] + k
        if seen[s]:
            continue
        seen[s] = True
        total_mass += mass
        name = labels[i] + bsuffix
        jf = joint_frame[jid]
        bodies.append((name, jid, jf, M, conns, Y, mass, nframes))
        # M @ pose of each connector, then of each collision geometry (numpy multiplies each matrix of the stack with
        # the BLAS call it makes for one pair with the same strides: the same numbers)
        Ps = _products(token, rec, M)
        link = links[i]
        n = 0
        for cid, _, c, _ in conns:
            if cid in link:
                j2, c2 = link[cid]
                rec2, entry = tabs[j2].connectors[c2]
                if not seen[off[j2] + rec2[0]]:
                    push((j2, rec2, jid) + _placed(token, rec, Ps, n, entry))
            elif i != bi or cid != bcon:
                free.append((c, jid, M, Ps[n]))
            n += 1
        if geoms:   # (n, name suffix, coal shape) per shape of the body's collision geometry
            if not jid:
                for g, (n, _, shape) in enumerate(geoms, n_geoms):   # (g: the object's index)
                    P = Ps[n]
                    root.append(("geom", g, P))
                    w.root_geoms.append((g, P, shape))
                w.root_key.append((token, id(rec)))
            placed.append((name, jid, jf, Ps, geoms, i, bid))
            n_geoms += len(geoms)
        if joints:
            _joints(w, i, (bid, rec, token), Ps, jid, joints, seen, off[i], push, tabs[i].bodies)
    w.mass, w.n_geoms = total_mass, n_geoms
    if not all(seen):
        missing = [(i, b[1]) for i, t in enumerate(tabs) for b in t.bodies if not seen[off[i] + b[0]]]
        raise AssemblyError(f"bodies not reachable from the base: {sorted(missing)}")
    _model(w)
    return w


def geometry_specs(geoms: List[tuple]) -> List[Tuple[str, int, int, np.ndarray, object]]:
    """The robot's collision objects of a walk's ``geoms``: (name, joint, joint's frame, placement, coal shape) each,
    in walk order."""
    return [(name + suffix, jid, jf, Ps[n], shape) for name, jid, jf, Ps, shapes, _, _ in geoms
            for n, suffix, shape in shapes]


def geometry_bodies(geoms: List[tuple]) -> List[Tuple[int, str]]:
    """The (instance, body id) of each collision object of a walk's ``geoms``, in walk order."""
    return [(i, bid) for _, _, _, _, shapes, i, bid in geoms for _ in shapes]


def _model(w: Walk) -> None:
    """The walk's joints (with their frames) added to the model. Its bodies are added later (:func:`add_bodies`):
    kinematics reads none of them, and many designs of a search never use more."""
    model = w.model
    add_joint, add_frame = model.addJoint, model.addJointFrame
    for n, (parent, jm, placement, name) in enumerate(w.joint_ops, 1):
        if add_joint(parent, jm, placement, name) != n or add_frame(n, -1) != n:
            raise AssertionError("pinocchio numbers joints and their frames in order")


def add_bodies(w: Walk, tcp_frame: int) -> None:
    """The walk's bodies added to its model (after :func:`finish`), in walk order: each body's inertia appended to
    its joint after the zero inertias of the frames on the joint so far (:func:`_zero_inertias`); then the zero
    inertias of the frames left, then the TCP frame's, as pinocchio's ``addFrame`` adds it. A joint's inertia is the
    sum of what is added to it, in that order, and nothing else reads it: the model's joints, frames and scratch
    space (``pin.Data``) are the same before, and its inertias are those of a build that adds each when it comes.
    Once per walk: a second call adds nothing."""
    if w.bodies_added:
        return
    w.bodies_added = True
    model, SE3 = w.model, pin.SE3
    append_body = model.appendBodyToJoint
    pending: Dict[int, int] = {}   # joint → zero-inertia additions of frames not made yet
    masses: Dict[int, float] = {}  # joint → its mass so far
    for _, jid, _, M, _, Y, mass, nframes in w.bodies:
        if Y is not None:
            if jid in pending:
                _zero_inertias(model, pending, masses, jid)
            append_body(jid, Y, SE3(M))
            masses[jid] = masses[jid] + mass if jid in masses else 0.0 + mass
        pending[jid] = pending[jid] + nframes if jid in pending else nframes
    for j in list(pending):
        _zero_inertias(model, pending, masses, j)
    frame = model.frames[tcp_frame]
    Y = model.inertias[frame.parentJoint]
    Y += frame.placement.act(frame.inertia)
    model.inertias[frame.parentJoint] = Y


def _joints(w: Walk, i: int, body: tuple, Ps, jid: int, joints: tuple, seen: List[bool], o: int,
            push, recs: tuple) -> None:
    """The joints at a body of instance ``i`` (``body``: its id, record and the token of its placement; on joint
    ``jid``; ``Ps``: its products) to bodies not met yet (``recs``: the instance's body records, ``o``: its offset in
    ``seen``)."""
    label, (bid, rec, token) = w.labels[i], body
    for k2, other, rev, n, Q, jm, jsuffix, info, row, _ in joints:
        if seen[o + k2]:
            continue
        w.direct_joint_pairs.append(((i, bid), (i, other)))
        placement = Ps[n]   # (M @ P)
        if jm is None:
            push((i, recs[k2], jid) + _placed(token, rec, Ps, n, Q))
            continue
        name = label + jsuffix
        new_jid = len(w.joint_ops) + 1   # (its frame's id too: _model checks it)
        X, norm = _joint_se3(token, rec, Ps, n)
        w.joint_ops.append((jid, jm, X, name))
        w.joint_norms.append(norm)
        w.joint_frame[new_jid] = new_jid
        if jid == 0:
            w.root_items.append(("joint", new_jid, placement))
        w.joints.append((name, i) + info)
        w.rows.append(row)
        push((i, recs[k2], new_jid, Q, id(Q)))


def finish(w: Walk) -> Tuple[int, int, Optional[np.ndarray]]:
    """The TCP frame (the free ``eef`` connector; else the last free connector in walk order; else the base frame),
    added without its zero inertia (:func:`add_bodies` adds it after the bodies): (its frame id, its joint, its
    placement on joint 0 or None)."""
    model, free = w.model, w.free
    eefs = [f for f in free if f[0].type == "eef"]
    tcp = eefs[0] if len(eefs) == 1 else free[-1] if free else None
    if tcp is None:
        return model.addFrame(pin.Frame("TCP", 0, 0, pin.SE3.Identity(), _OP_FRAME), False), 0, np.eye(4)
    tj, Mc = tcp[1], tcp[3]   # (M @ the connector's pose)
    X = pin.SE3(Mc)
    w.tcp_norm = vector_norm(X.translation)   # (the frame's placement is a copy of X; on joint 0, placed again)
    fid = model.addFrame(pin.Frame("TCP", tj, w.joint_frame[tj], X, _OP_FRAME), False)
    return fid, tj, (Mc.copy() if tj == 0 else None)


def chain_to(w: Walk, j: int) -> Tuple[int, ...]:
    """The joints from the world to joint ``j`` of the walk's model, in order (its parents, as pinocchio's
    ``model.parents`` holds them)."""
    ops, chain = w.joint_ops, []
    while j > 0:
        chain.append(j)
        j = ops[j - 1][0]
    return tuple(reversed(chain))


def add_body_frames(model: "pin.Model", bodies: List[tuple], base_pose: Optional[np.ndarray],
                    root_items: list) -> None:
    """The frames of the bodies (``<instance>.<body>``) and their connectors (``<instance>.<body>.<connector>``) in
    walk order, without their zero inertias (added when the robot was built); those on joint 0 at ``base_pose``
    (None: not placed yet), each also added to ``root_items``."""
    add, Frame, SE3 = model.addFrame, pin.Frame, pin.SE3
    BODY, OP = pin.FrameType.BODY, pin.FrameType.OP_FRAME
    for name, jid, jf, M, conns, _, _, _ in bodies:
        on_root = jid == 0
        fid = add(Frame(name, jid, jf, SE3(base_pose @ M if on_root and base_pose is not None else M), BODY), False)
        if on_root:
            root_items.append(("frame", fid, M.copy()))
        for _, pose, _, csuffix in conns:
            Mc = M @ pose
            cf = add(Frame(name + csuffix, jid, fid, SE3(base_pose @ Mc if on_root and base_pose is not None else Mc),
                           OP), False)
            if on_root:
                root_items.append(("frame", cf, Mc.copy()))
