"""The built-in module sets: robodesign_heavy's limits are the cited UR10e figures, its masses and inertias are
consistent with its geometry, a stretched arm's gravity torque matches a hand computation, and one of its
designs holds a 1.3 m goal with full orientation below the base (assets/modules/robodesign_heavy/README.md)."""
from __future__ import annotations

import importlib.util
import json
import math

import numpy as np
import pytest
from conftest import ROOT

from robodesign.core.paths import builtin_module_sets
from robodesign.formats.module_io import load_module_set
from robodesign.formats.tolerance import ToleratedPose
from robodesign.model.robot import Robot

HEAVY = ROOT / "assets" / "modules" / "robodesign_heavy"
EXAMPLE_A = ("1", "21", "22", "7", "24", "11", "25", "26", "25", "16")  # README.md, example A
EXAMPLE_B = ("1", "21", "22", "8", "24", "12", "25", "26", "25", "16")  # README.md, example B
G = 9.81


@pytest.fixture(scope="module")
def heavy():
    return load_module_set("robodesign_heavy")


def test_heavy_is_a_builtin_set_and_its_file_is_the_scripts_output(heavy):
    assert builtin_module_sets()["robodesign_heavy"] == HEAVY
    assert heavy.name == "robodesign_heavy" and len(heavy) == 23
    # the file is the script's output (deterministic), and the script's own check passes on it (schema,
    # masses, inertias, example orders, stretched-arm torques; few reach samples here)
    spec = importlib.util.spec_from_file_location("heavy_make_modules", HEAVY / "make_modules.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    built = script.build()
    assert json.dumps(built, indent=2, allow_nan=False) + "\n" == (HEAVY / "modules.json").read_text()
    script.check(built, verbose=False, samples=20)


def test_heavy_joint_limits_are_the_cited_ur10e_figures(heavy):
    # Universal Robots "Max. joint torques": size 4 330 Nm, size 3 150 Nm, size 2 56 Nm; UR10e speeds
    # 120°/s (base, shoulder: size 4) and 180°/s (the others); ±360°; no published acceleration limit
    cited = {"21": (330.0, 120.0), "22": (330.0, 120.0), "23": (150.0, 180.0), "24": (150.0, 180.0),
             "25": (56.0, 180.0), "26": (56.0, 180.0)}
    joints = {m.id: m.joints for m in heavy if m.dof}
    assert set(joints) == set(cited)
    for mid, (torque, deg_s) in cited.items():
        (j,) = joints[mid]
        assert j.limits.torque == torque
        assert j.limits.velocity == pytest.approx(math.radians(deg_s), abs=1e-9)
        assert j.limits.acceleration == math.inf
        assert (j.limits.lower, j.limits.upper) == pytest.approx((-2 * math.pi, 2 * math.pi), abs=1e-9)
        assert j.gear_ratio == 101.0


def test_heavy_link_mass_and_inertia_by_hand(heavy):
    # link_4_600: two 0.35 kg end flanges (r 0.075, 12 mm) and an aluminium tube r 0.075/0.070 over 0.576 m
    (b,) = heavy["6"].bodies
    lt = 0.6 - 2 * 0.012
    m_tube = 2700 * math.pi * (0.075 ** 2 - 0.070 ** 2) * lt
    assert m_tube == pytest.approx(3.5422, abs=1e-4)
    assert b.mass == pytest.approx(0.7 + m_tube, abs=1e-6)
    assert b.com[2] == pytest.approx(0.3, abs=1e-9)  # symmetric
    # about the CoM, across the tube: hollow cylinder + two discs at ±(0.3 − 0.006)
    i_tube = m_tube * (3 * (0.075 ** 2 + 0.070 ** 2) + lt ** 2) / 12
    i_disc = 0.35 * (3 * 0.075 ** 2 + 0.012 ** 2) / 12 + 0.35 * (0.3 - 0.006) ** 2
    assert b.inertia[0, 0] == pytest.approx(i_tube + 2 * i_disc, rel=1e-8)
    assert b.inertia[2, 2] == pytest.approx(m_tube * (0.075 ** 2 + 0.070 ** 2) / 2 + 2 * 0.35 * 0.075 ** 2 / 2, rel=1e-8)


@pytest.mark.parametrize("name", ["robodesign_arm", "robodesign_heavy"])
def test_every_inertia_is_physical_and_fits_its_geometry(name):
    """Positive, triangle inequality, and no larger than the mass placed at the body's farthest geometry point
    from its CoM (I ≤ m·ρ² about any axis through the CoM for mass within a ball of radius ρ)."""
    ms = load_module_set(name)
    for m in ms:
        assert 0.3 <= m.mass <= 10.0, (m.id, m.mass)
        for b in m.bodies:
            eig = np.linalg.eigvalsh(b.inertia)
            assert eig.min() > 0 and 2 * eig.max() <= eig.sum() + 1e-12, b.id
            rho = 0.0
            for g in b.collision:
                if g.kind == "mesh":
                    import trimesh
                    v = trimesh.load(g.file).vertices * np.asarray(g.scale)
                    pts = v @ g.pose[:3, :3].T + g.pose[:3, 3]
                    rho = max(rho, float(np.max(np.linalg.norm(pts - b.com, axis=1))))
                    continue
                half = {"cylinder": lambda s: math.hypot(s[0], s[1] / 2), "sphere": lambda s: s[0],
                        "box": lambda s: 0.5 * math.sqrt(s[0] ** 2 + s[1] ** 2 + s[2] ** 2)}[g.kind]
                rho = max(rho, float(np.linalg.norm(g.pose[:3, 3] - b.com)) + half(g.size))
            assert eig.max() <= b.mass * rho ** 2, (b.id, eig.max(), b.mass, rho)


@pytest.mark.parametrize("name", ["robodesign_arm", "robodesign_heavy"])
def test_joint_bodies_have_the_density_of_an_actuator(name):
    """Each joint body's mass over its collision cylinders' volume (housings with motor, gear and air inside):
    between 500 and 4,000 kg/m³ (aluminium is 2,700; the UR10e's size-4 shoulder link, 7.37 kg in about
    Ø 0.15 × 0.18 m, is about 2,300)."""
    for m in load_module_set(name):
        for b in m.bodies if m.dof else ():
            vol = sum(math.pi * g.size[0] ** 2 * g.size[1] for g in b.collision if g.kind == "cylinder")
            assert 500 <= b.mass / vol <= 4000, (m.id, b.id, b.mass / vol)


def test_examples_weigh_like_a_ur10e(heavy):
    for order in (EXAMPLE_A, EXAMPLE_B):
        assert sum(heavy[m].mass for m in order) == pytest.approx(33.5, rel=0.05)  # UR10e data sheet: 33.5 kg


def test_stretched_arm_gravity_torque_by_hand(heavy):
    """Example A held straight out (shoulder at 90°): the elbow joint carries every body beyond it, each
    weight times its lever along the arm; values from the module table (README.md)."""
    robot = Robot.from_order(heavy, EXAMPLE_A)
    tau = robot.gravity_torque([0.0, math.pi / 2, 0.0, 0.0, 0.0, 0.0])
    tube_32 = 2700 * math.pi * (0.045 ** 2 - 0.042 ** 2) * (0.3 - 0.010 - 0.008)
    levers = [  # (kg, m from the elbow axis); module starts 0.115, 0.415, 0.55, 0.73, 0.865 m beyond it
        (0.5, 0.09),                                                    # 24 output flange
        (0.22, 0.115 + 0.005), (tube_32, 0.115 + 0.010 + 0.141), (0.12, 0.115 + 0.296),  # link_32_300
        (1.7, 0.415 + 0.055), (0.3, 0.415 + 0.1225),                    # 25 wrist roll: housing, flange
        (0.3, 0.55 + 0.02), (1.4, 0.55 + 0.09), (0.3, 0.55 + 0.16),     # 26 wrist pitch: neck, drum, output
        (1.7, 0.73 + 0.055), (0.3, 0.73 + 0.1225),                      # 25 again
        (0.15, 0.865 + 0.0075), (0.3, 0.865 + 0.05), (0.04, 0.865 + 0.11),  # tool flange
    ]
    elbow = G * sum(m * r for m, r in levers)
    assert elbow == pytest.approx(44.750, abs=0.001)
    assert abs(tau[2]) == pytest.approx(elbow, rel=1e-6) and abs(tau[2]) < 150.0
    assert abs(tau[1]) == pytest.approx(124.03, abs=0.01) and abs(tau[1]) < 330.0
    assert max(abs(tau[0]), abs(tau[3]), abs(tau[5])) < 1e-6  # roll joints carry no moment


def test_a_design_holds_a_1_3_m_goal_below_the_base(heavy):
    """Example B reaches goals 1.3 m from its base, 0.3 m below the base plane, tool pointing down (±1 mm, 0.5°),
    in four directions, and holds each pose within every joint's torque limit; robodesign_arm's example A
    cannot reach them."""
    from robodesign.solvers.ik import solve_ik
    robot = Robot.from_order(heavy, EXAMPLE_B)
    arm = Robot.from_order(load_module_set("robodesign_arm"), ("1", "21", "22", "4", "22", "3", "23", "24", "23", "12"))
    o, R = arm.reach_bound()
    d = math.sqrt(1.3 ** 2 - 0.3 ** 2)
    for x, y in ((d, 0.0), (0.0, d), (-d, 0.0), (d / math.sqrt(2), -d / math.sqrt(2))):
        T = np.eye(4)
        T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # Rx(π): TCP z axis down
        T[:3, 3] = (x, y, -0.3)
        goal = ToleratedPose(T, ("x", "y", "z", "Theta_R"), ((-1e-3, 1e-3),) * 3 + ((0.0, math.radians(0.5)),))
        res = solve_ik(robot, goal, rng=0, max_restarts=300)
        assert res.success, (x, y, res.stats)
        assert goal.valid(robot.fk(res.q))
        assert np.all(np.abs(robot.gravity_torque(res.q)) <= robot.tau_max)
        assert np.linalg.norm(T[:3, 3] - o) > R


def test_heavy_readme_lists_every_module(heavy):
    text = (HEAVY / "README.md").read_text()
    for m in heavy:
        assert f"| {m.id} | {m.name} |" in text, m.id
    data = json.loads((HEAVY / "modules.json").read_text())
    assert data["ignore_collisions"] == "rigid_via_joint"
