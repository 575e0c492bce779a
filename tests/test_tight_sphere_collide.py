"""The collision culler's sphere of a robot shape (``collision_cull.tight_sphere``, issue 25 round 6): it contains
the shape (checked on the shape's extreme points: a cylinder's and cone's rims, a capsule's caps, a sphere's surface
along random directions, a convex polytope's vertices, and on the points coal reports farthest along random
directions) and is never larger than the box's sphere (``bounding_sphere``) it replaces."""
import coal
import numpy as np
import pytest
from conftest import IMPROV

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.model.collision_cull import _bounding_sphere, tight_sphere
from robodesign.model.robot import Robot


def directions(n, seed):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1)[:, None]


def extreme_points(shape, seed) -> np.ndarray:
    """Points of ``shape`` (its frame) where it reaches farthest: rims, caps, vertices, and coal's farthest point
    along random directions (the witness point of a distance query to a far tiny sphere)."""
    kind, pts = type(shape).__name__, []
    t = np.linspace(0.0, 2 * np.pi, 73)
    if kind in ("Cylinder", "Cone"):
        for z in (-shape.halfLength, shape.halfLength):
            pts += [np.c_[shape.radius * np.cos(t), shape.radius * np.sin(t), np.full_like(t, z)]]
    elif kind == "Capsule":
        pts += [d * shape.radius + (0, 0, np.sign(d[2]) * shape.halfLength) for d in directions(200, seed)]
    elif kind == "Sphere":
        pts += [directions(200, seed) * shape.radius]
    elif kind.startswith("Convex"):
        pts += [np.asarray(shape.points()).reshape(-1, 3)]
    probe, req = coal.Sphere(1e-6), coal.DistanceRequest()
    for d in directions(200, seed + 1):
        res = coal.DistanceResult()
        coal.distance(shape, coal.Transform3s(), probe, coal.Transform3s(np.eye(3), 100.0 * d), req, res)
        pts.append(np.asarray(res.getNearestPoint1()).reshape(1, 3))
    return np.vstack(pts)


SHAPES = [coal.Cylinder(0.045, 0.09), coal.Cylinder(0.04, 0.6), coal.Cone(0.1, 0.3), coal.Capsule(0.05, 0.4),
          coal.Sphere(0.09), coal.Box(0.1, 0.2, 0.3)]




def improv_shapes():
    """The shapes of an IMPROV arm (cylinders, spheres, convex hulls)."""
    ms = load_module_set(IMPROV)
    robot = Robot(ms, Assembly.from_order(ms, ("1", "21", "4", "22", "5", "23", "12")))
    return [o.geometry for o in robot.geom_model.geometryObjects]


@pytest.mark.parametrize("shape", SHAPES + improv_shapes())
def test_the_sphere_contains_the_shape_and_is_no_larger_than_the_boxes(shape):
    c, r = tight_sphere(shape)
    c0, r0 = _bounding_sphere(shape)
    assert r <= r0
    P = extreme_points(shape, 3)
    assert np.linalg.norm(P - c, axis=1).max() <= r + 1e-12
    if type(shape).__name__ in ("Cylinder", "Sphere", "Capsule"):
        assert np.linalg.norm(P - c, axis=1).max() >= r - 1e-3   # the farthest points reach it: tight
