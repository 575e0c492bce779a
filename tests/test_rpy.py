"""One roll-pitch-yaw convention (issue 23): core.spatial's rpy_to_matrix / matrix_to_rpy, used by the tolerance
projections, the URDF writer and the viewer; round trips on random rotations and at gimbal lock."""
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from robodesign.core import spatial
from robodesign.core.spatial import matrix_to_rpy, rot_x, rot_y, rot_z, rpy_to_matrix
from robodesign.formats import tolerance, urdf_export
from robodesign.viewer import html


def _random_rotation(rng):
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_rpy_is_rz_ry_rx_and_round_trips_random_rotations():
    rng = np.random.default_rng(0)
    r, p, y = 0.3, -0.7, 2.9
    assert np.allclose(rpy_to_matrix(r, p, y), rot_z(y) @ rot_y(p) @ rot_x(r), atol=1e-15)
    assert np.allclose(matrix_to_rpy(rpy_to_matrix(r, p, y)), (r, p, y), atol=1e-14)
    for _ in range(500):
        R = _random_rotation(rng)
        rpy = matrix_to_rpy(R)
        assert -math.pi / 2 <= rpy[1] <= math.pi / 2
        assert np.allclose(rpy_to_matrix(*rpy), R, atol=1e-12)


@pytest.mark.parametrize("pitch", [math.pi / 2, -math.pi / 2])
@pytest.mark.parametrize("roll,yaw", [(0.4, 1.1), (-2.0, 0.0), (3.0, -3.0)])
def test_gimbal_lock_puts_the_angle_in_yaw(pitch, roll, yaw):
    """At pitch ±π/2 only roll ∓ yaw is defined: roll is 0 and yaw carries it, and the matrix is reproduced."""
    R = rpy_to_matrix(roll, pitch, yaw)
    r, p, y = matrix_to_rpy(R)
    assert r == 0.0 and p == pytest.approx(pitch, abs=1e-12)
    assert np.allclose(rpy_to_matrix(r, p, y), R, atol=1e-12)
    # the angle kept: yaw - roll at +π/2 (R depends on y - r), yaw + roll at −π/2
    kept = yaw - roll if pitch > 0 else yaw + roll
    assert math.cos(y - kept) == pytest.approx(1.0, abs=1e-12)


def test_every_user_reads_the_one_convention():
    """The tolerance projections, the URDF writer and the viewer's pose text all go through core.spatial."""
    assert tolerance.rotation_to_rpy is spatial.matrix_to_rpy and tolerance.rpy_matrix is spatial.rpy_to_matrix
    assert not hasattr(urdf_export, "_matrix_to_rpy")
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(0.0, math.pi / 2, 0.5)  # gimbal lock
    el = urdf_export._origin(ET.Element("joint"), T)
    rpy = [float(v) for v in el.get("rpy").split()]
    assert rpy[0] == 0.0 and np.allclose(rpy_to_matrix(*rpy), T[:3, :3], atol=1e-12)
    assert "rpy [0°, 90°, 28.65°]" in html._fmt_pose(T)
