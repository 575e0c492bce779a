"""What a trajectory *does* on a robot in its cell: the quantities the judge, the solver and the viewer read.

:class:`TrajectoryQuantities` wraps one sampled trajectory (``t``, ``q``, ``dq``, ``ddq`` and the goal
times) of one robot (built by :mod:`robodesign.model.cell`) in one task. Every quantity is a property computed on
first use and cached (as in Timor's ``Trajectory``), so a check that never needs torques never runs
inverse dynamics:

* :attr:`~TrajectoryQuantities.tcp_poses` (N, 4, 4) and :attr:`~TrajectoryQuantities.tcp_twists` (N, 6):
  world TCP pose and world-aligned TCP twist ``[v; ω]`` at every sample;
* :attr:`~TrajectoryQuantities.goal_windows`: for each goal the samples ``(k0, k1)`` it spans, as the goal's
  ``time_window`` says (``pause``/``follow``: [t_g − duration, t_g]; ``leave``: [t_g, t_g + duration];
  ``at``/``reach``/``returnTo``: the sample at t_g). A goal without a window (no goal time, no unique sample
  at it, or a window outside the trajectory) is absent;
* :attr:`~TrajectoryQuantities.external_wrenches` (N, 6): the world wrench ``[f; τ]`` a goal applies at the
  TCP during its window (a follow goal's; the first such goal wins where windows overlap), zero elsewhere;
* :attr:`~TrajectoryQuantities.torques` and :attr:`~TrajectoryQuantities.link_torques` (N, dof): drivetrain
  and link-side torques (:meth:`Robot.drivetrain_torques <robodesign.model.robot.Robot.drivetrain_torques>`)
  under those wrenches.

* :attr:`~TrajectoryQuantities.motion`: the motion the samples describe between them
  (:mod:`robodesign.judge.motion`: least-acceleration arcs through q and the witness velocities), what the
  checker judges limits and collisions on; :attr:`~TrajectoryQuantities.motion_failures`: per joint the first
  step through which no motion within the acceleration limit passes; :attr:`~TrajectoryQuantities.motion_accelerations`
  and the torques on the motion (:attr:`~TrajectoryQuantities.motion_drivetrain_torques`, ``motion_link_torques``),
  what the costs read;
* :attr:`~TrajectoryQuantities.steps`: the former one-motion residuals (:class:`StepResiduals`, a diagnostic).

Timed follow poses read q interpolated linearly between samples (:meth:`~TrajectoryQuantities.q_at`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Dict, Optional, Tuple

import numpy as np
import pinocchio as pin

from robodesign.formats.solution import Solution
from robodesign.formats.task_spec import Goal, JointLimitsConstraint, Task
from robodesign.judge.motion import StepMotion, judge_kernels, witness_velocities
from robodesign.model.robot import Robot

TIME_ATOL = 1e-8  # goal times match a sample by numpy.isclose with these tolerances (the reference's rule)
TIME_RTOL = 1e-5


# q must be the integral of dq, and dq of ddq, over every step (docs/checker.md, "One motion"). With h the
# step and A a joint's largest acceleration in the file (max |ddq| and max |Δdq|/h over the trajectory):
#   |Δq − h·(dq_k + dq_k+1)/2| ≤ Q_RULE_FACTOR·A·h²             (trapezoid rule for q)
#   |Δdq − h·(ddq_k + ddq_k+1)/2| ≤ h·|ddq_k+1 − ddq_k|/2 + DQ_RULE_FACTOR·A·h
# The exact motion of samples with |q̈| ≤ A is within A·h²/4 of the first rule; robodesign's solvers write
# samples that meet both rules to rounding (ddq_k is the acceleration over [t_k, t_k+1]); the reference's
# numpy.gradient-filled trapezoids (Trajectory.from_mstraj) reach 0.50·A·h² and 0.25·A·h (worst over random
# via points, step sizes and blend times, experiments/consistency_tolerances.py). The factors keep 20 % over.
Q_RULE_FACTOR = 0.6
DQ_RULE_FACTOR = 0.3
RULE_ATOL = 1e-9  # absolute slack of both rules (rounding) [rad, m, rad/s, m/s]
RULE_RTOL = 1e-9  # relative slack (of |Δq| resp. |Δdq|)


@dataclass(frozen=True)
class StepResiduals:
    """Per step k (samples k → k+1) and joint: how far the samples are from describing one motion.

    ``q``/``dq``: residual of the q rule and of the dq rule (module constants), ``q_tol``/``dq_tol``: what
    each may be, of which ``dq_hull`` = h·|ddq_k+1 − ddq_k|/2 is exact (ddq_k may be the acceleration before,
    after or around sample k); arrays (N−1, dof). ``mean_velocity`` = Δq/h and ``mean_acceleration`` = Δdq/h: the
    velocity and acceleration of the motion between the samples under the linear interpolation of q and dq.
    """
    q: np.ndarray
    q_tol: np.ndarray
    dq: np.ndarray
    dq_tol: np.ndarray
    dq_hull: np.ndarray
    mean_velocity: np.ndarray
    mean_acceleration: np.ndarray

    @property
    def worst_ratio(self) -> Tuple[float, float]:
        """The largest share of the slack a step uses, q rule and dq rule: |r_q| / q_tol and
        (|r_dq| − dq_hull) / (dq_tol − dq_hull) (≤ 1: the samples are one motion; ~0: the rules hold exactly)."""
        return (float(np.max(np.abs(self.q) / self.q_tol, initial=0.0)),
                float(np.max((np.abs(self.dq) - self.dq_hull) / (self.dq_tol - self.dq_hull), initial=0.0)))


def step_residuals(t, q, dq, ddq) -> StepResiduals:
    """The :class:`StepResiduals` of samples ``t`` (N,), ``q``, ``dq``, ``ddq`` (N, dof)."""
    t, q, dq, ddq = (np.asarray(x, dtype=float) for x in (t, q, dq, ddq))
    h = np.diff(t)[:, None]
    d_q, d_dq = np.diff(q, axis=0), np.diff(dq, axis=0)
    mean_v, mean_a = d_q / h, d_dq / h
    A = np.max(np.abs(np.concatenate([ddq, mean_a])), axis=0, initial=0.0)  # per joint
    r_q = d_q - h * (dq[1:] + dq[:-1]) / 2
    r_dq = d_dq - h * (ddq[1:] + ddq[:-1]) / 2
    q_tol = Q_RULE_FACTOR * A * h ** 2 + RULE_ATOL + RULE_RTOL * np.abs(d_q)
    hull = h * np.abs(np.diff(ddq, axis=0)) / 2
    dq_tol = hull + DQ_RULE_FACTOR * A * h + RULE_ATOL + RULE_RTOL * np.abs(d_dq)
    return StepResiduals(r_q, q_tol, r_dq, dq_tol, hull, mean_v, mean_a)


_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _chain_axes(robot: Robot) -> Optional[list]:
    """(joint id, velocity index, prismatic, unit axis in the joint's frame) of every joint from the world to the
    TCP, or None when one is not a one-axis revolute or prismatic joint."""
    out = []
    for j in robot.tcp_chain():
        jm = robot.model.joints[j]
        name = jm.shortname()
        if name[:11] in ("JointModelR", "JointModelP") and name[11:] in _AXES:
            out.append((j, int(jm.idx_v), name[10] == "P", np.array(_AXES[name[11:]])))
        elif name in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
            a = np.asarray(jm.extract().axis, dtype=float)
            out.append((j, int(jm.idx_v), "Prismatic" in name, a / np.linalg.norm(a)))
        else:
            return None
    return out


def _world_axis(J: np.ndarray, j: int, ax: np.ndarray) -> list:
    """The components (3 arrays (N,)) of ``J[:, j, :3, :3] @ ax``, joint j's unit axis ``ax`` in world axes at every
    sample. Along a coordinate axis (ax = ±e_c) that is ±(column c of the rotations): the product's other terms are
    R·0 = ±0, so its sum is ±R_ic to the sign of a zero, which no sum of the twists keeps (they start at +0) —
    unless a rotation entry is no finite number (R·0 is NaN then: the product as written)."""
    R = J[:, j, :3, :3]
    c = np.flatnonzero(ax)
    if len(c) == 1 and abs(ax[c[0]]) == 1.0 and np.isfinite(R).all():
        return [R[:, i, c[0]] * ax[c[0]] for i in range(3)]
    z = R @ ax
    return [np.ascontiguousarray(z[:, i]) for i in range(3)]


def _twists_compiled(J: np.ndarray, T: np.ndarray, dq: np.ndarray, axes: list) -> Optional[np.ndarray]:
    """:attr:`TrajectoryQuantities.tcp_twists` by the compiled kernel (the numpy path's operations per sample: the
    same numbers, a NaN's sign bit aside, which no reader sees) from the joint poses J, the TCP poses T, the
    velocities and :func:`_chain_axes`; None without the kernel, when a joint of the chain is not along ±(a
    coordinate axis) or a rotation entry is no finite number (:func:`_world_axis` takes the matrix product then)."""
    kernel = judge_kernels()
    cols = [np.flatnonzero(ax) for *_, ax in axes]
    if kernel is None or any(len(c) != 1 or abs(ax[c[0]]) != 1.0 for c, (*_, ax) in zip(cols, axes)):
        return None
    out = kernel.tcp_twists(np.ascontiguousarray(J, dtype=float), np.ascontiguousarray(T, dtype=float),
                            np.ascontiguousarray(dq[:, [iv for _, iv, _, _ in axes]], dtype=float),
                            np.array([j for j, *_ in axes], dtype=np.int64),
                            np.array([pr for _, _, pr, _ in axes], dtype=np.bool_),
                            np.array([c[0] for c in cols], dtype=np.int64),
                            np.array([ax[c[0]] for c, (*_, ax) in zip(cols, axes)], dtype=float))
    return out if len(out) == len(J) else None


def find_time_index(t: np.ndarray, value: float) -> Optional[int]:
    """The unique sample at ``value`` (numpy.isclose rule of the reference), else None. numpy.isclose's own test
    written out for a float ``value`` (the same result, without its argument checks)."""
    v = float(value)
    with np.errstate(invalid="ignore"):
        close = np.nonzero((np.abs(t - v) <= TIME_ATOL + TIME_RTOL * abs(v)) & math.isfinite(v) | (t == v))[0]
    return int(close[0]) if len(close) == 1 else None


class TrajectoryQuantities:
    """Lazily computed quantities of one trajectory of ``robot`` in ``task`` (see the module docstring).

    ``task`` may be None (no goals: no windows, no external wrenches). Arrays are read-only views of the
    inputs; do not change them while the object is in use.
    """

    def __init__(self, robot: Robot, t, q, dq, ddq, task: Optional[Task] = None,
                 goal2time: Optional[Dict[str, float]] = None):
        self.robot, self.task = robot, task
        self.t = np.asarray(t, dtype=float)
        self.q, self.dq, self.ddq = (np.asarray(x, dtype=float) for x in (q, dq, ddq))
        self.goal2time = dict(goal2time or {})
        self.judge_cache: Dict[Any, Any] = {}  # the checker's results shared between rules (judge.checker)

    @classmethod
    def from_solution(cls, robot: Robot, solution: Solution, task: Optional[Task] = None) -> "TrajectoryQuantities":
        tr = solution.trajectory
        return cls(robot, tr.t, tr.q, tr.dq, tr.ddq, task, tr.goal2time)

    @property
    def n(self) -> int:
        return len(self.t)

    @cached_property
    def acceleration_bound(self) -> np.ndarray:
        """(dof,) the acceleration the judged motion may use per joint: the joint's limit when the task limits
        ddq (a ``joint`` constraint with ddq), else the largest the file reports (max |ddq| and |Δdq|/h)."""
        limited = self.task is not None and any(isinstance(c, JointLimitsConstraint) and "ddq" in c.parts
                                                for c in self.task.constraints)
        if limited:
            return np.asarray(self.robot.ddq_max, dtype=float)
        if self.n < 2:
            return np.max(np.abs(self.ddq), axis=0, initial=0.0)
        mean_a = np.diff(self.dq, axis=0) / np.diff(self.t)[:, None]
        return np.max(np.abs(np.vstack([self.ddq, mean_a])), axis=0)

    @cached_property
    def _witness(self):
        if self.n < 2:
            return self.dq.copy(), None
        A = self.acceleration_bound
        finite = np.isfinite(A)
        A = np.where(finite, A, 0.0)
        h = np.diff(self.t)
        h_adj = np.maximum(np.concatenate([h[:1], h]), np.concatenate([h, h[-1:]]))  # longer neighbouring step
        v, fail = witness_velocities(self.t, self.q, self.dq, A, A[None, :] * h_adj[:, None] / 2)
        v[:, ~finite] = self.dq[:, ~finite]  # no acceleration bound: the file's velocities as they are
        if fail is not None:
            fail = np.where(finite, fail, -1)
            fail = fail if np.any(fail >= 0) else None
        return v, fail

    @property
    def velocities(self) -> np.ndarray:
        """(N, dof) the judged motion's velocity at every sample: the file's dq moved by at most the velocity
        slack (A·h/2; none where dq = 0) so that a motion within the acceleration limit passes through
        (:func:`robodesign.judge.motion.witness_velocities`)."""
        return self._witness[0]

    @property
    def motion_failures(self) -> Optional[np.ndarray]:
        """Per joint the first step k (samples k → k+1) through which no motion within the joint's acceleration
        limit passes (−1: none), or None when every joint has one."""
        return self._witness[1]

    @cached_property
    def motion(self) -> StepMotion:
        """The motion between the samples (:class:`robodesign.judge.motion.StepMotion` through q and
        :attr:`velocities`)."""
        return StepMotion.through(self.t, self.q, self.velocities)

    @cached_property
    def one_sided_accelerations(self) -> Tuple[np.ndarray, np.ndarray]:
        """(N, dof) the motion's acceleration just before and just after every sample (the first sample's
        'before' and the last one's 'after' repeat the other side)."""
        m = self.motion
        if self.n < 2:
            return self.ddq.copy(), self.ddq.copy()
        hb = np.broadcast_to(m.h, m.tau.shape)
        after = np.where(m.tau > 0, m.a1, m.a2)  # the step's first arc unless it has zero length
        before = np.where(m.tau < hb, m.a2, m.a1)
        return np.vstack([after[:1], before]), np.vstack([after, before[-1:]])

    @cached_property
    def _motion_link_sides(self) -> Tuple[np.ndarray, np.ndarray]:
        """Link-side torques at every sample with the motion's acceleration just before and just after it (one
        pass of RNEA per row; a row whose two accelerations agree is computed once)."""
        W = self.external_wrenches
        wr = W if np.any(W) else None
        before, after = self.one_sided_accelerations
        la = self._rnea(self.q, self.velocities, after, wr)
        lb = la.copy()
        differ = np.any(before != after, axis=1)
        if np.any(differ):
            lb[differ] = self._rnea(self.q[differ], self.velocities[differ], before[differ],
                                                 None if wr is None else wr[differ])
        return lb, la

    @cached_property
    def motion_torques(self) -> Tuple[np.ndarray, np.ndarray]:
        """Drivetrain torques at every sample with the motion's acceleration just before and just after it
        (torque is affine in q̈ at fixed q, q̇: these two and the file's ddq bound it at the sample)."""
        before, after = self.one_sided_accelerations
        lb, la = self._motion_link_sides
        return (self.robot.drivetrain_torques(self.q, self.velocities, before, link_torques=lb),
                self.robot.drivetrain_torques(self.q, self.velocities, after, link_torques=la))

    @cached_property
    def motion_accelerations(self) -> np.ndarray:
        """(N, dof) the judged motion's acceleration *at* every sample, what the costs read: the acceleration
        just after the sample (over the step it starts; robodesign's solvers write exactly this as ddq), at the
        last sample 0 where the motion ends at rest (it stays there) and the one just before it elsewhere. Not
        the file's ddq: a file cannot lower an acceleration-dependent cost by under-reporting ddq."""
        before, after = self.one_sided_accelerations
        a = after.copy()
        if self.n >= 2:
            a[-1] = np.where(self.velocities[-1] == 0, 0.0, before[-1])
        return a

    @cached_property
    def motion_link_torques(self) -> np.ndarray:
        """(N, dof) link-side torques on the judged motion (q, :attr:`velocities`, :attr:`motion_accelerations`)
        under :attr:`external_wrenches`: what linkMechEnergy reads. Rows whose acceleration is the one just after
        (or just before) the sample are those of :attr:`motion_torques`' RNEA pass."""
        W = self.external_wrenches
        a = self.motion_accelerations
        before, after = self.one_sided_accelerations
        lb, la = self._motion_link_sides
        out = la.copy()
        not_after = np.any(a != after, axis=1)
        use_before = not_after & np.all(a == before, axis=1)
        out[use_before] = lb[use_before]
        rest = not_after & ~use_before
        if np.any(rest):
            out[rest] = self._rnea(self.q[rest], self.velocities[rest], a[rest],
                                                W[rest] if np.any(W) else None)
        return out

    @cached_property
    def motion_drivetrain_torques(self) -> np.ndarray:
        """(N, dof) drivetrain torques on the judged motion: what mechEnergy and effort read."""
        return self.robot.drivetrain_torques(self.q, self.velocities, self.motion_accelerations,
                                             link_torques=self.motion_link_torques)

    @cached_property
    def steps(self) -> StepResiduals:
        """Consistency of q, dq, ddq over every step (:func:`step_residuals`)."""
        return step_residuals(self.t, self.q, self.dq, self.ddq)

    # -- kinematics ---------------------------------------------------------------------------------
    @cached_property
    def tcp_poses(self) -> np.ndarray:
        """(N, 4, 4) world pose of the TCP at every sample (:meth:`Robot.fk_batch
        <robodesign.model.robot.Robot.fk_batch>`: one vectorised pass over the samples)."""
        if self.n == 0:
            return np.empty((0, 4, 4))
        return self.robot.fk_batch(self.q)

    @cached_property
    def joint_poses(self) -> Optional[np.ndarray]:
        """(N, njoints, 4, 4) :meth:`Robot.joint_poses_batch <robodesign.model.robot.Robot.joint_poses_batch>` of
        q (None: a joint type batched FK does not model): what :attr:`tcp_twists` and the judge's sweep read."""
        try:
            return self.robot.joint_poses_batch(self.q)
        except NotImplementedError:
            return None

    @cached_property
    def tcp_twists(self) -> np.ndarray:
        """(N, 6) TCP twist ``[v; ω]`` in world-aligned axes at the TCP, at every sample: Σ_j over the TCP's chain
        of ω_j = a_j·q̇_j and v_j = a_j × (p_TCP − o_j)·q̇_j (revolute; a_j·q̇_j prismatic), world axes a_j and
        origins o_j from :meth:`Robot.joint_poses_batch <robodesign.model.robot.Robot.joint_poses_batch>` (one
        pass over the samples; pinocchio per sample for a joint type it does not model)."""
        r = self.robot
        axes = _chain_axes(r)
        if axes is None or self.n == 0:
            return self._tcp_twists_per_sample()
        J = self.joint_poses
        if J is None:
            J = r.joint_poses_batch(self.q)
        fast = _twists_compiled(J, self.tcp_poses, self.dq, axes)
        return fast if fast is not None else self._tcp_twists_numpy(J, axes)

    def _tcp_twists_numpy(self, J: np.ndarray, axes: list) -> np.ndarray:
        """:attr:`tcp_twists` by numpy passes over the samples (J: the joint poses, ``axes``: :func:`_chain_axes`)."""
        p = [np.ascontiguousarray(self.tcp_poses[:, i, 3]) for i in range(3)]
        v, w = [np.zeros(self.n) for _ in range(3)], [np.zeros(self.n) for _ in range(3)]
        for j, iv, prismatic, ax in axes:
            z = _world_axis(J, j, ax)
            qd = np.ascontiguousarray(self.dq[:, iv])
            if prismatic:
                for i in range(3):
                    v[i] += z[i] * qd
                continue
            for i in range(3):
                w[i] += z[i] * qd
            b = [p[i] - J[:, j, i, 3] for i in range(3)]
            for i in range(3):  # numpy.cross(z, b)[:, i], times q̇
                v[i] += (z[(i + 1) % 3] * b[(i + 2) % 3] - z[(i + 2) % 3] * b[(i + 1) % 3]) * qd
        return np.column_stack(v + w)

    def _tcp_twists_per_sample(self) -> np.ndarray:
        r = self.robot
        out = np.empty((self.n, 6))
        for k in range(self.n):
            pin.forwardKinematics(r.model, r.data, self.q[k], self.dq[k])
            pin.updateFramePlacements(r.model, r.data)
            out[k] = pin.getFrameVelocity(r.model, r.data, r.tcp_frame, pin.LOCAL_WORLD_ALIGNED).vector
        return out

    def q_at(self, time: float) -> np.ndarray:
        """q at any time (linear interpolation between samples, held constant outside)."""
        return np.array([np.interp(time, self.t, self.q[:, j]) for j in range(self.q.shape[1])])

    def tcp_at(self, time: float) -> np.ndarray:
        """TCP pose at any time (q interpolated linearly between samples)."""
        return self.robot.fk(self.q_at(time))

    # -- goals --------------------------------------------------------------------------------------
    def goal_sample(self, goal_id: str) -> Optional[int]:
        """The unique sample at the goal's time (None without a goal time or a unique sample)."""
        tg = self.goal2time.get(goal_id)
        return None if tg is None else find_time_index(self.t, tg)

    def sample_at(self, time: float) -> Optional[int]:
        """The unique sample at ``time`` (:func:`find_time_index`), else None."""
        return find_time_index(self.t, time)

    def goal_window(self, goal: Goal) -> Optional[Tuple[int, int]]:
        """Samples (k0, k1), inclusive, that ``goal`` spans (its :meth:`~Goal.time_window`), or None."""
        k = self.goal_sample(goal.id)
        return None if k is None else goal.time_window(self, k)

    @cached_property
    def goal_windows(self) -> Dict[str, Tuple[int, int]]:
        """goal id → its window (k0, k1); goals without a window are absent."""
        out = {}
        for g in (self.task.goals if self.task is not None else ()):
            w = self.goal_window(g)
            if w is not None:
                out[g.id] = w
        return out

    # -- dynamics -----------------------------------------------------------------------------------
    @cached_property
    def external_wrenches(self) -> np.ndarray:
        """(N, 6) world wrench ``[f; τ]`` at the TCP: a goal's :attr:`~Goal.external_wrench` (a follow goal's
        force and torque) during its window."""
        W = np.zeros((self.n, 6))
        taken = np.zeros(self.n, dtype=bool)
        for g in (self.task.goals if self.task is not None else ()):
            wrench = g.external_wrench if g.id in self.goal_windows else None
            if wrench is None or not np.any(wrench != 0):
                continue
            k0, k1 = self.goal_windows[g.id]
            rows = np.arange(k0, k1 + 1)
            rows = rows[~taken[rows]]
            W[rows] = wrench
            taken[rows] = True
        return W

    def _rnea(self, Q, V, A, W: Optional[np.ndarray]) -> np.ndarray:
        """:meth:`Robot.link_torques <robodesign.model.robot.Robot.link_torques>` of the rows (without a wrench:
        pinocchio's RNEA of every row in one call)."""
        return self.robot.link_torques(Q, V, A, W if W is not None and np.any(W) else None)

    @cached_property
    def link_torques(self) -> np.ndarray:
        """(N, dof) link-side torques (no motor inertia, no friction) under :attr:`external_wrenches`."""
        W = self.external_wrenches
        return self._rnea(self.q, self.dq, self.ddq, W if np.any(W) else None)

    @cached_property
    def torques(self) -> np.ndarray:
        """(N, dof) drivetrain torques under :attr:`external_wrenches` (what peakTorque limits)."""
        return self.robot.drivetrain_torques(self.q, self.dq, self.ddq, link_torques=self.link_torques)
