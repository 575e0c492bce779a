import json
import math

import numpy as np
import pytest

from conftest import COBRA as _COBRA

from robodesign.core.errors import InputError
from robodesign.core.jsonio import dumps_json, loads_json
from robodesign.core.spatial import homogeneous, rot_x, rot_y, rot_z, translation
from robodesign.formats.tolerance import (PROJECTIONS, ToleratedPose, ToleranceSamplingError, projection_value,
                                  quaternion_to_rotation, rotation_to_quaternion)

PTP_3 = _COBRA / "tasks" / "simple" / "PTP_3.json"
ALL = list(PROJECTIONS)


def values_of(T, nominal=None, frame="nominal", resolver=None):
    """All projections of T (relative to nominal) in one frame, as a dict."""
    nominal = np.eye(4) if nominal is None else nominal
    tp = ToleratedPose(nominal, ALL, [list(_full(p)) for p in ALL], [frame] * len(ALL), frame_resolver=resolver)
    return {k[0]: v for k, v in tp.values(T).items()}


def _full(p):
    info = PROJECTIONS[p]
    return (info.lo, info.hi) if not info.periodic else (-math.pi, math.pi)


# ------------------------------------------------------------------------------------------------ projections
def test_translation_projections_by_hand():
    v = values_of(translation(0.3, 0.4, 0.0))
    assert v["x"] == pytest.approx(0.3) and v["y"] == pytest.approx(0.4) and v["z"] == 0
    assert v["r_cyl"] == pytest.approx(0.5)
    assert v["phi_cyl"] == pytest.approx(math.atan2(0.4, 0.3))
    assert v["r_sph"] == pytest.approx(0.5)
    assert v["theta"] == pytest.approx(math.pi / 2)
    assert v["phi_sph"] == pytest.approx(math.atan2(0.4, 0.3))
    v = values_of(translation(0.3, 0.4, 1.2))
    assert v["r_sph"] == pytest.approx(1.3)                    # 3-4-12-13
    assert v["theta"] == pytest.approx(math.acos(1.2 / 1.3))
    assert v["r_cyl"] == pytest.approx(0.5)


def test_rotation_about_z_by_hand():
    v = values_of(homogeneous(rot_z(0.3)))
    assert v["Theta_R"] == pytest.approx(0.3)
    assert (v["N_x"], v["N_y"], v["N_z"]) == pytest.approx((0.0, 0.0, 0.3))
    assert (v["R"], v["P"], v["Y"]) == pytest.approx((0.0, 0.0, 0.3))
    assert (v["Alpha"], v["Beta"], v["Gamma"]) == pytest.approx((0.3, 0.0, 0.0))
    assert (v["A"], v["B"], v["C"], v["D"]) == pytest.approx((math.cos(0.15), 0, 0, math.sin(0.15)))
    # translation projections of a pure rotation are zero
    assert v["x"] == v["r_sph"] == 0


def test_rpy_and_zyx_euler():
    R = rot_z(0.3) @ rot_y(0.2) @ rot_x(0.1)
    v = values_of(homogeneous(R))
    assert (v["R"], v["P"], v["Y"]) == pytest.approx((0.1, 0.2, 0.3))
    assert (v["Alpha"], v["Beta"], v["Gamma"]) == pytest.approx((0.3, 0.2, 0.1))
    v = values_of(homogeneous(rot_x(-0.2)))
    assert (v["N_x"], v["Theta_R"]) == pytest.approx((-0.2, 0.2))


def test_quaternion_sign_convention():
    q = rotation_to_quaternion(rot_z(-0.3))
    assert q == pytest.approx([math.cos(0.15), 0, 0, -math.sin(0.15)])
    q = rotation_to_quaternion(rot_z(2 * math.pi - 0.3))       # same rotation, w stays ≥ 0
    assert q == pytest.approx([math.cos(0.15), 0, 0, -math.sin(0.15)])
    q = rotation_to_quaternion(rot_x(math.pi))                 # w = 0: first non-zero made positive
    assert q == pytest.approx([0, 1, 0, 0])
    R = rot_z(0.3) @ rot_x(1.1)
    assert quaternion_to_rotation(rotation_to_quaternion(R)) == pytest.approx(R)


def test_projection_value_helper_and_tiny_angle():
    assert projection_value("Theta_R", homogeneous(rot_y(1e-9))) == pytest.approx(1e-9, rel=1e-6)
    assert projection_value("r_cyl", translation(3, 4, 9)) == pytest.approx(5)


# ------------------------------------------------------------------------------------------------ frames
def test_world_frame_differs_from_nominal_frame_for_rotated_nominal():
    nominal = homogeneous(rot_z(math.pi / 2), (1.0, 0.0, 0.0))
    T = translation(0.1, 0, 0) @ nominal                       # moved +0.1 along *world* x
    vn = values_of(T, nominal, "nominal")
    vw = values_of(T, nominal, "world")
    # in nominal axes (x_nom = world y, y_nom = −world x) the move is (0, −0.1, 0)
    assert (vn["x"], vn["y"], vn["z"]) == pytest.approx((0.0, -0.1, 0.0))
    assert (vw["x"], vw["y"], vw["z"]) == pytest.approx((0.1, 0.0, 0.0))
    assert vn["phi_cyl"] == pytest.approx(-math.pi / 2) and vw["phi_cyl"] == pytest.approx(0.0)

    tol_world = ToleratedPose(nominal, ["x"], [[0.05, 0.15]], ["world"])
    tol_nominal = ToleratedPose(nominal, ["x"], [[0.05, 0.15]], ["nominal"])
    assert tol_world.valid(T)
    assert not tol_nominal.valid(T)
    (name, value, lo, hi), = tol_nominal.violations(T)
    assert name == "x" and value == pytest.approx(0.0) and (lo, hi) == (0.05, 0.15)

    # rotation by 0.2 about the world x axis = about the nominal −y axis
    T2 = homogeneous(rot_x(0.2)) @ nominal
    vn, vw = values_of(T2, nominal, "nominal"), values_of(T2, nominal, "world")
    assert (vn["N_x"], vn["N_y"], vn["N_z"]) == pytest.approx((0.0, -0.2, 0.0))
    assert (vw["N_x"], vw["N_y"], vw["N_z"]) == pytest.approx((0.2, 0.0, 0.0))
    assert vn["Theta_R"] == pytest.approx(vw["Theta_R"]) == pytest.approx(0.2)  # angle is frame-independent


def test_named_task_frame():
    nominal = homogeneous(rot_z(math.pi / 2), (1.0, 0.0, 0.0))
    frames = {"table": homogeneous(rot_z(math.pi), (5.0, 5.0, 0.0))}
    T = translation(0.1, 0, 0) @ nominal
    v = values_of(T, nominal, "table", frames.__getitem__)
    # world +x expressed in axes rotated by π about z is −x; the frame's origin does not matter
    assert (v["x"], v["y"], v["z"]) == pytest.approx((-0.1, 0.0, 0.0))
    tp = ToleratedPose.from_json({"nominal": nominal.tolist(), "toleranceProjection": ["x"],
                                  "tolerance": [[-0.15, -0.05]], "toleranceFrame": ["table"]},
                                 "t.json", ["goals", 0, "goalPose"], frames.__getitem__)
    assert tp.valid(T) and not tp.valid(nominal)


def test_nominal_parent_resolved_at_construction_and_round_trip():
    frames = {"base": homogeneous(rot_z(math.pi / 2), (1.0, 2.0, 0.0))}
    obj = {"nominal": translation(0.5, 0, 0).tolist(), "nominalParent": "base",
           "toleranceProjection": ["r_sph"], "tolerance": [[0, 0.01]]}
    tp = ToleratedPose.from_json(obj, "t.json", ["goals", 0, "goalPose"], frames.__getitem__)
    assert tp.nominal[:3, 3] == pytest.approx([1.0, 2.5, 0.0])    # base x axis = world y
    assert tp.valid(translation(1.0, 2.505, 0.0))
    out = tp.to_json()
    assert out["nominalParent"] == "base" and out["nominal"] == obj["nominal"]
    with pytest.raises(InputError, match=r"t\.json: goals\[0\]\.goalPose\.nominalParent: unknown frame 'nowhere'"):
        ToleratedPose.from_json({**obj, "nominalParent": "nowhere"}, "t.json", ["goals", 0, "goalPose"],
                                frames.__getitem__)


# ------------------------------------------------------------------------------------------------ angles
def point_at_angle(a, r=1.0):
    return translation(r * math.cos(a), r * math.sin(a), 0.0)


def test_phi_interval_crossing_pi_wraps():
    tp = ToleratedPose(np.eye(4), ["phi_cyl"], [[2.9, 3.4]])    # the wedge around the −x axis
    assert tp.valid(point_at_angle(math.pi))
    assert tp.valid(point_at_angle(-3.0))                      # −3.0 ≡ 3.283
    assert tp.valid(point_at_angle(3.0))
    assert not tp.valid(point_at_angle(2.8))
    assert not tp.valid(point_at_angle(-2.8))                  # ≡ 3.483
    assert tp.residual(point_at_angle(2.8))[0] == pytest.approx(-0.1)
    assert tp.residual(point_at_angle(-2.8))[0] == pytest.approx(2 * math.pi - 2.8 - 3.4)


def test_pi_and_minus_pi_are_the_same_angle():
    tp = ToleratedPose(np.eye(4), ["phi_sph"], [[3.0, math.pi]])
    T = translation(-1.0, -1e-17, 0.0)                          # atan2 gives −π (almost)
    assert projection_value("phi_sph", T) == pytest.approx(-math.pi)
    assert tp.valid(T)
    tp = ToleratedPose(np.eye(4), ["Y"], [[-math.pi, -3.0]])
    assert tp.valid(homogeneous(rot_z(-math.pi + 0.05)))
    assert tp.valid(homogeneous(rot_z(math.pi)))               # yaw reported as +π ≡ −π
    assert not tp.valid(homogeneous(rot_z(math.pi - 0.05)))   # ≡ −π − 0.05: just outside


def test_azimuth_on_the_axis_is_treated_as_satisfied():
    tp = ToleratedPose(np.eye(4), ["phi_cyl", "theta"], [[0.5, 1.0], [0.1, 0.2]])
    assert tp.valid(np.eye(4))                                 # origin: both undefined
    assert not tp.valid(translation(0, 0, 0.3))                # theta = 0 is defined here


# ------------------------------------------------------------------------------------------------ merging
def test_same_projection_entries_are_intersected():
    tp = ToleratedPose(np.eye(4), ["x", "x"], [[-0.1, 0.1], [0.0, 0.2]])
    assert tp.constraint_keys == [("x", "nominal")]
    assert tp.valid(translation(0.05, 0, 0))
    assert not tp.valid(translation(-0.05, 0, 0)) and not tp.valid(translation(0.15, 0, 0))
    assert tp.residual(translation(0.15, 0, 0)) == pytest.approx([0.05])
    assert tp.residual(translation(-0.05, 0, 0)) == pytest.approx([-0.05])
    # same projection in another frame is a separate constraint
    tp = ToleratedPose(homogeneous(rot_z(1.0)), ["z", "z"], [[0, 0.05], [-0.02, 0.02]], ["nominal", "world"])
    assert len(tp.constraint_keys) == 2
    assert tp.valid(translation(0, 0, 0.01)) and not tp.valid(translation(0, 0, 0.03))


def test_periodic_intersection():
    tp = ToleratedPose(np.eye(4), ["phi_cyl", "phi_cyl"], [[2.9, 3.4], [-math.pi, -3.0]])
    assert not tp.valid(point_at_angle(3.0))
    assert tp.valid(point_at_angle(-3.1))
    assert tp.valid(point_at_angle(math.pi))


def test_empty_intersection_is_an_input_error():
    with pytest.raises(InputError, match=r"g\.json: tolerance\[1\]: the intervals for 'x' .*do not overlap"):
        ToleratedPose.from_json({"nominal": np.eye(4).tolist(), "toleranceProjection": ["x", "x"],
                                 "tolerance": [[0, 0.1], [0.2, 0.3]]}, "g.json")


# ------------------------------------------------------------------------------------------------ empty tolerance
def test_empty_tolerance_means_any_by_default():
    tp = ToleratedPose.from_json({"nominal": np.eye(4).tolist()}, "t.json", ["constraints", 5, "pose"])
    assert tp.is_unconstrained
    far = homogeneous(rot_x(2.0), (10, -3, 7))
    assert tp.valid(far) and tp.violations(far) == [] and tp.residual(far).size == 0
    assert np.array_equal(tp.sample(np.random.default_rng(1)), tp.nominal)
    assert tp.to_json() == {"nominal": np.eye(4).tolist()}


def test_empty_tolerance_can_mean_the_reference_default():
    tp = ToleratedPose.from_json({"nominal": np.eye(4).tolist(), "toleranceProjection": []}, "t.json",
                                 empty_means_any=False)
    assert not tp.is_unconstrained and tp.uses_default
    assert tp.valid(translation(0.0005, -0.0005, 0.0009))
    assert not tp.valid(translation(0.002, 0, 0))
    assert tp.valid(homogeneous(rot_x(math.radians(0.4))))
    assert not tp.valid(homogeneous(rot_x(math.radians(0.6))))


def test_full_range_entries_are_unconstrained():
    tp = ToleratedPose(np.eye(4), ["x", "Theta_R"], [[-math.inf, math.inf], [0, math.pi]])
    assert tp.is_unconstrained


# ------------------------------------------------------------------------------------------------ errors
def goal(obj):
    return ToleratedPose.from_json(obj, "PTP_3.json", ["goals", 0, "goalPose"])


BASE = {"nominal": np.eye(4).tolist()}


@pytest.mark.parametrize("extra, message", [
    ({"toleranceProjection": ["r_sph", "Theta"], "tolerance": [[0, 0.01], [0, 0.01]]},
     r"PTP_3\.json: goals\[0\]\.goalPose\.toleranceProjection\[1\]: unknown tolerance projection 'Theta' "
     r"\(did you mean 'Theta_R'\?\); known projections: x, y, z, r_cyl"),
    ({"toleranceProjection": ["r_sph", "Theta_R"], "tolerance": [[0, 0.01], [0.02, 0.01]]},
     r"PTP_3\.json: goals\[0\]\.goalPose\.tolerance\[1\]: lower bound 0\.02 is greater than upper bound 0\.01"),
    ({"toleranceProjection": ["r_cyl"], "tolerance": [[-0.1, 0.2]]},
     r"goalPose\.tolerance\[0\]: bounds \[-0\.1, 0\.2\] of 'r_cyl' are outside its allowed range \[0, ∞\]"),
    ({"toleranceProjection": ["Theta_R"], "tolerance": [[0, 4]]},
     r"goalPose\.tolerance\[0\]: bounds \[0, 4\] of 'Theta_R' are outside its allowed range"),
    ({"toleranceProjection": ["phi_cyl"], "tolerance": [[-4, 4]]},
     r"goalPose\.tolerance\[0\]: bounds \[-4, 4\] of angle 'phi_cyl' must lie in \[-2π, 2π\] and span at most 2π"),
    ({"toleranceProjection": ["x", "y"], "tolerance": [[0, 0.01]]},
     r"goalPose\.tolerance: 2 projection\(s\) in toleranceProjection but 1 interval\(s\) in tolerance"),
    ({"toleranceProjection": ["x", "y"], "tolerance": [[0, 1], [0, 1]], "toleranceFrame": ["world"]},
     r"goalPose\.toleranceFrame: 2 projection\(s\) in toleranceProjection but 1 frame\(s\)"),
    ({"toleranceProjection": ["x"], "tolerance": [[0, "a"]]},
     r"goalPose\.tolerance\[0\]\[1\]: expected a number, got \"a\""),
    ({"toleranceProjection": ["x"], "tolerance": [[math.nan, 1]]},
     r"goalPose\.tolerance\[0\]\[0\]: NaN is not a valid bound"),
    ({"toleranceProjection": ["x"], "tolerance": [[0, 1]], "toleranceFrame": ["table"]},
     r"goalPose\.toleranceFrame\[0\]: unknown frame 'table'"),
    ({"tolerances": []}, r"goalPose\.tolerances: unknown key 'tolerances' \(did you mean 'tolerance'\?\)"),
])
def test_bad_input_names_file_and_json_path(extra, message):
    with pytest.raises(InputError, match=message):
        goal({**BASE, **extra})


def test_missing_nominal_and_bad_pose():
    with pytest.raises(InputError, match=r"goals\[0\]\.goalPose: missing required key 'nominal'"):
        goal({"toleranceProjection": []})
    with pytest.raises(InputError, match=r"goals\[0\]\.goalPose\.nominal: expected a 4x4 matrix"):
        goal({"nominal": [[1, 0], [0, 1]]})


def test_bounds_slack_for_pi():
    tp = ToleratedPose(np.eye(4), ["Theta_R"], [[0, 3.1416]])      # 3.1416 > π by 7e-6: accepted, clipped
    assert tp.intervals[0][1] == pytest.approx(math.pi)


# ------------------------------------------------------------------------------------------------ real task
def test_ptp3_goal_tolerances_5mm_valid_15mm_not():
    task = loads_json(PTP_3.read_text(), str(PTP_3))
    for i, g in enumerate(task["goals"]):
        tp = ToleratedPose.from_json(g["goalPose"], PTP_3.name, ["goals", i, "goalPose"])
        assert tp.projections == ("r_sph", "Theta_R")
        n = tp.nominal
        d = np.array([3.0, -4.0, 0.0]) / 5.0                  # a unit direction in the world
        ok = translation(*(0.005 * d)) @ n
        bad = translation(*(0.015 * d)) @ n
        assert tp.valid(ok)
        assert not tp.valid(bad)
        (name, value, lo, hi), = tp.violations(bad)
        assert name == "r_sph" and value == pytest.approx(0.015) and (lo, hi) == (0.0, 0.01)
        assert tp.residual(bad) == pytest.approx([0.005, 0.0])
        # rotation: 0.005 rad about the tool z axis is inside, 0.015 rad is not
        assert tp.valid(n @ homogeneous(rot_z(0.005)))
        assert not tp.valid(n @ homogeneous(rot_z(0.015)))
        s = tp.sample(np.random.default_rng(i))
        assert tp.valid(s)


# ------------------------------------------------------------------------------------------------ IK helpers
def test_residual_zero_exactly_when_valid():
    rng = np.random.default_rng(3)
    tp = ToleratedPose(homogeneous(rot_y(0.4), (0.2, 0.1, 0.5)), ["x", "z", "r_cyl", "N_z", "Theta_R"],
                       [[-0.02, 0.02], [0, 0.05], [0, 0.03], [-0.1, 0.1], [0, 0.2]],
                       ["nominal", "world", "nominal", "nominal", "nominal"])
    for _ in range(300):
        T = tp.nominal @ homogeneous(rot_x(rng.uniform(-0.3, 0.3)) @ rot_z(rng.uniform(-0.3, 0.3)),
                                     rng.uniform(-0.06, 0.06, 3))
        assert tp.valid(T) == bool(np.all(tp.residual(T) == 0))


def test_sample_is_inside_and_reproducible():
    tp = ToleratedPose(homogeneous(rot_x(1.0), (1, 2, 3)), ["phi_cyl", "x", "z", "Theta_R", "A"],
                       [[2.9, 3.4], [-1, -0.5], [0, 0.01], [0.1, 0.2], [0.99, 1]],
                       ["nominal", "nominal", "world", "nominal", "nominal"])
    a = [tp.sample(np.random.default_rng(7)) for _ in range(2)]
    assert np.array_equal(a[0], a[1])
    rng = np.random.default_rng(0)
    for _ in range(100):
        assert tp.valid(tp.sample(rng))


def test_sample_keeps_unconstrained_part_nominal():
    n = homogeneous(rot_x(0.7), (1, 2, 3))
    tp = ToleratedPose(n, ["Theta_R"], [[0.1, 0.2]])
    s = tp.sample(1)
    assert s[:3, 3] == pytest.approx(n[:3, 3])
    assert 0.1 <= projection_value("Theta_R", tp.delta(s)) <= 0.2


def test_contradicting_frames_cannot_be_sampled():
    n = homogeneous(rot_z(math.pi / 2))
    tp = ToleratedPose(n, ["x", "y"], [[0.1, 0.2], [-0.01, 0.01]], ["nominal", "world"])
    with pytest.raises(ToleranceSamplingError):
        tp.sample(0, max_tries=200)                            # nominal x = world y, so y ∈ [0.1, 0.2] ≠ ±0.01


def test_project_moves_pose_inside():
    tp = ToleratedPose(np.eye(4), ["r_sph", "Theta_R"], [[0, 0.01], [0, 0.01]])
    T = homogeneous(rot_z(0.5), (0.03, 0.04, 0.0))
    P = tp.project(T)
    assert tp.valid(P)
    assert P[:3, 3] == pytest.approx([0.006, 0.008, 0.0], abs=1e-8)    # radial clip keeps the direction
    assert projection_value("Theta_R", P) == pytest.approx(0.01, abs=1e-8)
    assert np.array_equal(tp.project(np.eye(4)), np.eye(4))


def test_project_nominal_when_nominal_is_outside():
    n = homogeneous(rot_z(1.0), (1, 1, 1))
    tp = ToleratedPose(n, ["x", "phi_cyl"], [[0.1, 0.2], [0.5, 1.0]])
    assert not tp.nominal_is_valid
    P = tp.project_nominal()
    assert tp.valid(P)
    d = tp.delta(P)
    assert d[0, 3] == pytest.approx(0.1, abs=1e-6)


# ------------------------------------------------------------------------------------------------ JSON
def test_to_json_round_trip_with_infinity_and_frames():
    obj = {"nominal": homogeneous(rot_z(0.5), (1, 2, 3)).tolist(),
           "toleranceProjection": ["x", "z", "N_z", "phi_cyl"],
           "tolerance": [[-math.inf, 0.1], [0, 0.05], [-0.1, 0.1], [2.9, 3.4]],
           "toleranceFrame": ["nominal", "world", "nominal", "nominal"]}
    tp = ToleratedPose.from_json(obj, "t.json")
    text = dumps_json(tp.to_json())
    assert "-Infinity" in text
    back = ToleratedPose.from_json(loads_json(text), "t.json")
    assert back.projections == tp.projections and back.intervals == tp.intervals and back.frames == tp.frames
    assert back.nominal == pytest.approx(tp.nominal)
    assert json.loads(json.dumps(tp.to_json()["toleranceFrame"])) == obj["toleranceFrame"]


def test_the_fast_values_of_plain_tolerances_equal_the_general_ones():
    """A tolerance of x, y, z and Theta_R only (the published goals) computes just those values; they are bit for
    bit the values of the general path (translation_values / rotation_values of Δ in the entry's frame), in the
    nominal frame and in the world frame, and the verdicts agree on poses at and around the bounds."""
    from robodesign.formats.tolerance import rotation_values, translation_values

    rng = np.random.default_rng(11)
    nominal = homogeneous(rot_z(0.7) @ rot_x(-0.4), [0.5, -0.2, 0.9])
    specs = [
        {"toleranceProjection": ["x", "y", "z", "Theta_R"],
         "tolerance": [[-0.001, 0.001], [-0.001, 0.001], [-0.001, 0.001], [0, 0.008726646259971648]]},
        {"toleranceProjection": ["x", "z", "Theta_R"], "tolerance": [[-0.01, 0.02], [0, 0.05], [0, 0.1]],
         "toleranceFrame": ["world", "nominal", "world"]},
        {"toleranceProjection": ["z", "N_z", "Theta_R"], "tolerance": [[-0.01, 0.01], [-0.3, 0.3], [0, 0.5]]},  # general
    ]
    for spec in specs:
        tp = ToleratedPose.from_json({"nominal": nominal.tolist(), **spec})
        for k in range(300):
            scale = [1e-4, 1e-3, 1e-2, 0.3][k % 4]
            T = nominal @ homogeneous(rot_z(rng.normal() * scale) @ rot_y(rng.normal() * scale),
                                      rng.normal(size=3) * scale)
            got = tp.values(T)
            D = tp.delta(T)
            for (name, frame), v in got.items():
                Q = tp._Q[frame]
                want = {**translation_values(Q @ D[:3, 3]),
                        **rotation_values(Q @ D[:3, :3] @ Q.T)}[name][0]
                assert v == want, (spec, name, frame)
            if "N_z" not in spec["toleranceProjection"]:  # the verdict from the general values, by hand
                assert tp.valid(T) == all(lo - 1e-12 <= got[(n, f)] <= hi + 1e-12 for n, (lo, hi), f in tp.entries)
