"""A goal type from outside robodesign (issue 23: the "where to add" table, proved): ``approach``, a TCP
position to pass within ``radius`` of, in any orientation::

    {"ID": "1", "type": "approach", "position": [x, y, z], "radius": 0.01}

It is an ``at`` goal whose tolerated pose is the ball of that radius (orientation free), so it inherits
the ``at`` goal's check, solver handler ("pose") and view; all this module adds is the class, its
JSON schema and its parser, registered with robodesign's goal-type registry when imported.
"""
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from robodesign.formats.goal_types import register_goal_type
from robodesign.formats.task_spec import At
from robodesign.formats.tolerance import ToleratedPose

SCHEMA = {
    "type": "object",
    "required": ["ID", "type", "position", "radius"],
    "additionalProperties": False,
    "properties": {
        "ID": {"type": ["string", "integer"]}, "type": {"const": "approach"},
        "position": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
        "radius": {"type": "number", "exclusiveMinimum": 0},
        "constraints": {"type": "array"},
    },
}


@dataclass(frozen=True, eq=False)
class Approach(At):
    radius: float = 0.0
    type_name: ClassVar[str] = "approach"


def parse_approach(g, ctx):
    k, pos = ctx.key("position")
    nominal = np.eye(4)
    nominal[:3, 3] = [float(x) for x in pos]
    r = float(ctx.key("radius")[1])
    pose = ToleratedPose.from_json({"nominal": nominal.tolist(), "toleranceProjection": ["r_sph"],
                                    "tolerance": [[0.0, r]]}, file=ctx.file, path=ctx.path + [k])
    return Approach(ctx.id, ctx.constraints, pose, radius=r)


register_goal_type(Approach, parse_approach, keys=("position", "radius"), schema=SCHEMA)
