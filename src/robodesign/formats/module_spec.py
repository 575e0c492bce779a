"""Typed, immutable description of robot modules (what a module *is*; no pinocchio or coal objects).

Mirrors the CoBRA module format (docs/formats.md): a module has bodies and joints; a body has
mass, centre of mass, inertia about the CoM, collision/visual geometry and connectors.
Specs are plain dataclasses: cheap to pickle to worker processes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Dict, Iterator, Optional, Tuple

import numpy as np

from robodesign.core.spatial import RX_PI, inv
from robodesign.formats.geometry import GeometrySpec

GENDERS = ("f", "m", "h")
JOINT_TYPES = ("revolute", "prismatic", "fixed")
IGNORE_COLLISIONS = ("rigid", "via_joint", "rigid_via_joint")


@dataclass(frozen=True, eq=False)
class Connector:
    id: str
    body_id: str
    pose: np.ndarray  # body frame → connector frame; z points away from the body
    gender: str = "h"  # 'f', 'm' or 'h'
    type: str = ""
    size: Tuple[float, ...] = ()

    @cached_property
    def entry_pose(self) -> np.ndarray:
        """Rx(π)·pose⁻¹: the pose of this connector's body in the frame of the connector it is mounted on
        (mated connectors face each other: one frame is the other flipped about x). Computed once."""
        return RX_PI @ inv(self.pose)

    def mates_with(self, other: "Connector") -> Tuple[bool, str]:
        """The paper's connector rule. Returns (ok, reason-if-not)."""
        if self.type != other.type:
            return False, f"connector types differ ({self.type!r} vs {other.type!r})"
        if tuple(self.size) != tuple(other.size):
            # Unlike the reference (numpy broadcasting makes [] equal [x]) sizes must match exactly.
            return False, f"connector sizes differ ({list(self.size)} vs {list(other.size)})"
        g = {self.gender, other.gender}
        if not (g == {"f", "m"} or (self.gender == "h" and other.gender == "h")):
            return False, f"connector genders do not mate ({self.gender!r} with {other.gender!r})"
        return True, ""


@dataclass(frozen=True, eq=False)
class Body:
    id: str
    mass: float
    com: np.ndarray  # (3,) in body frame
    inertia: np.ndarray  # (3,3) about the CoM, body axes
    connectors: Tuple[Connector, ...] = ()
    collision: Tuple[GeometrySpec, ...] = ()
    visual: Tuple[GeometrySpec, ...] = ()


@dataclass(frozen=True)
class JointLimits:
    lower: float
    upper: float
    velocity: float = math.inf
    acceleration: float = math.inf
    torque: float = math.inf


@dataclass(frozen=True, eq=False)
class Joint:
    id: str
    type: str  # revolute | prismatic | fixed; motion about/along the joint frame's z axis
    parent: str  # body id in the same module
    child: str
    pose_parent: np.ndarray  # parent body → joint frame
    pose_child: np.ndarray  # joint frame (after motion) → child body
    limits: JointLimits
    gear_ratio: float = 1.0
    motor_inertia: float = 0.0
    friction_coulomb: float = 0.0
    friction_viscous: float = 0.0

    @property
    def actuated(self) -> bool:
        return self.type != "fixed"


@dataclass(frozen=True)
class ModuleHeader:
    id: str
    name: str
    date: str = ""
    author: Tuple[str, ...] = ()
    email: Tuple[str, ...] = ()
    affiliation: Tuple[str, ...] = ()
    cost: float = 0.0


@dataclass(frozen=True, eq=False)
class Module:
    header: ModuleHeader
    bodies: Tuple[Body, ...]
    joints: Tuple[Joint, ...] = ()

    @property
    def id(self) -> str:
        return self.header.id

    @property
    def name(self) -> str:
        return self.header.name

    def body(self, body_id: str) -> Body:
        for b in self.bodies:
            if b.id == body_id:
                return b
        raise KeyError(body_id)

    @cached_property
    def connectors(self) -> Tuple[Connector, ...]:
        return tuple(c for b in self.bodies for c in b.connectors)

    def connector(self, con_id: str) -> Connector:
        for c in self.connectors:
            if c.id == con_id:
                return c
        raise KeyError(con_id)

    @cached_property
    def dof(self) -> int:
        return sum(1 for j in self.joints if j.actuated)

    @property
    def mass(self) -> float:
        return float(sum(b.mass for b in self.bodies))

    @cached_property
    def is_base(self) -> bool:
        return any(c.type == "base" for c in self.connectors)

    @cached_property
    def is_end_effector(self) -> bool:
        return any(c.type == "eef" for c in self.connectors)

    @cached_property
    def kind(self) -> str:
        """'base', 'eef', 'joint' or 'link' (for search-space rules)."""
        if self.is_base:
            return "base"
        if self.is_end_effector:
            return "eef"
        return "joint" if self.dof > 0 else "link"


@dataclass(frozen=True, eq=False)
class ModuleSet:
    name: str
    modules: Dict[str, Module]
    root: Optional[Path] = None  # folder that holds modules.json; mesh paths are inside it
    ignore_collisions: str = "via_joint"
    source: Optional[str] = None  # file the set was read from
    warnings: Tuple[str, ...] = ()  # what was tolerated while reading (ignored keys, unreadable visual meshes)

    def __getitem__(self, module_id) -> Module:
        return self.modules[str(module_id)]

    def __contains__(self, module_id) -> bool:
        return str(module_id) in self.modules

    def __iter__(self) -> Iterator[Module]:
        return iter(self.modules.values())

    def __len__(self) -> int:
        return len(self.modules)

    @property
    def ids(self) -> Tuple[str, ...]:
        return tuple(self.modules)

    def of_kind(self, kind: str) -> Tuple[Module, ...]:
        return tuple(m for m in self.modules.values() if m.kind == kind)
