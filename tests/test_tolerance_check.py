"""The fast path of ToleratedPose.valid (formats/tolerance_check.py, issue 25) against the reference
(``violations``/``_frame_values``): the same values and the same verdicts on random poses on, next to and off the
bounds of every projection kind, in the nominal frame (where the plan leaves out the identity product) and in
others."""
import math
import zlib

import numpy as np
import pytest

from robodesign.core.spatial import homogeneous, rot_x, rot_y, rot_z
from robodesign.formats.tolerance import EPS, PROJECTIONS, ToleratedPose, quaternion_to_rotation

FRAME_POSE = homogeneous(rot_z(0.7) @ rot_x(-0.4), [0.2, -0.1, 0.3])
NOMINAL = homogeneous(rot_y(0.5) @ rot_z(2.0), [0.4, 0.1, -0.2])

# projection sets sharing one frame: plain ones (x, y, z, Theta_R), ones where the nominal frame's identity
# product is left out (no azimuth, no R/P/Y, Euler or quaternion value) and ones where it is not
GROUPS = [("x",), ("x", "y", "z", "Theta_R"), ("Theta_R",), ("r_sph", "Theta_R"), ("r_cyl", "z"), ("theta",),
          ("r_sph", "theta", "N_z"), ("N_x", "N_y"), ("N_x", "N_y", "N_z", "Theta_R"), ("phi_cyl", "r_cyl"),
          ("phi_sph", "theta", "x"), ("R", "P", "Y"), ("Alpha", "Beta", "Gamma", "Theta_R"), ("A", "B", "C", "D"),
          ("B", "N_y", "y"), ("P",), ("Y", "phi_cyl")]
FRAMES = ["nominal", "world", "task"]


def _resolver(name):
    assert name == "task"
    return FRAME_POSE


def _full(p):
    info = PROJECTIONS[p]
    return [-math.pi, math.pi] if info.periodic else [info.lo, info.hi]


def _pose(names, frame, intervals=None):
    iv = intervals or [_full(n) for n in names]
    return ToleratedPose(NOMINAL, list(names), iv, [frame] * len(names), frame_resolver=_resolver)


def _rotation(rng):
    kind = rng.integers(6)
    if kind == 0:
        return np.eye(3)
    if kind == 1:      # half turns and quarter turns: exact zeros and ±1 entries (signs of zeros, branch cuts)
        return [rot_z(math.pi), rot_x(math.pi), rot_y(math.pi / 2), rot_z(-math.pi / 2)][rng.integers(4)]
    if kind == 2:      # tiny angles
        return rot_z(rng.normal() * 1e-9) @ rot_x(rng.normal() * 1e-7)
    if kind == 3:      # near a half turn (log3's other branch)
        return rot_x(math.pi - abs(rng.normal()) * 1e-3) @ rot_z(rng.normal() * 1e-4)
    q = rng.normal(size=4)
    return quaternion_to_rotation(q / np.linalg.norm(q))


def _translation(rng):
    kind = rng.integers(5)
    if kind == 0:
        return np.zeros(3)
    if kind == 1:      # on the z axis (azimuth degenerate), signed zeros
        return np.array([0.0, -0.0, rng.normal() * 0.1])
    if kind == 2:      # on the negative x axis: atan2(±0, x < 0)
        return np.array([-abs(rng.normal()), -0.0, 0.0])
    return rng.normal(size=3) * 10.0 ** rng.integers(-6, 1)


def _delta_poses(rng, n):
    """World poses T whose Δ = nominal⁻¹·T has the structured parts above (the product rounds them a little)."""
    out = []
    for _ in range(n):
        D = homogeneous(_rotation(rng), _translation(rng))
        out.append(NOMINAL @ D)
        out.append(D)          # a pose that is not near the nominal one
    return out


def _same(a, b):
    return a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b))


def _around(v, lo_allowed, hi_allowed):
    """Bounds on, one ulp and one eps next to, and off a value."""
    pts = [v, np.nextafter(v, -math.inf), np.nextafter(v, math.inf), v - EPS, v + EPS,
           np.nextafter(v - EPS, -math.inf), np.nextafter(v + EPS, math.inf), v - 1e-3, v + 1e-3]
    return [float(min(max(p, lo_allowed), hi_allowed)) for p in pts]


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("names", GROUPS)
def test_the_plan_computes_the_reference_values(names, frame):
    tp = _pose(names, frame)
    rng = np.random.default_rng(zlib.crc32(repr((names, frame)).encode()))
    checked = 0
    for T in _delta_poses(rng, 60):
        ref = tp._frame_values(T)[frame]
        fast = tp._plan.values(tp.delta(T))
        assert fast is not None and len(fast) == 1
        for n in names:
            (v, dv), (w, dw) = ref[n], fast[0][n]
            assert dv == dw and _same(v, w), (n, frame, v, w)
            if not (tp._plan.frames[0].skip_p or tp._plan.frames[0].skip_r):
                assert math.copysign(1.0, v) == math.copysign(1.0, w)   # the very same product: even zeros' signs
            checked += 1
    assert checked == 120 * len(names)


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("names", GROUPS)
def test_verdicts_on_next_to_and_off_the_bounds(names, frame):
    """Bounds are placed on each pose's own values (and an ulp, an eps and a millimetre/milliradian next to
    them), one projection at a time, so that the check runs exactly where the comparisons decide."""
    base = _pose(names, frame)
    rng = np.random.default_rng(zlib.crc32(repr((frame, names)).encode()) + 1)
    verdicts = {True: 0, False: 0}
    for T in _delta_poses(rng, 12):
        vals = base._frame_values(T)[frame]
        for i, n in enumerate(names):
            v = vals[n][0]
            info = PROJECTIONS[n]
            lo_a, hi_a = (-2 * math.pi, 2 * math.pi) if info.periodic else (info.lo, info.hi)
            pts = _around(v, lo_a, hi_a)
            for lo, hi in [(pts[0], pts[0]), (pts[1], pts[0]), (pts[0], pts[2]), (pts[3], pts[4]), (pts[4], pts[8]),
                           (pts[6], pts[8]), (pts[7], pts[5]), (pts[7], pts[3]), (pts[7], pts[8])]:
                if lo > hi:
                    continue
                iv = [_full(m) for m in names]
                iv[i] = [lo, hi]
                tp = _pose(names, frame, iv)
                for eps in (EPS, 0.0):
                    ref = not tp.violations(T, eps)
                    assert tp.valid(T, eps) is ref, (n, frame, lo, hi, v)
                    verdicts[ref] += 1
    assert verdicts[True] > 50 and verdicts[False] > 50


def test_several_frames_and_entries_on_one_projection():
    names = ["r_sph", "x", "Theta_R", "N_z", "phi_cyl", "x", "R", "A"]
    frames = ["nominal", "world", "task", "task", "world", "world", "nominal", "task"]
    rng = np.random.default_rng(3)
    n_valid = 0
    for T in _delta_poses(rng, 200):
        vals = {}
        wide = ToleratedPose(NOMINAL, names, [_full(n) for n in names], frames, frame_resolver=_resolver)
        for (n, f), v in wide.values(T).items():
            vals[(n, f)] = v
        iv = []
        for n, f in zip(names, frames):     # an interval of ±20 % of each value's range around it
            v = vals[(n, f)]
            info = PROJECTIONS[n]
            w = 0.2 * (2 * math.pi if info.periodic else min(info.hi - info.lo, 2.0))
            lo_a, hi_a = (-2 * math.pi, 2 * math.pi) if info.periodic else (info.lo, info.hi)
            iv.append([max(v - w * rng.uniform(0, 1.2), lo_a), min(v + w * rng.uniform(0, 1.2), hi_a)])
        tp = ToleratedPose(NOMINAL, names, iv, frames, frame_resolver=_resolver)
        for T2 in (T, T @ homogeneous(rot_z(0.05), [0.01, 0.0, 0.0])):
            ref = not tp.violations(T2)
            assert tp.valid(T2) is ref
            n_valid += ref
    assert 100 < n_valid < 700   # of 800: both verdicts, many times


def test_non_finite_and_unconstrained_poses_go_the_reference_way():
    with np.errstate(invalid="ignore", over="ignore"):   # the reference's products of infinities
        tp = _pose(("r_sph", "Theta_R"), "nominal", [[0.0, 0.01], [0.0, 0.01]])
        T = NOMINAL.copy()
        assert tp.valid(T) is True and tp._plan.needs_finite
        for bad in (math.inf, -math.inf, math.nan):
            T2 = NOMINAL.copy()
            T2[0, 3] = bad
            assert tp._plan.valid(tp.delta(T2), EPS) is None
            assert tp.valid(T2) is (not tp.violations(T2)) is False
        # x in (−∞, ∞) holds for an infinite x, but I @ p makes NaNs of it: the plan leaves the pose to the reference
        tx = _pose(("x", "r_cyl"), "nominal", [[-math.inf, math.inf], [0.0, math.inf]])
        T3 = np.eye(4)
        T3[:3, 3] = (0.0, math.inf, 0.0)
        T3 = NOMINAL @ T3
        assert tx.valid(T3) is (not tx.violations(T3))
        free = ToleratedPose(NOMINAL)
        assert free.is_unconstrained and free.valid(np.full((4, 4), math.nan)) is True


def test_ptp3_goal_checks_as_before():
    tp = ToleratedPose(NOMINAL, ["r_sph", "Theta_R"], [[0.0, 0.01], [0.0, 0.01]])
    f = tp._plan.frames[0]
    assert (f.skip_p, f.skip_r, f.needs_finite) == (True, True, True)
    assert tp.valid(NOMINAL @ homogeneous(rot_x(0.0099), [0.0099, 0.0, 0.0])) is True
    assert tp.valid(NOMINAL @ homogeneous(rot_x(0.0101), [0.0, 0.0, 0.0])) is False
    assert tp.valid(NOMINAL @ homogeneous(np.eye(3), [0.0, 0.006, 0.0081])) is False   # r = 0.01006


def _exact_deltas():
    """Δs with exact zeros of both signs and half turns: atan2's branch cut (an azimuth or roll/yaw of ±π) is
    where the sign of a zero shows, i.e. where leaving out the identity product would change a value."""
    m0, z = -0.0, 0.0
    rots = [np.eye(3), np.array([[-1.0, m0, z], [z, -1.0, m0], [m0, z, 1.0]]),
            np.array([[1.0, z, z], [z, -1.0, m0], [z, z, -1.0]]), np.array([[-1.0, z, m0], [m0, 1.0, z], [z, z, -1.0]]),
            np.array([[z, -1.0, z], [1.0, m0, z], [z, z, 1.0]])]
    ps = [(z, z, z), (m0, m0, m0), (-0.3, m0, z), (-0.3, z, m0), (m0, z, 0.2), (0.1, -0.2, 0.3)]
    return [homogeneous(R, p) for R in rots for p in ps]


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("names", GROUPS)
def test_signed_zeros_on_branch_cuts(names, frame):
    tp = _pose(names, frame)
    tp.delta = lambda T: np.asarray(T, dtype=float)     # the reference on these very Δs (no product rounding)
    for D in _exact_deltas():
        ref = tp._frame_values(D)[frame]
        fast = tp._plan.values(D)[0]
        for n in names:
            (v, dv), (w, dw) = ref[n], fast[n]
            assert dv == dw and v == w, (n, frame, D.tolist(), v, w)


def test_huge_poses_go_the_reference_way():
    """A Python float's ``**`` raises OverflowError where numpy's float64 (the reference) gives inf."""
    for names, frame in ((("Theta_R",), "task"), (("r_sph", "Theta_R"), "nominal"), (("N_x", "N_z"), "world")):
        tp = _pose(names, frame, [[0.0, 0.5] if n in ("Theta_R", "r_sph") else [-0.5, 0.5] for n in names])
        T = NOMINAL @ homogeneous(np.array([[1.0, -1e200, 0.0], [1e200, 1.0, 0.0], [0.0, 0.0, 1.0]]), [0.0, 0.0, 0.0])
        with np.errstate(all="ignore"):
            assert tp._plan.valid(tp.delta(T), EPS) is None
            assert tp.valid(T) is (not tp.violations(T))


RADIAL_GROUPS = [g for g in GROUPS if set(g) <= {"x", "y", "z", "r_cyl", "r_sph", "Theta_R"}]


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("names", RADIAL_GROUPS)
def test_radial_frames_give_the_reference_values_in_entry_order(names, frame):
    """A frame of x, y, z, r_cyl, r_sph and Theta_R only takes the plan's list path (``radial_values``): the same
    values, bit for bit, as the dict path and as the reference, in the entries' order."""
    pose = _pose(names, frame)
    plan = pose._plan
    assert plan.radial
    rng = np.random.default_rng(zlib.crc32(repr((names, frame)).encode()))
    for T in _delta_poses(rng, 60):
        D = pose._nominal_inv @ T
        rows = D.tolist()
        ref = pose._frame_values(T)
        for fr in plan.frames:
            fast = fr.radial_values(D, rows)
            slow = fr.values(D, rows)
            for (name, *_), v in zip(fr.entries, fast):
                assert _same(v, slow[name][0]) and _same(v, ref[fr.frame][name][0])
