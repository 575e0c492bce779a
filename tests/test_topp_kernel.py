"""The compiled TOPP-RA passes (robodesign.solvers.topp_kernel, toppra_loop.compiled_rest_to_rest) against toppra's own
compute_parameterization with its seidel solver: the same path velocities bit for bit wherever the kernel answers,
and the same trajectories from time_parameterize with and without the kernel."""
import numpy as np
import pytest
from conftest import IMPROV

from robodesign import Robot, load_module_set
from robodesign.core.defaults import DEFAULT_ORDER
from robodesign.solvers import timing, topp_kernel, toppra_loop

ARM = ["1", "21", "4", "22", "5", "23", "12"]


@pytest.fixture(scope="module")
def kernel():
    if not (topp_kernel.available() and topp_kernel.warm_up()):
        pytest.skip("numba unavailable or ROBODESIGN_JIT=0")
    return topp_kernel


@pytest.fixture(scope="module")
def ptp3_paths():
    """(robot, joint path) of every move time_parameterize timed while solving PTP_3 with the known-good IMPROV
    arm (seeds 0 and 1): the planner's real paths."""
    from conftest import TASKS

    from robodesign.design import goal_planner
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.formats.task_io import load_task
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    seen = []
    real = goal_planner.time_parameterize

    def record(robot, path, **kw):
        seen.append((robot, np.array(path, dtype=float)))
        return real(robot, path, **kw)
    goal_planner.time_parameterize = record
    try:
        for seed in (0, 1):
            assert solve(task, ms, ARM, settings=SolveSettings(seed=seed)).feasible
    finally:
        goal_planner.time_parameterize = real
    assert len(seen) >= 4
    return seen


def _robots():
    imp = load_module_set(IMPROV)
    from conftest import ROOT
    builtin = load_module_set(ROOT / "assets" / "modules" / "robodesign_arm")
    return [Robot.from_order(imp, ARM), Robot.from_order(imp, ["1", "22", "5", "23", "15", "29", "101"]),
            Robot.from_order(builtin, list(DEFAULT_ORDER))]


def _scaled(robot, factor):
    """A shallow copy of ``robot`` with its torque limits scaled."""
    import copy
    r = copy.copy(robot)
    r.tau_max = np.asarray(robot.tau_max, float) * factor
    return r


def _compare(robot, waypoints, x0_value, use_torque=True):
    """One TOPP-RA pass both ways: (kernel answered, toppra succeeded); asserts the same velocities, bit for bit,
    whenever the kernel answers."""
    tp = timing._toppra()
    path = timing.BlendedPolyline(waypoints, 0.05)
    grid = path.gridpoints(0.02)
    vmax, amax = timing._finite(robot.dq_max), timing._finite(robot.ddq_max)
    terms = timing._PathTerms(robot, path, grid, use_torque)
    dyn = timing._dynamics_constraint_class()(robot, amax, np.asarray(robot.tau_max, float),
                                               np.full(len(grid), x0_value), use_torque, terms)
    vel = timing._velocity_constraint(vmax)
    xbound = vel.compute_constraint_params(path, grid)[-1]
    fast = toppra_loop.compiled_rest_to_rest(dyn, path, grid, xbound)
    dyn.terms = None    # seidelWrapper's coefficients by compute_constraint_params and seidel_rows instead
    generic = toppra_loop.compiled_rest_to_rest(dyn, path, grid, xbound)
    assert (fast is None) == (generic is None) and (fast is None or fast.tobytes() == generic.tobytes())
    algo = tp.algorithm.TOPPRA([vel, dyn], path, gridpoints=grid, solver_wrapper="seidel")
    algo.compute_parameterization(0.0, 0.0)
    pd = algo.problem_data
    ok = pd.return_code == tp.algorithm.ParameterizationReturnCode.Ok and pd.sd_vec is not None
    if fast is not None:
        assert ok, "the kernel answered where toppra failed"
        assert fast.tobytes() == np.asarray(pd.sd_vec, float).tobytes()
    return fast is not None, ok


def test_kernel_gives_toppras_velocities_on_ptp3_paths(kernel, ptp3_paths):
    """The planner's PTP_3 paths, the arm's torque limits and tighter ones (active torque rows), several viscous
    tangent points, with and without torque rows."""
    runs = []
    for robot, path in ptp3_paths:
        for factor in (1.0, 0.5, 0.3):
            r = robot if factor == 1.0 else _scaled(robot, factor)
            for x0 in (0.05, 0.5, 4.0):
                runs.append(_compare(r, path, x0))
        runs.append(_compare(robot, path, 1.0, use_torque=False))
    answered, solved = sum(f for f, _ in runs), sum(ok for _, ok in runs)
    print(f"{len(runs)} passes: toppra solved {solved}, the kernel answered {answered}")
    assert solved >= len(ptp3_paths) * 4 and answered == solved


def test_kernel_gives_toppras_velocities_on_random_paths(kernel):
    """Random waypoint paths on two IMPROV arms and the built-in arm, with torque limits down to a fifth (where
    toppra fails the kernel must not answer; where it answers the velocities are toppra's)."""
    rng = np.random.default_rng(7)
    answered = solved = 0
    for robot in _robots():
        lo, hi = np.maximum(robot.q_lower, -3.0), np.minimum(robot.q_upper, 3.0)
        for _ in range(6):
            path = lo + (hi - lo) * rng.random((int(rng.integers(2, 6)), robot.dof))
            for factor in (1.0, 0.35, 0.2):
                fast, ok = _compare(robot if factor == 1.0 else _scaled(robot, factor), path,
                                    float(rng.choice([0.02, 0.3, 2.0])))
                answered += fast
                solved += ok
    print(f"toppra solved {solved} passes, the kernel answered {answered}")
    assert solved >= 20 and answered >= 0.9 * solved


def test_seidel_rows_are_the_dot_products(kernel, ptp3_paths):
    """seidel_rows picks F's columns where seidelWrapper multiplies by Fᵀ with BLAS: the same bytes, negative zeros
    included (BLAS sums from +0)."""
    robot, waypoints = ptp3_paths[0]
    path = timing.BlendedPolyline(waypoints, 0.05)
    grid = path.gridpoints(0.02)
    terms = timing._PathTerms(robot, path, grid, True)
    dyn = timing._dynamics_constraint_class()(robot, timing._finite(robot.ddq_max), np.asarray(robot.tau_max, float),
                                               np.full(len(grid), 0.3), True, terms)
    A, B, C, F, h, _, _ = dyn.compute_constraint_params(path, grid)
    A, B, C = A.copy(), B.copy(), C.copy()
    for X in (A, B, C):       # negative zeros and zeros in some places
        X[::7, ::5] = -0.0
        X[3::11, 2::9] = 0.0
    xbound = timing._velocity_constraint(timing._finite(robot.dq_max)).compute_constraint_params(path, grid)[-1]
    a, b, c, low, high = toppra_loop.seidel_rows(A, B, C, F, h, xbound)
    assert a[:, 2:].tobytes() == A.dot(F.T).tobytes()
    assert b[:, 2:].tobytes() == B.dot(F.T).tobytes()
    assert c[:, 2:].tobytes() == (C.dot(F.T) - h).tobytes()
    assert np.array_equal(low[:, 1], np.maximum(-1e8, xbound[:, 0]))
    assert np.array_equal(high[:, 1], np.minimum(1e8, xbound[:, 1]))
    F2 = F.copy()
    F2[0, 1] = 0.5      # not a signed selection: no rows (toppra's own set-up runs)
    assert toppra_loop.seidel_rows(A, B, C, F2, h, xbound) is None


def _timed(robot, path):
    """time_parameterize's trajectory arrays and info, or its TimingError's message."""
    try:
        tr = timing.time_parameterize(robot, path, dt=0.01)
    except timing.TimingError as e:
        return str(e)
    return [x.tobytes() for x in (tr.t, tr.q, tr.dq, tr.ddq)] + [tr.info["method"], tr.info["stretch"]]


@pytest.mark.parametrize("factor", [1.0, 0.5])
def test_time_parameterize_is_the_same_without_the_kernel(kernel, ptp3_paths, monkeypatch, factor):
    """Whole trajectories (every pass, the resampling, the torque checks; or the same failure): with the kernel and
    with toppra's loop (the kernel not ready), bit for bit."""
    timed = 0
    for robot, path in ptp3_paths:
        r = robot if factor == 1.0 else _scaled(robot, factor)
        fast = _timed(r, path)
        with monkeypatch.context() as m:
            m.setattr(topp_kernel, "ready", lambda: False)
            assert _timed(r, path) == fast
        timed += not isinstance(fast, str)
    assert timed >= len(ptp3_paths) // 2


def _rows_both_ways(robot, waypoints, x0, use_torque=True):
    path = timing.BlendedPolyline(waypoints, 0.05)
    grid = path.gridpoints(0.02)
    terms = timing._PathTerms(robot, path, grid, use_torque)
    dyn = timing._dynamics_constraint_class()(robot, timing._finite(robot.ddq_max), np.asarray(robot.tau_max, float),
                                               x0(len(grid)), use_torque, terms)
    xbound = timing._velocity_constraint(timing._finite(robot.dq_max)).compute_constraint_params(path, grid)[-1]
    numpy_rows = toppra_loop.seidel_rows(*dyn.compute_constraint_params(path, grid)[:5], xbound)
    compiled = toppra_loop._compiled_rows(dyn, terms, np.diff(grid), xbound)
    assert (numpy_rows is None) == (compiled is None)
    if compiled is not None:
        for x, y in zip(compiled, numpy_rows):
            assert x.tobytes() == y.tobytes()
    return compiled is not None


def test_compiled_constraint_rows_are_the_numpy_ones(kernel, ptp3_paths):
    """topp_kernel.constraint_rows against DynamicsConstraint.compute_constraint_params + seidel_rows: torque rows on
    and off, limits scaled, a joint without a torque limit, viscous tangent points below the 1e-8 floor, NaN."""
    robot, path = ptp3_paths[0]
    unlimited = _scaled(robot, 1.0)
    unlimited.tau_max = np.where(np.arange(robot.dof) == 2, np.inf, robot.tau_max)
    rng = np.random.default_rng(5)
    answered = 0
    for r in (robot, _scaled(robot, 0.4), unlimited):
        for x0 in (lambda n: np.full(n, 0.3), lambda n: rng.uniform(0.0, 3.0, n),
                   lambda n: np.where(np.arange(n) % 3 == 0, 1e-12, 0.5)):
            for _, p in ptp3_paths[:2]:
                answered += _rows_both_ways(r, p, x0)
        answered += _rows_both_ways(r, path, lambda n: np.full(n, 1.0), use_torque=False)
    assert answered == 3 * 7
    assert not _rows_both_ways(robot, path, lambda n: np.where(np.arange(n) == 4, np.nan, 0.5))
