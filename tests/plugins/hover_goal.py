"""A goal type of its own from outside robodesign (issue 23: goal types as objects): ``hover``, the TCP stays
within ``radius`` of a point for the ``duration`` seconds up to the goal time::

    {"ID": "H", "type": "hover", "position": [x, y, z], "radius": 0.002, "duration": 0.4}

It subclasses no built-in goal: the class itself provides its parsing (``canonical_json``, ``from_json``,
``json_keys``, ``json_schema``), its poses (``target_poses``, for the solver's "pose" handler and the views), its time window
and its check. It is found through the entry point ``hover = hover_goal:Hover`` in the group
``robodesign.goal_types`` (tests/test_goal_plugins.py installs that entry point in a tmp folder).
"""
from dataclasses import dataclass
from typing import ClassVar, Optional, Tuple

import numpy as np

from robodesign.formats.task_spec import WINDOW_TIME_TOL, Goal
from robodesign.formats.tolerance import ToleratedPose


@dataclass(frozen=True, eq=False)
class Hover(Goal):
    position: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float = 0.0
    duration: float = 0.0
    type_name: ClassVar[str] = "hover"
    solver_kind: ClassVar[str] = "pose"
    json_keys: ClassVar[Tuple[str, ...]] = ("position", "radius", "duration")
    json_schema: ClassVar[dict] = {
        "type": "object", "required": ["ID", "type", "position", "radius", "duration"], "additionalProperties": False,
        "properties": {
            "ID": {"type": ["string", "integer"]}, "type": {"const": "hover"}, "constraints": {"type": "array"},
            "position": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
            "radius": {"type": "number", "exclusiveMinimum": 0}, "duration": {"type": "number", "minimum": 0}},
    }

    @classmethod
    def canonical_json(cls, data, file, path, warnings):
        """A variant read with a warning: the position as an object {"x": …, "y": …, "z": …}."""
        pos = data.get("position")
        if isinstance(pos, dict) and set(pos) == {"x", "y", "z"}:
            warnings.add(file, path + ["position"], "read as [x, y, z]")
            data = {**data, "position": [pos["x"], pos["y"], pos["z"]]}
        return data

    @classmethod
    def from_json(cls, data, ctx) -> "Hover":
        return cls(ctx.id, ctx.constraints, tuple(float(x) for x in ctx.key("position")[1]),
                   float(ctx.key("radius")[1]), float(ctx.key("duration")[1]))

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        nominal = np.eye(4)
        nominal[:3, 3] = self.position
        return (ToleratedPose.from_json({"nominal": nominal.tolist(), "toleranceProjection": ["r_sph"],
                                         "tolerance": [[0.0, self.radius]]}),)

    def time_window(self, tq, k: int) -> Optional[Tuple[int, int]]:
        t_start = tq.goal2time[self.id] - self.duration
        if t_start < tq.t[0] - WINDOW_TIME_TOL:
            return None
        return int(np.searchsorted(tq.t, t_start - WINDOW_TIME_TOL, side="left")), k

    def check(self, tq, k: int, violation):
        window = tq.goal_windows.get(self.id)
        if window is None:
            return [violation(f"hover: the window starts before the trajectory (t_g − duration = "
                              f"{tq.goal2time[self.id] - self.duration:.4f} s)", sample=k)]
        d = np.linalg.norm(tq.tcp_poses[window[0]:k + 1, :3, 3] - np.asarray(self.position), axis=1)
        far = np.nonzero(d > self.radius)[0]
        if not len(far):
            return []
        kk = int(far[0]) + window[0]
        return [violation(f"hover: the TCP is {d[far[0]]:.6g} m from the point at t={tq.t[kk]:.4f} s, farther than "
                          f"the radius {self.radius:g} m ({len(far)} samples of the window)", sample=kk,
                          time=float(tq.t[kk]), value=float(d[far[0]]), bound=self.radius)]
