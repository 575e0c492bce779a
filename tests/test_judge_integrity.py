"""Time and cost integrity of the judge (issue 22, cases 1, 5 and 6; case 4 is in test_costs.py).

Each test starts from robodesign's own PTP_3 solution (IMPROV 1,21,4,22,5,23,12, as in the README), applies the
attack of the issue and asserts the fixed behaviour through the API and the CLI.
"""
import json

import numpy as np
import pytest
from conftest import IMPROV, TASKS

from robodesign.cli.entry import main
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.module_io import load_module_set
from robodesign.formats.solution import SolutionTrajectory
from robodesign.formats.task_io import load_task
from robodesign.judge.checker import check

ORDER = ["1", "21", "4", "22", "5", "23", "12"]
PTP3 = TASKS / "simple" / "PTP_3.json"


@pytest.fixture(scope="module")
def ptp3():
    task = load_task(PTP3)
    ms = load_module_set(IMPROV)
    res = solve(task, ms, ORDER, settings=SolveSettings(seed=0))
    assert res.feasible, res.message
    return task, ms, res.solution


def _write(sol, path, **overrides):
    d = sol.to_json()
    d.update(overrides)
    path.write_text(json.dumps(d))
    return str(path)


def _cli(capsys, *argv):
    code = main(["check", str(PTP3), *argv, "--modules", str(IMPROV)])
    return code, capsys.readouterr()


def test_time_shift_is_invalid(ptp3, tmp_path, capsys):
    """Case 1: t and goal2time shifted by −100 s gave VALID with cyc = −96.51."""
    task, ms, sol = ptp3
    v0 = check(task, sol, ms)
    assert v0.valid and v0.costs["cyc"] == pytest.approx(sol.trajectory.t[-1]) and sol.trajectory.t[0] == 0.0
    tr = sol.trajectory
    shifted = sol.with_(trajectory=SolutionTrajectory(tr.t - 100, tr.q, tr.dq, tr.ddq,
                                                      {g: x - 100 for g, x in tr.goal2time.items()}))
    v = check(task, shifted, ms)
    assert not v.valid
    bad = [x for x in v.violations if x.constraint == "trajectory.t"]
    assert len(bad) == 1 and bad[0].sample == 0 and bad[0].value == pytest.approx(-100) and bad[0].bound == 0.0
    assert "must start at t = 0" in bad[0].message
    code, out = _cli(capsys, _write(shifted, tmp_path / "shift.json"))
    assert code == 1 and "INVALID" in out.out and "must start at t = 0" in out.out


def test_sampled_every_second_step_is_invalid(ptp3, tmp_path, capsys):
    """Case 6: every 2nd sample (steps of 2·timeStepSize) was VALID; the reference asserts "Solution should be
    sampled every timeStepSize". Judged the same way now, over the whole trajectory."""
    task, ms, sol = ptp3
    tr = sol.trajectory
    keep = np.arange(0, tr.n, 2)
    g2t = {g: x for g, x in tr.goal2time.items() if np.isclose(tr.t[keep], x).any()}
    half = sol.with_(trajectory=SolutionTrajectory(tr.t[keep], tr.q[keep], tr.dq[keep], tr.ddq[keep], g2t))
    v = check(task, half, ms)
    bad = [x for x in v.violations if x.constraint == "trajectory.t"]
    assert not v.valid and len(bad) == 1
    assert bad[0].sample == 0 and bad[0].value == pytest.approx(2 * task.dt) and bad[0].bound == task.dt
    assert "timeStepSize" in bad[0].message and f"{len(keep) - 1} such steps" in bad[0].message
    code, out = _cli(capsys, _write(half, tmp_path / "half.json"))
    assert code == 1 and "sampled every timeStepSize" in out.out


@pytest.mark.parametrize("cost", ["cyc_1e308", "cyc,fulfillN_-1e308"])
def test_overflowing_cost_is_bad_input(ptp3, tmp_path, capsys, cost):
    """Case 5: such costs were stored as valid with cost null; now exit 2 with one line naming file and field."""
    task, ms, sol = ptp3
    f = _write(sol, tmp_path / "big.json", costFunction=cost)
    code, out = _cli(capsys, f)
    err = out.err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "big.json" in err[0] and "costFunction" in err[0]
    assert "larger than 1e+06" in err[0] and "Traceback" not in out.err


def test_check_json_is_strict_on_non_finite_values(ptp3, tmp_path, capsys):
    """Case 5: `check --json` printed Infinity for a q of 1e308. Non-finite numbers are strings now."""
    task, ms, sol = ptp3
    q = sol.trajectory.q.copy()
    q[5, 0] = 1e308
    d = sol.to_json()
    d["trajectory"]["q"] = q.tolist()
    f = tmp_path / "huge.json"
    f.write_text(json.dumps(d))
    code, out = _cli(capsys, str(f), "--json")

    def refuse(x):
        raise AssertionError(f"non-JSON constant {x}")
    data = json.loads(out.out, parse_constant=refuse)
    assert code == 1 and data["valid"] is False
    assert data["costs"]["qDist"] == "inf"  # Σ|Δq| overflows
    qv = [x for x in data["violations"] if x["constraint"] == "joint.q"]
    assert qv[0]["sample"] == 5 and qv[0]["joint"] == 0 and qv[0]["value"] == 1e308


def test_under_reported_accelerations_do_not_lower_the_cost(ptp3):
    """Costs read the judged motion, not the file's ddq: a file that keeps q, dq of robodesign's PTP_3 solution
    but reports ddq = 0, ddq/2, or per sample the ddq (of 0, ±ddq/2, ddq, 2·ddq) that makes |τ·dq| smallest,
    got lower effort, mechEnergy and Liu2 before (measured: effort 300.92 against 302.12 with ddq = 0) while
    staying VALID. Now every cost equals the honest file's (the motion is the same)."""
    from robodesign.model.cell import solution_robot
    task, ms, sol = ptp3
    tr = sol.trajectory
    honest = check(task, sol, ms)
    assert honest.valid
    robot = solution_robot(task, sol, ms)
    lams = [0.0, -0.5, 0.5, 1.0, 2.0]
    power = np.array([np.abs(np.einsum("ij,ij->i", robot.drivetrain_torques(tr.q, tr.dq, lam * tr.ddq), tr.dq))
                      for lam in lams])
    cheapest = np.array(lams)[np.argmin(power, axis=0)][:, None] * tr.ddq
    # the cheapest ddq's file torques give a lower mechEnergy than the honest ones (what a cheat gains)
    file_energy = float(np.sum(power.min(axis=0)[:-1] * np.diff(tr.t)))
    assert file_energy < 0.99 * honest.costs["mechEnergy"]
    for name, ddq in (("zero", 0 * tr.ddq), ("half", 0.5 * tr.ddq), ("cheapest", cheapest)):
        cheat = sol.with_(trajectory=SolutionTrajectory(tr.t, tr.q, tr.dq, ddq, dict(tr.goal2time)))
        v = check(task, cheat, ms)
        assert v.valid, (name, [str(x) for x in v.violations])
        for term in ("mechEnergy", "linkMechEnergy", "effort", "Liu2"):
            assert v.costs[term] == pytest.approx(honest.costs[term], rel=1e-9), (name, term)
    # the honest file's costs are those of its own samples (ddq_k is the motion's acceleration after sample k)
    tau = robot.drivetrain_torques(tr.q, tr.dq, tr.ddq)
    assert honest.costs["effort"] == pytest.approx(float(np.sum(np.abs(tau)) * (tr.t[1] - tr.t[0])), rel=1e-9)
    assert honest.costs["mechEnergy"] == pytest.approx(float(np.sum(power[lams.index(1.0)][:-1] * np.diff(tr.t))),
                                                       rel=1e-9)
    assert honest.costs["Liu2"] == pytest.approx(honest.costs["mechEnergy"] + 0.2 * tr.t[-1], rel=1e-12)

