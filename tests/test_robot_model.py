"""Robot models: FK, dynamics and collision against hand computations."""
import numpy as np
import pinocchio as pin
import pytest

from robodesign import Assembly, AssemblyError, Robot, load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.model.robot import Obstacle

from conftest import IMPROV, PRIMITIVES

G = 9.81


def u(theta):
    return np.array([-np.sin(theta), 0.0, np.cos(theta)])


def Ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def test_fk_of_toy_chain_matches_hand_computation(toy_set):
    r = Robot.from_order(toy_set, ["B", "J", "J", "E"])
    assert r.dof == 2
    assert r.mass == pytest.approx(1.0 + 2 * 2.0 + 0.5)
    for q1, q2 in [(0, 0), (0.3, -0.7), (1.2, 0.4), (-2.0, 2.5)]:
        T = r.fk([q1, q2])
        # joint 1 sits at z = 0.15; the TCP is 0.25 further along u(q1), then 0.3 along u(q1+q2)
        p = np.array([0, 0, 0.15]) + 0.25 * u(q1) + 0.3 * u(q1 + q2)
        np.testing.assert_allclose(T[:3, 3], p, atol=1e-12)
        np.testing.assert_allclose(T[:3, :3], Ry(-(q1 + q2)), atol=1e-12)


def test_gravity_and_drivetrain_torque_by_hand(toy_set):
    r = Robot.from_order(toy_set, ["B", "J", "J", "E"])
    q1, q2 = 0.4, -1.1
    # V = Σ m g z; link 1 CoM 0.1 along u(q1); link 2 CoM at 0.25 u(q1) + 0.1 u(q1+q2); eef CoM at
    # 0.25 u(q1) + 0.25 u(q1+q2) (flange 0.2 + CoM 0.05)
    dV1 = -G * (2.0 * 0.1 * np.sin(q1) + 2.0 * (0.25 * np.sin(q1) + 0.1 * np.sin(q1 + q2))
                + 0.5 * (0.25 * np.sin(q1) + 0.25 * np.sin(q1 + q2)))
    dV2 = -G * (2.0 * 0.1 * np.sin(q1 + q2) + 0.5 * 0.25 * np.sin(q1 + q2))
    np.testing.assert_allclose(r.gravity_torque([q1, q2]), [dV1, dV2], atol=1e-12)
    # drivetrain at rest with ddq: τ = g(q) + M ddq + k² I_m ddq (+ friction 0 at dq=0)
    ddq = np.array([1.0, -2.0])
    dq = np.zeros(2)
    M = pin.crba(r.model, r.data, np.array([q1, q2]))
    M = np.triu(M) + np.triu(M, 1).T  # includes armature
    tau = r.drivetrain_torques([q1, q2], dq, ddq)[0]
    np.testing.assert_allclose(tau, [dV1, dV2] + M @ ddq, atol=1e-10)
    assert r.model.armature == pytest.approx([100 ** 2 * 1e-5] * 2)
    # friction: viscous 3·dq + Coulomb 2·sin(atan(100 dq))
    dq = np.array([0.5, -0.01])
    tau_f = r.drivetrain_torques([q1, q2], dq, np.zeros(2))[0] - r.rnea([q1, q2], dq, np.zeros(2))
    np.testing.assert_allclose(tau_f, 3 * dq + 2 * np.sin(np.arctan(100 * dq)), atol=1e-12)
    # forward dynamics inverts the drivetrain torque
    dq = np.array([0.3, -0.2])
    np.testing.assert_allclose(r.forward_dynamics([q1, q2], dq, r.drivetrain_torques([q1, q2], dq, ddq)[0]), ddq,
                               atol=1e-9)


def test_jacobian_matches_finite_differences(toy_set):
    r = Robot.from_order(toy_set, ["B", "J", "J", "E"])
    q = np.array([0.2, 0.5])
    J = r.jacobian(q)
    eps = 1e-7
    for k in range(2):
        dqv = np.zeros(2)
        dqv[k] = eps
        dp = (r.fk(q + dqv)[:3, 3] - r.fk(q - dqv)[:3, 3]) / (2 * eps)
        np.testing.assert_allclose(J[:3, k], dp, atol=1e-7)
        np.testing.assert_allclose(J[3:, k], [0, -1, 0], atol=1e-12)


def test_base_pose_moves_everything(toy_set):
    r = Robot.from_order(toy_set, ["B", "J", "J", "E"])
    T0 = r.fk([0.3, 0.2])
    B = np.eye(4)
    B[:3, :3] = pin.rpy.rpyToMatrix(0.1, -0.2, 0.7)
    B[:3, 3] = [1.0, -2.0, 0.5]
    r.set_base_pose(B)
    np.testing.assert_allclose(r.fk([0.3, 0.2]), B @ T0, atol=1e-12)
    # gravity stays along world -z: torques change once the base is tilted
    r2 = Robot.from_order(toy_set, ["B", "J", "J", "E"], base_pose=B)
    np.testing.assert_allclose(r2.fk([0.3, 0.2]), B @ T0, atol=1e-12)


def test_self_collision_hit_and_miss(toy_set):
    r = Robot.from_order(toy_set, ["B", "J", "J", "J", "E"])
    # 3 revolute joints; folding joint 2 by π brings link 3 down into the base (not adjacent)
    assert not r.in_self_collision([0.0, 0.0, 0.0])
    assert r.in_self_collision([0.0, np.pi, 0.0])
    pairs = r.colliding_pairs([0.0, np.pi, 0.0])
    assert any("B." in a or "B." in b for a, b in pairs)
    # rigid_via_joint: no pair between rigid bodies or neighbours across one joint
    names = [o.name for o in r.geom_model.geometryObjects]
    for cp in r.geom_model.collisionPairs:
        ja = r.geom_model.geometryObjects[cp.first].parentJoint
        jb = r.geom_model.geometryObjects[cp.second].parentJoint
        assert ja != jb and r.model.parents[ja] != jb and r.model.parents[jb] != ja
    assert len(names) == r.n_collision_geometries == 1 + 2 * 3 + 1


def test_obstacle_collision_hit_and_miss_and_distance(toy_set):
    import coal
    r = Robot.from_order(toy_set, ["B", "J", "J", "E"])
    box = coal.Box(0.1, 0.1, 0.1)
    tcp = r.fk([0, 0])[:3, 3]  # (0, 0, 0.7)
    hit = Obstacle("hit", box, np.block([[np.eye(3), tcp[:, None]], [np.zeros((1, 3)), np.ones((1, 1))]]))
    r.set_obstacles([hit])
    assert r.in_collision([0, 0]) and r.collides_with_obstacles([0, 0])
    far = np.eye(4)
    far[:3, 3] = [1.0, 0, 0.7]
    r.set_obstacles([Obstacle("far", box, far)])
    assert not r.in_collision([0, 0])
    # box face at x = 0.95 spans z ∈ [0.65, 0.75]; the eef cylinder (r 0.02, z ∈ [0.6, 0.7]) is 0.93 away,
    # the top rim of link 2 (r 0.03 at z = 0.6) is closer: √(0.92² + 0.05²)
    d_self, d_obs = r.min_distances([0, 0])
    assert d_obs == pytest.approx(np.hypot(0.92, 0.05), abs=1e-6)
    # safety margin: 0.95 m margin makes the same configuration collide
    r.set_obstacles([Obstacle("far", box, far)], safety_margin=0.95)
    assert r.in_collision([0, 0])


@pytest.mark.parametrize("folder", [IMPROV, PRIMITIVES])
def test_reference_module_sets_load_and_random_assemblies_build(folder):
    ms = load_module_set(folder)
    assert len(ms) == {"IMPROV": 16, "geometric_primitive_modules": 10}[folder.name]
    rng = np.random.default_rng(1)
    for _ in range(15):
        order = random_serial_order(ms, rng, dof=6)
        r = Robot.from_order(ms, order)
        assert r.dof == 6
        assert r.mass == pytest.approx(sum(ms[m].mass for m in order))
        assert r.model.nq == 6 and np.isfinite(r.fk(r.random_configuration(rng))).all()
        assert r.n_collision_geometries >= len(order) - 1


@pytest.mark.parametrize("folder", [IMPROV, PRIMITIVES])
def test_random_serial_orders_keep_their_rules(folder):
    """Every order: a base first, an end effector last and nowhere else, exactly ``dof`` joint DoF, at most
    ``max_links_between`` links in a row, and it assembles; the same generator state gives the same order."""
    ms = load_module_set(folder)
    checked = 0
    for seed in range(6):
        for dof in (1, 3, 6, 7):
            for most in (0, 1, 2):
                rng = np.random.default_rng(seed)
                try:
                    order = random_serial_order(ms, rng, dof=dof, max_links_between=most, max_tries=300)
                except AssemblyError:
                    continue
                kinds = [ms[m].kind for m in order]
                assert kinds[0] == "base" and kinds[-1] == "eef" and "eef" not in kinds[1:-1]
                assert sum(ms[m].dof for m in order if ms[m].kind == "joint") == dof
                run = 0
                for k in kinds[1:-1]:
                    run = run + 1 if k == "link" else 0
                    assert run <= most
                Assembly.from_order(ms, order)
                assert random_serial_order(ms, np.random.default_rng(seed), dof=dof, max_links_between=most,
                                           max_tries=300) == order
                checked += 1
    assert checked >= 18   # (IMPROV has no 1- or 7-DoF chains, and needs links between some joints)


def test_improv_known_arm_values():
    ms = load_module_set(IMPROV)
    r = Robot.from_order(ms, ["1", "21", "4", "21", "23", "12"])
    assert r.dof == 6
    # masses straight from the module file (sum of body masses)
    assert r.mass == pytest.approx(2 * ms["21"].mass + ms["4"].mass + ms["23"].mass + ms["12"].mass)
    assert ms["21"].mass == pytest.approx(3.9)  # PB21: only its middle body has mass
    # the joint limits are copied 1:1
    assert r.q_upper[0] == pytest.approx(2.9671) and r.dq_max[0] == pytest.approx(1.2566)
    assert r.tau_max[0] == pytest.approx(75.504)
    # the IMPROV .wrl decompositions become several convex parts
    import coal
    shapes = [type(o.geometry).__name__ for o in r.geom_model.geometryObjects]
    assert any(s.startswith("Convex") for s in shapes)


def test_invalid_orders_say_which_pair_and_why():
    ms = load_module_set(IMPROV)
    with pytest.raises(AssemblyError, match=r"'12' \(L3\) → '21'.*do not connect"):
        Assembly.from_order(ms, ["1", "21", "12", "21"])
    with pytest.raises(AssemblyError, match="must have exactly one base connector"):
        Assembly.from_order(ms, ["21", "1"])
    with pytest.raises(AssemblyError, match="not in module set"):
        Assembly.from_order(ms, ["1", "31"])
    with pytest.raises(AssemblyError, match="types differ"):
        Assembly.from_order(ms, ["1", "21", "12", "4"])  # nothing mates with an eef flange
    a = Assembly.from_order(ms, ["1", "13"])
    assert a.connections == ((1, "13_proximal_connector", 0, "base_out"),)


def test_connector_rule():
    from robodesign.formats.module_spec import Connector
    E = np.eye(4)
    f = Connector("a", "b", E, "f", "t", (1.0,))
    m = Connector("c", "d", E, "m", "t", (1.0,))
    h = Connector("e", "f", E, "h", "t", (1.0,))
    assert f.mates_with(m)[0] and m.mates_with(f)[0] and h.mates_with(h)[0]
    assert not f.mates_with(f)[0] and "genders" in f.mates_with(f)[1]
    assert not h.mates_with(m)[0]
    assert "sizes differ" in f.mates_with(Connector("x", "y", E, "m", "t", (2.0,)))[1]
    # unlike the reference, [] does not match [x]
    assert not f.mates_with(Connector("x", "y", E, "m", "t", ()))[0]
    assert "types differ" in f.mates_with(Connector("x", "y", E, "m", "u", (1.0,)))[1]


def test_explicit_connection_graph_equals_serial_order():
    ms = load_module_set(IMPROV)
    order = ["1", "21", "4", "22", "5", "23", "12"]
    a = Assembly.from_order(ms, order)
    g = Assembly.from_graph(ms, order, a.connections, a.base)
    q = np.random.default_rng(0).uniform(-1, 1, 6)
    np.testing.assert_allclose(Robot(ms, a).fk(q), Robot(ms, g).fk(q), atol=1e-14)
    with pytest.raises(AssemblyError, match="already used"):
        Assembly.from_graph(ms, order, list(a.connections) + [(2, "4_proximal_connector", 0, "base_out")], a.base)
    with pytest.raises(AssemblyError, match="do not connect"):
        Assembly.from_graph(ms, ["1", "21"], [(1, "21_distal_connector", 0, "base_out")], (0, "base"))
    with pytest.raises(AssemblyError, match="not connected to the base"):
        Assembly.from_graph(ms, ["1", "21", "4"], [(1, "21_proximal_connector", 0, "base_out")], (0, "base"))


def test_mated_frames_have_aligned_x_and_antiparallel_z():
    ms = load_module_set(IMPROV)
    r = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    frames = r.fk_all(np.random.default_rng(3).uniform(-1, 1, 6))
    for a, ca, b, cb in r.assembly.connections:
        la, lb = r.instance_labels[a], r.instance_labels[b]
        Fa = next(v for k, v in frames.items() if k.startswith(la + ".") and k.endswith("." + ca))
        Fb = next(v for k, v in frames.items() if k.startswith(lb + ".") and k.endswith("." + cb))
        np.testing.assert_allclose(Fa[:3, 3], Fb[:3, 3], atol=1e-12)
        np.testing.assert_allclose(Fa[:3, 0], Fb[:3, 0], atol=1e-12)
        np.testing.assert_allclose(Fa[:3, 2], -Fb[:3, 2], atol=1e-12)


def test_frames_of_bodies_and_connectors_are_added_when_asked_for():
    """A new robot's model has the joints' frames and the TCP; add_frames (frame_id, fk_all) adds one frame per
    body and per connector, the same poses whether the base pose was set before or after, with a new data."""
    ms = load_module_set(IMPROV)
    order = ["1", "21", "4", "22", "5", "23", "12"]
    T = np.array([[0.0, -1, 0, 0.3], [1, 0, 0, -0.2], [0, 0, 1, 0.1], [0, 0, 0, 1]])
    early, late = Robot.from_order(ms, order, base_pose=T), Robot.from_order(ms, order)
    assert early.model.nframes == early.model.njoints + 1          # universe, one per joint, TCP
    q = np.random.default_rng(5).uniform(-1, 1, early.dof)
    tcp = early.fk(q)
    data = early.data
    early.add_frames()
    late.add_frames()
    late.set_base_pose(T)
    assert early.data is not data and len(early.data.oMf) == early.model.nframes
    bodies = sum(len(ms[m].bodies) for m in early.assembly.module_ids)
    connectors = sum(len(b.connectors) for m in early.assembly.module_ids for b in ms[m].bodies)
    assert early.model.nframes == early.model.njoints + 1 + bodies + connectors
    a, b = early.fk_all(q), late.fk_all(q)
    assert list(a) == list(b) and all(np.array_equal(a[k], b[k]) for k in a)
    assert np.array_equal(early.fk(q), tcp) and np.array_equal(a["TCP"], tcp)
    # a body frame is its joint's pose times the body's placement; the root body follows the base pose
    base_body = f"{early.instance_labels[0]}.{ms[order[0]].bodies[0].id}"
    assert np.allclose(a[base_body], T @ Robot.from_order(ms, order).fk_all(q)[base_body], atol=1e-14)
    assert early.add_frames() is early.model and early.model.nframes == late.model.nframes   # once


@pytest.mark.parametrize("mass", [0.0, 0.244, 0.333903, 1.0, 2.5, 2.844885, 49.0, 3.7])   # 1.0, 2.5: m·(1/m) = 1
def test_zero_inertias_of_deferred_frames_are_pinocchios(mass):
    """What adding k frames (with pinocchio's default: the frame's zero inertia appended) does to a joint's inertia,
    as robot._zero_inertias makes it without the frames: bit for bit, for masses whose m·(1/m) is not 1 too."""
    from robodesign.model import robot as robot_mod
    rng = np.random.default_rng(int(mass * 1000))
    for _ in range(50):
        ref = pin.Model()
        j = ref.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "j")
        if mass > 0:
            ref.appendBodyToJoint(j, pin.Inertia(mass, rng.normal(size=3) * 0.2, np.diag(rng.uniform(0.01, 0.1, 3))),
                                  pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3)))
        lean = pin.Model(ref)
        k = int(rng.integers(1, 5))
        for i in range(k):
            ref.addFrame(pin.Frame(f"f{i}", j, 0, pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3)),
                                   pin.FrameType.OP_FRAME))
        robot_mod._zero_inertias(lean, {j: k}, {j: mass}, j)
        Y, Z = ref.inertias[j], lean.inertias[j]
        assert Y.mass == Z.mass and np.array_equal(Y.lever, Z.lever) and np.array_equal(Y.inertia, Z.inertia)
