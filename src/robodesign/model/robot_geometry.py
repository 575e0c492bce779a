"""The robot's coal collision geometry and its collision queries (:class:`RobotGeometry`, a part of
:class:`robodesign.model.robot.Robot`): the robot's objects and the self pairs among them, the cell's obstacles
and their pairs with every robot object, the scratch space of the queries (``pin.GeometryData``, kept apart as
pinocchio keeps ``Data``), and the queries themselves — a configuration in collision, the pairs in contact, the
contacts of the base whatever the joints do, the smallest distances. Everything here is made on first use: a
design that fails before its first collision query needs none of it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import pinocchio as pin

from robodesign.model import collision_cull, geometry_kernel
from robodesign.model.box_screen import all_clear, boxes_of
from robodesign.model.collision_cull import SLACK, bounding_sphere, distance_field, obstacle_bounds
from robodesign.model.robot_build import geometry_bodies, geometry_specs

if TYPE_CHECKING:
    from robodesign.formats.module_spec import ModuleSet


@dataclass
class Obstacle:
    """A collision object of the environment: shape + world pose (world-fixed unless moved)."""
    name: str
    shape: object  # coal CollisionGeometry
    pose: np.ndarray  # 4x4 world


class RobotGeometry:
    """The collision part of :class:`~robodesign.model.robot.Robot` (what its ``_build`` sets is declared here)."""

    kinematic_model: "pin.Model"   # (Robot.model, its bodies perhaps not added yet: no collision query reads them)
    data: "pin.Data"
    module_set: "ModuleSet"
    base_pose: np.ndarray
    dof: int
    obstacles: List["Obstacle"]
    safety_margin: float
    _geom_model: Optional["pin.GeometryModel"]
    _geom_data: Optional["pin.GeometryData"]
    _geoms: List[tuple]   # the walk's bodies with collision geometry (robot_build.Walk.geoms)
    _n_geoms: int
    _root_geoms: List[Tuple[int, np.ndarray, object]]
    _root_key: Tuple[Tuple[int, int], ...]   # (robot_build.Walk.root_key: what decides the root objects)
    _specs: Optional[List[Tuple[str, int, int, np.ndarray, object]]]
    _bodies_of_geoms: Optional[List[Tuple[int, str]]]
    _root_items: List[Tuple[str, int, np.ndarray]]
    _obstacle_ids: List[int]
    _base_probe: Optional[tuple]
    _root_spheres: Optional[tuple]
    _obstacle_bounds: Optional[Any]
    _placed: bool
    _direct_joint_pairs: List[tuple]   # ((instance, body), (instance, body)) of each joint (robot_build.Walk)
    _self_map: Optional[np.ndarray]
    _n_self: int

    def _q(self, q) -> np.ndarray:
        """One configuration, checked (Robot's own)."""
        raise NotImplementedError

    @property
    def _geom_specs(self) -> List[Tuple[str, int, int, np.ndarray, object]]:
        """The robot's collision objects: (name, joint, joint's frame, placement, coal shape) each, in walk order,
        made on first use (a design that fails before its first collision query needs only the count and the
        objects fixed to the world)."""
        specs = self._specs
        if specs is None:
            specs = self._specs = geometry_specs(self._geoms)
        return specs

    @property
    def _geom_body(self) -> List[Tuple[int, str]]:
        """The (instance, body id) of each collision object, made on first use."""
        bodies = self._bodies_of_geoms
        if bodies is None:
            bodies = self._bodies_of_geoms = geometry_bodies(self._geoms)
        return bodies

    @property
    def _self_pairs(self) -> np.ndarray:
        """The self-collision pairs (:meth:`_self_collision_map`), made on first use."""
        if self._self_map is None:
            self._self_map = self._self_collision_map(self._direct_joint_pairs)
            self._n_self = int(self._self_map.sum())
        return self._self_map

    @property
    def _n_self_pairs(self) -> int:
        return self._n_self if self._self_map is not None else int(self._self_pairs.sum())

    def _self_collision_map(self, direct_joint_pairs) -> np.ndarray:
        """Every pair of robot objects on different joints, but those the module set ignores (a boolean map, set
        in one call, row-major)."""
        mode = self.module_set.ignore_collisions
        parents = np.asarray(self.kinematic_model.parents, dtype=int)
        J = np.array([spec[1] for spec in self._geom_specs], dtype=int).reshape(-1)
        keep = np.triu(J[:, None] != J[None, :], 1)  # rigidly connected: same joint
        if mode == "rigid_via_joint":
            keep &= (parents[J][:, None] != J[None, :]) & (parents[J][None, :] != J[:, None])
        if mode == "via_joint" and direct_joint_pairs:
            ids = {b: k for k, b in enumerate(dict.fromkeys(self._geom_body))}  # body → index
            B = np.array([ids[b] for b in self._geom_body], dtype=int)
            D = np.zeros((len(ids), len(ids)), dtype=bool)  # bodies joined directly by a joint
            for pair in direct_joint_pairs:
                ab = [ids[b] for b in pair if b in ids]
                if len(ab) == 2:
                    D[ab[0], ab[1]] = D[ab[1], ab[0]] = True
            keep &= ~D[B[:, None], B[None, :]]
        return keep

    @property
    def geom_model(self) -> "pin.GeometryModel":
        """The coal collision geometry: the robot's objects (pairs among them first), then the obstacles (each with
        every robot object), made on first use (a design that fails before any collision query needs none)."""
        geom = self._geom_model
        if geom is None:
            geom = self._geom_model = pin.GeometryModel()
            for k in range(len(self._geom_specs)):
                geom.addGeometryObject(self._geometry_object(k))
            geom.setCollisionPairs(self._self_pairs)
            self._add_obstacles(geom)
        return geom

    @geom_model.setter
    def geom_model(self, geom: "pin.GeometryModel") -> None:
        self._geom_model = geom
        # base_collisions' probe and bounds were made of the geometry before (its objects, its obstacles' poses)
        self._base_probe = self._obstacle_bounds = None
        self._geometry_changed()

    def _geometry_changed(self) -> None:
        """Forget the collision culler (built for the geometry before the change; kept aside as ``_kept_culler``,
        which :func:`~robodesign.model.collision_cull.culler_of` takes up again if the geometry comes back to the
        state it was made for)."""
        self._kept_culler = getattr(self, "_culler", None) or getattr(self, "_kept_culler", None)
        self._culler: Optional[Any] = None   # model.collision_cull.CollisionCuller of the current geometry
        self._plain_queries = 0              # in_collision queries asked of every pair (< 0: while waiting)

    def _geometry_object(self, k: int) -> "pin.GeometryObject":
        """Robot object ``k`` as the geometry holds it (one fixed to the world at the base pose)."""
        name, jid, fid, P, shape = self._geom_specs[k]
        return pin.GeometryObject(name, jid, fid, pin.SE3(self.base_pose @ P if jid == 0 and self._placed else P),
                                  shape)

    def _obstacle_object(self, ob: "Obstacle") -> "pin.GeometryObject":
        return pin.GeometryObject("obstacle:" + ob.name, 0, 0, pin.SE3(np.asarray(ob.pose, float)), ob.shape)

    def _add_obstacles(self, geom) -> None:
        n_robot = self._n_geoms
        for ob in self.obstacles:  # at the indices _obstacle_ids: after the robot's objects, in order
            geom.addGeometryObject(self._obstacle_object(ob))
        add = geom.addCollisionPair
        for k in self._obstacle_ids:
            for pair in _pair_column(k, n_robot):
                add(pair)

    def set_obstacles(self, obstacles: Sequence[Obstacle], safety_margin: float = 0.0) -> None:
        """Add environment collision objects; robot–obstacle pairs are checked with ``safety_margin``."""
        n_robot = self._n_geoms
        self.obstacles = list(obstacles)
        self._obstacle_ids = list(range(n_robot, n_robot + len(self.obstacles)))  # after the robot's own objects
        geom = self._geom_model
        if geom is not None:  # drop the previous obstacles; else geom_model adds these when it is made
            if len(geom.geometryObjects) > n_robot:
                self._geom_model = geom = self._robot_only_geom()
            self._add_obstacles(geom)
        self.safety_margin = float(safety_margin)
        self._geom_data = self._base_probe = self._obstacle_bounds = None
        self._geometry_changed()

    @property
    def obstacle_geometry_ids(self) -> Tuple[int, ...]:
        """Geometry-model index of each obstacle (in the order of :attr:`obstacles`)."""
        return tuple(self._obstacle_ids)

    def move_obstacle(self, index: int, pose: np.ndarray) -> None:
        self.geom_model.geometryObjects[self._obstacle_ids[index]].placement = pin.SE3(np.asarray(pose, float))
        self._base_probe = self._obstacle_bounds = None
        self._geometry_changed()

    def _robot_only_geom(self):
        g = pin.GeometryModel()
        for k in range(self._n_geoms):
            g.addGeometryObject(self.geom_model.geometryObjects[k])
        for cp in list(self.geom_model.collisionPairs)[: self._n_self_pairs]:
            g.addCollisionPair(cp)
        return g

    @property
    def geom_data(self) -> "pin.GeometryData":
        """Scratch space of the collision queries (built lazily, after the last change of the geometry)."""
        gd = self._geom_data
        if gd is None:
            gd = self._geom_data = pin.GeometryData(self.geom_model)
            self._apply_margins(gd)
            probe, self._base_probe = self._base_probe, None
            if probe is not None:  # the base contacts were queried on the probe: their GJK guesses carry over
                for k, req in zip(self._base_pair_indices(probe[2]), probe[1].collisionRequests):
                    to = gd.collisionRequests[k]
                    to.cached_gjk_guess, to.cached_support_func_guess = req.cached_gjk_guess, req.cached_support_func_guess
                    to.distance_upper_bound = req.distance_upper_bound  # (pinocchio sets it at every query)
        return gd

    def _apply_margins(self, gd) -> None:
        """Contacts on for every request, the safety margin on the robot–obstacle pairs' (after the self pairs).
        enable_contact=True: coal's boolean-only GJK misses some exactly aligned overlaps (e.g. a box centred on a
        cylinder's end face); with contacts it runs EPA and is exact. A new scratch space's requests are all alike:
        two copies of its first one, set so, make the whole vector at once (C++ copies)."""
        reqs = gd.collisionRequests
        m = self._request_margins(len(reqs))
        n, ns = len(m), min(self._n_self_pairs, len(m))
        if n:
            vec = type(reqs)
            own, other, out = vec(), vec(), vec()
            own.append(reqs[0])
            own[0].enable_contact = True
            other.append(own[0])
            other[0].security_margin = float(m[n - 1])
            out.extend([own[0]] * ns + [other[0]] * (n - ns))
            gd.collisionRequests = out
        self._margins_set = (gd, m)

    def _request_margins(self, n: int) -> np.ndarray:
        """The security margins of the ``n`` collision requests as :meth:`_apply_margins` sets them: coal's default
        (0) on the self pairs, the safety margin on the robot–obstacle pairs."""
        m = np.full(n, float(getattr(self, "safety_margin", 0.0)))
        m[:min(self._n_self_pairs, n)] = 0.0
        return m

    def pair_requests(self) -> Tuple[np.ndarray, np.ndarray]:
        """(security margins, active flags) of every collision pair: those of the scratch space, or, before it is
        made, those it will have (:meth:`_request_margins`; pinocchio makes every pair active). What
        :class:`~robodesign.model.collision_cull.CollisionCuller` bounds with, without making the scratch space."""
        gd = self._geom_data
        if gd is None:
            n = len(self.geom_model.collisionPairs)
            return self._request_margins(n), np.ones(n, dtype=bool)
        m = self.request_margins(gd)
        if m is None:
            m = np.array([req.security_margin for req in gd.collisionRequests], dtype=float)
        return m, np.fromiter(gd.activeCollisionPairs, dtype=bool, count=len(m))

    def request_margins(self, gd) -> Optional[np.ndarray]:
        """The security margins of ``gd``'s collision requests as :meth:`_apply_margins` set them (None for another
        scratch space): what :class:`~robodesign.model.collision_cull.CollisionCuller` bounds with."""
        rec = getattr(self, "_margins_set", None)
        return rec[1] if rec is not None and rec[0] is gd else None

    # ------------------------------------------------------------------------------------------
    # collision
    @property
    def n_collision_geometries(self) -> int:
        return self._n_geoms

    @property
    def n_self_collision_pairs(self) -> int:
        return self._n_self_pairs

    def _update_geometry(self, q) -> None:
        pin.updateGeometryPlacements(self.kinematic_model, self.data, self.geom_model, self.geom_data,
                                     self._q(q))

    def _check_pairs(self, start: int, stop: int, first: bool = True) -> List[int]:
        hits = []
        for k in range(start, stop):
            if pin.computeCollision(self.geom_model, self.geom_data, k):
                hits.append(k)
                if first:
                    break
        return hits

    def in_self_collision(self, q) -> bool:
        self._update_geometry(q)
        return bool(self._check_pairs(0, self._n_self_pairs))

    def in_collision(self, q) -> bool:
        """Self-collision or contact with an obstacle (within the safety margin). coal is asked only about the
        pairs that the compiled bounds of :class:`~robodesign.model.collision_cull.CollisionCuller` do not clear
        (the same verdicts); about every pair while the compiled kernel is not ready."""
        culler = self._culler
        if culler is None:
            self._plain_queries += 1
            if self._plain_queries <= 0 or (culler := self._single_culler()) is None:
                return bool(pin.computeCollisions(self.kinematic_model, self.data, self.geom_model, self.geom_data,
                                                  self._q(q), True))
        return bool(culler.in_collision(self._q(q)))

    def _single_culler(self):
        """The culler for :meth:`in_collision`, or None (kernel not compiled yet: asked again later)."""
        if not geometry_kernel.ready():
            self._plain_queries = -_CULL_RETRY   # (ready() reads the cache's stamp: not at every query)
            return None
        try:
            self._culler = collision_cull.culler_of(self)
        except (AttributeError, NotImplementedError):   # a joint the bounds' kinematics do not model
            self._plain_queries = -(1 << 62)
        return self._culler

    def collides_with_obstacles(self, q) -> bool:
        self._update_geometry(q)
        return bool(self._check_pairs(self._n_self_pairs, len(self.geom_model.collisionPairs)))

    def colliding_pairs(self, q) -> List[Tuple[str, str]]:
        self._update_geometry(q)
        hits = self._check_pairs(0, len(self.geom_model.collisionPairs), first=False)
        objs = self.geom_model.geometryObjects
        out = []
        for k in hits:
            cp = self.geom_model.collisionPairs[k]
            out.append((objs[cp.first].name, objs[cp.second].name))
        return out

    def base_collisions(self) -> List[Tuple[str, str]]:
        """The robot–obstacle pairs in contact whatever the joints do: the robot's geometry fixed to the world
        (the bodies before the first joint) against the obstacles, within the safety margin. A design with one
        collides at every configuration."""
        if not self._obstacle_ids:
            return []
        # the pairs of an obstacle and an object fixed to the world; those that a certified bound clears are not asked
        # (their answer is no)
        near = self._base_pairs_near()
        if not near:
            return []
        ab = [(a, self._obstacle_ids[j]) for j, a in near]
        if self._geom_data is None:  # the same queries on a probe of just these pairs (no scratch space for all)
            gm, gd, _ = self._base_probe = self._base_probe or _probe(self, ab, near)
            pin.updateGeometryPlacements(self.kinematic_model, self.data, gm, gd, np.zeros(self.dof))
            hit = [pin.computeCollision(gm, gd, i) for i in range(len(near))]
        else:
            self._update_geometry(np.zeros(self.dof))
            hit = [pin.computeCollision(self.geom_model, self.geom_data, k) for k in self._base_pair_indices(near)]
        if not any(hit):
            return []
        names = [s[0] for s in self._geom_specs] + ["obstacle:" + ob.name for ob in self.obstacles]
        return [(names[a], names[ob]) for (a, ob), h in zip(ab, hit) if h]

    def _base_pair_indices(self, near: List[Tuple[int, int]]) -> List[int]:
        """The collision pair index of each (obstacle j, robot object a) of ``near``: set_obstacles' pairs come after
        the self pairs, (a, j) at n_self_pairs + j·n + a (n: the robot's objects). Asked only with a scratch space for
        every pair, so that a design whose base contacts are queried on a probe never makes its self-pair map."""
        start, n = self._n_self_pairs, self._n_geoms
        return [start + j * n + a for j, a in near]

    def _base_pairs_near(self) -> List[Tuple[int, int]]:
        """(obstacle j, robot object a), obstacle by obstacle, of every pair of an obstacle and an object fixed to
        the world (the bodies before the first joint) that the bounds of the collision culler do not clear: the
        object's bounding sphere farther from the obstacle than the safety margin (its box, then its distance
        field; :class:`robodesign.model.collision_cull.ObstacleBounds`, after the quick screen of
        :mod:`robodesign.model.box_screen`)."""
        if self._root_spheres is None:   # (root objects, sphere centres in the base frame, radii): once per build
            root = [k for k, _, _ in self._root_geoms]   # (parentJoint 0, in index order)
            self._root_spheres = (root, *_placed_spheres([(P, shape) for _, P, shape in self._root_geoms],
                                                         self._root_key))
        root, C, r = self._root_spheres
        if not root:
            return []
        if self._obstacle_bounds is None:   # the obstacles where they are (move_obstacle too)
            made = self._geom_model
            poses = [ob.pose if made is None else made.geometryObjects[k].placement.homogeneous
                     for ob, k in zip(self.obstacles, self._obstacle_ids)]
            fields = [distance_field(ob.shape, T) for ob, T in zip(self.obstacles, poses)]
            self._obstacle_bounds = obstacle_bounds(fields)
        T = self.base_pose
        C = C @ T[:3, :3].T + T[:3, 3]
        if all_clear(boxes_of(self._obstacle_bounds), C, r + (self.safety_margin + SLACK)):   # (near's limits)
            return []
        near = self._obstacle_bounds.near(C, r, self.safety_margin)
        return [(j, root[i]) for j, i in zip(*(x.tolist() for x in np.nonzero(near)))]

    def min_distances(self, q) -> Tuple[float, float]:
        """(minimum self distance, minimum robot–obstacle distance); inf where there are no pairs."""
        pin.computeDistances(self.kinematic_model, self.data, self.geom_model, self.geom_data, self._q(q))
        d = [r.min_distance for r in self.geom_data.distanceResults]
        s = min(d[: self._n_self_pairs], default=math.inf)
        o = min(d[self._n_self_pairs:], default=math.inf)
        return float(s), float(o)


_CULL_RETRY = 1000   # queries before asking again whether the compiled kernel is ready


_SPHERES: Dict[tuple, Tuple[np.ndarray, np.ndarray]] = {}   # the walk's key of the root objects → (C, r)


def _placed_spheres(objects: List[Tuple[np.ndarray, object]], key: tuple) -> Tuple[np.ndarray, np.ndarray]:
    """(C, r): the bounding spheres (:func:`~robodesign.model.collision_cull.bounding_sphere`) of the ``objects``
    (placement P, coal shape), their centres placed by P (the base frame for the objects fixed to the world),
    read-only. Kept per ``key``, the walk's key of the objects (``robot_build.Walk.root_key``: the token of each body's
    placement and its record decide the placements' numbers and the shapes): robots of one search share their first
    modules, so their roots' spheres are the same numbers."""
    hit = _SPHERES.get(key)
    if hit is not None:
        return hit
    C, r = np.zeros((len(objects), 3)), np.zeros(len(objects))
    for i, (P, shape) in enumerate(objects):
        c, r[i] = bounding_sphere(shape)
        C[i] = P[:3, :3] @ c + P[:3, 3]
    C.setflags(write=False)
    r.setflags(write=False)
    if len(_SPHERES) >= 4096:
        _SPHERES.clear()
    hit = _SPHERES[key] = (C, r)
    return hit


_PAIR_COLUMNS: Dict[int, List["pin.CollisionPair"]] = {}   # object k → CollisionPair(a, k) for a = 0, 1, …


def _pair_column(k: int, n: int) -> List["pin.CollisionPair"]:
    """``[pin.CollisionPair(a, k) for a in range(n)]``, the pairs kept for the process (making one takes pinocchio
    ~2 µs, adding one to a model, which copies it, a tenth of that; nothing changes a kept pair)."""
    col = _PAIR_COLUMNS.get(k)
    if col is None or len(col) < n:   # (a new list, made whole before it is kept: threads see one or the other)
        col = _PAIR_COLUMNS[k] = [pin.CollisionPair(a, k) for a in range(n)]
    return col[:n]


def _probe(robot: RobotGeometry, ab: List[Tuple[int, int]], near: List[Tuple[int, int]]) -> tuple:
    """(geometry model, its scratch space, ``near``) of just the robot–obstacle pairs ``ab`` (``near``: their
    (obstacle, robot object), :meth:`RobotGeometry._base_pair_indices`), with the requests of the robot's own scratch
    space (contacts on, the safety margin)."""
    gm, n, made = pin.GeometryModel(), robot._n_geoms, robot._geom_model
    index: Dict[int, int] = {}
    for a, ob in ab:
        for g in (a, ob):
            if g not in index:  # the objects as the robot's geometry holds (or will hold) them
                index[g] = gm.addGeometryObject(made.geometryObjects[g] if made is not None else robot._geometry_object(
                    g) if g < n else robot._obstacle_object(robot.obstacles[g - n]))
        gm.addCollisionPair(pin.CollisionPair(index[a], index[ob]))
    gd = pin.GeometryData(gm)
    for req in gd.collisionRequests:
        req.enable_contact = True
        req.security_margin = robot.safety_margin
    return gm, gd, near
