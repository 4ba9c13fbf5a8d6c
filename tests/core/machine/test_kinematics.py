"""XYZ-3RPS kinematics: FK(IK) = identity, the parasitic motion against the leg-plane constraints,
home pose, left/right symmetry, agreement with the shared independent checker, and bad poses."""

import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import least_squares

from core.errors import MachineError
from core.machine.kinematics import (
    JOINT_ANGLES,
    axis_velocities,
    base_joints,
    forward_kinematics,
    inverse_kinematics,
    inverse_kinematics_rates,
    parasitic_centre,
    platform_joints,
    tilt_angles,
    zero_torsion_rotation,
)
from core.machine.model import load_machine, machine_to_toml

from ...conftest import CHECKS

MACHINE = load_machine()
SIGN = {"left": -1.0, "right": 1.0}  # the side's tool axis points roughly to SIGN * Z_W


def axis_w(side, tilt, azimuth):
    """(n, 3) unit tool axes in W tilted by tilt (rad) from SIGN * Z_W towards azimuth (rad)."""
    tilt, azimuth = np.broadcast_arrays(np.asarray(tilt, float), np.asarray(azimuth, float))
    return np.column_stack([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth),
                            SIGN[side] * np.cos(tilt)])


def random_poses(side, n, seed):
    rng = np.random.default_rng(seed)
    tips = np.column_stack([rng.uniform(40, 235, n), rng.uniform(-90, 90, n), rng.uniform(-60, 60, n)])
    tilt = np.radians(MACHINE.max_tilt_deg) * np.sqrt(rng.uniform(0, 1, n))
    return tips, axis_w(side, tilt, rng.uniform(-np.pi, np.pi, n))


def angle_between(u, v):
    return np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.einsum("ij,ij->i", u, v))


def assert_round_trip(side, tips, axes):
    values = inverse_kinematics(MACHINE, side, tips, axes)
    tips2, axes2 = forward_kinematics(MACHINE, side, values)
    assert np.linalg.norm(tips2 - tips, axis=1).max() < 1e-6
    assert angle_between(axes2, axes).max() < 1e-8
    np.testing.assert_allclose(np.linalg.norm(axes2, axis=1), 1.0, atol=1e-14)


# --- FK(IK(pose)) = pose ------------------------------------------------------------------------------

@settings(max_examples=300, deadline=None)
@given(side=st.sampled_from(["left", "right"]),
       x=st.floats(40, 235), y=st.floats(-90, 90), z=st.floats(-60, 60),
       tilt_deg=st.floats(0, MACHINE.max_tilt_deg), azimuth_deg=st.floats(-180, 180))
def test_fk_inverts_ik_hypothesis(side, x, y, z, tilt_deg, azimuth_deg):
    tips = np.array([[x, y, z]])
    assert_round_trip(side, tips, axis_w(side, [np.radians(tilt_deg)], [np.radians(azimuth_deg)]))


@pytest.mark.parametrize("side", ["left", "right"])
def test_fk_inverts_ik_batch(side):
    tips, axes = random_poses(side, 20000, seed=7)
    assert_round_trip(side, tips, axes)
    # tiny tilts (phi ill-defined) and exactly the limit
    t = np.array([0.0, 1e-12, 1e-9, 1e-6, np.radians(MACHINE.max_tilt_deg)])
    assert_round_trip(side, np.tile([100.0, 20.0, -5.0], (len(t), 1)), axis_w(side, t, 0.7))


def test_fk_converges_tightly():
    tips, axes = random_poses("left", 2000, seed=3)
    values = inverse_kinematics(MACHINE, "left", tips, axes)
    tips2, axes2 = forward_kinematics(MACHINE, "left", values)
    # round trip at rounding level, far inside the 1e-10 mm Newton tolerance's effect
    assert np.abs(tips2 - tips).max() < 1e-9
    assert np.abs(axes2 - axes).max() < 1e-12


def test_empty_input():
    assert inverse_kinematics(MACHINE, "left", np.zeros((0, 3)), np.zeros((0, 3))).shape == (0, 6)
    tips, axes = forward_kinematics(MACHINE, "right", np.zeros((0, 6)))
    assert tips.shape == axes.shape == (0, 3)


# --- the parasitic motion against the leg-plane constraints --------------------------------------------

def rz(a):
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])


def ry(a):
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1.0, 0], [-np.sin(a), 0, np.cos(a)]])


def solve_leg_planes(theta, phi, h, r_p):
    """Numerical (c_x, c_y, torsion) with R = Rz(phi) Ry(theta) Rz(torsion - phi) such that every platform
    joint P_i = c + R q_i lies in the vertical plane of leg i: -sin a_i P_ix + cos a_i P_iy = 0."""
    q = r_p * np.column_stack([np.cos(JOINT_ANGLES), np.sin(JOINT_ANGLES), np.zeros(3)])

    def residual(u):
        cx, cy, torsion = u
        r = rz(phi) @ ry(theta) @ rz(torsion - phi)
        p = np.array([cx, cy, h]) + q @ r.T
        return -np.sin(JOINT_ANGLES) * p[:, 0] + np.cos(JOINT_ANGLES) * p[:, 1]

    sol = least_squares(residual, x0=[0.0, 0.0, 0.1], xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.abs(sol.fun).max() < 1e-11
    return sol.x


@settings(max_examples=60, deadline=None)
@given(theta=st.floats(1e-3, np.radians(60)), phi=st.floats(-np.pi, np.pi), h=st.floats(100, 300),
       r_p=st.floats(20, 120))
def test_parasitic_centre_solves_the_leg_plane_constraints(theta, phi, h, r_p):
    cx, cy, torsion = solve_leg_planes(theta, phi, h, r_p)
    c = parasitic_centre(np.array([theta]), np.array([phi]), r_p, h)[0]
    assert abs(cx - c[0]) < 1e-9 and abs(cy - c[1]) < 1e-9 and c[2] == h
    assert abs(np.angle(np.exp(1j * torsion))) < 1e-9  # zero torsion: R = Rz(phi) Ry(theta) Rz(-phi)


def test_zero_torsion_rotation_is_the_spec_product():
    rng = np.random.default_rng(5)
    theta, phi = rng.uniform(0, 1, 50), rng.uniform(-np.pi, np.pi, 50)
    r = zero_torsion_rotation(theta, phi)
    for k in range(50):
        np.testing.assert_allclose(r[k], rz(phi[k]) @ ry(theta[k]) @ rz(-phi[k]), atol=1e-15)
    w = r[:, :, 2]
    t2, f2 = tilt_angles(w)
    np.testing.assert_allclose(t2, theta, atol=1e-15)
    np.testing.assert_allclose(np.angle(np.exp(1j * (f2 - phi))), 0, atol=1e-12)


def test_ik_is_the_spec_formulas():
    """IK against a literal transcription of SPEC.md section 9 in (theta, phi), one pose at a time."""
    m = MACHINE
    b, q = base_joints(m), platform_joints(m)
    l0 = np.hypot(m.base_radius - m.platform_radius, m.home_height)
    for side in ("left", "right"):
        tips, axes = random_poses(side, 30, seed=11)
        values = inverse_kinematics(m, side, tips, axes)
        t = m.side(side)
        for k in range(len(tips)):
            p = t.rotation.T @ (tips[k] - t.origin)
            w = t.rotation.T @ axes[k]
            theta, phi = np.arccos(w[2]), np.arctan2(w[1], w[0])
            r = rz(phi) @ ry(theta) @ rz(-phi)
            c = np.array([-(m.platform_radius / 2) * (1 - np.cos(theta)) * np.cos(2 * phi),
                          (m.platform_radius / 2) * (1 - np.cos(theta)) * np.sin(2 * phi), m.home_height])
            o = p + m.gauge_length * w - c
            d = np.linalg.norm(c + q @ r.T - b, axis=1) - l0
            np.testing.assert_allclose(values[k], np.concatenate([o, d]), atol=1e-9)


# --- home pose and symmetry -----------------------------------------------------------------------------

@pytest.mark.parametrize("side", ["left", "right"])
def test_ik_rates_are_the_derivative_of_ik(side):
    """The analytic Jacobian times the pose's rates equals a central difference of the inverse
    kinematics along the same motion (tip p + h dp, axis normalised w + h dw), over random poses up to
    the tilt limit and near zero tilt; an axis rate's part along the axis (which only changes its
    length) changes nothing."""
    tips, axes = random_poses(side, 400, 11)
    axes[:20] = axis_w(side, np.full(20, 1e-7), np.linspace(-3, 3, 20))  # (near zero tilt)
    axes[20:30] = axis_w(side, np.radians(MACHINE.max_tilt_deg) * 0.999, np.linspace(-3, 3, 10))
    rng = np.random.default_rng(3)
    dp = rng.normal(size=(400, 3)) * 0.02  # mm/ms
    dw = rng.normal(size=(400, 3)) * 0.002  # 1/ms
    dw -= axes * np.einsum("ij,ij->i", axes, dw)[:, None]  # (tangent: as a unit axis moves)
    values, rates = inverse_kinematics_rates(MACHINE, side, tips, axes, dp, dw)
    np.testing.assert_array_equal(values, inverse_kinematics(MACHINE, side, tips, axes))

    def at(h):
        w = axes + h * dw
        return inverse_kinematics(MACHINE, side, tips + h * dp, w / np.linalg.norm(w, axis=1)[:, None])

    h = 1e-3  # ms: the truncation error (h^2 / 6 times the third derivative) and the rounding stay below 1e-9
    fd = (at(h) - at(-h)) / (2 * h)
    np.testing.assert_allclose(rates, fd, rtol=0, atol=1e-9)
    assert np.abs(rates).max() > 1e-2  # (the motion is not negligible)
    along = inverse_kinematics_rates(MACHINE, side, tips, axes, dp, dw + 0.5 * axes)[1]
    np.testing.assert_allclose(along, rates, rtol=0, atol=1e-12)


@pytest.mark.parametrize("side", ["left", "right"])
def test_home_pose_gives_zero_legs(side):
    tips = np.array([[137.5, 0.0, 0.0], [40.0, -90.0, 60.0], [235.0, 90.0, -60.0]])
    values = inverse_kinematics(MACHINE, side, tips, axis_w(side, np.zeros(3), np.zeros(3)))
    np.testing.assert_allclose(values[:, 3:], 0.0, atol=1e-12)
    np.testing.assert_allclose(values[0, :3], 0.0, atol=1e-12)  # the toml's documented home: o = 0
    tips2, axes2 = forward_kinematics(MACHINE, side, np.zeros((1, 6)))
    np.testing.assert_allclose(tips2[0], [137.5, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(axes2[0], [0.0, 0.0, SIGN[side]], atol=1e-14)


def test_left_and_right_symmetry():
    """The default right machine is the left one turned 180 deg about X_W (both proper rotations), not its
    mirror image. Exact symmetries that follow:
    - turn: a left pose (x, y, z; i, j, k) and the right pose (x, -y, -z; i, -j, -k) give identical values;
    - mirror through Z_W = 0: a left pose and the right pose (x, y, -z; i, j, -k) give the left values with
      y negated and legs 2 and 3 swapped, (x, -y, z, d1, d3, d2): the mirror is the turn followed by the
      mirror y -> -y, which maps leg 1 (a = 0) onto itself and swaps legs 2 (120 deg) and 3 (240 deg)."""
    tips, axes = random_poses("left", 5000, seed=9)
    left = inverse_kinematics(MACHINE, "left", tips, axes)
    turn = np.array([1.0, -1.0, -1.0])
    right_turned = inverse_kinematics(MACHINE, "right", tips * turn, axes * turn)
    np.testing.assert_allclose(right_turned, left, atol=1e-9)
    mirror = np.array([1.0, 1.0, -1.0])
    right_mirrored = inverse_kinematics(MACHINE, "right", tips * mirror, axes * mirror)
    expected = left[:, [0, 1, 2, 3, 5, 4]] * [1, -1, 1, 1, 1, 1]
    np.testing.assert_allclose(right_mirrored, expected, atol=1e-9)
    assert np.abs(left[:, 4] - left[:, 5]).max() > 1.0  # the swap is not vacuous


# --- bad poses ------------------------------------------------------------------------------------------

def test_tilt_beyond_limit_names_the_samples():
    tips, axes = random_poses("left", 10, seed=2)
    axes[[3, 7]] = axis_w("left", np.radians([40.5, 55.0]), [0.3, 2.0])
    with pytest.raises(MachineError) as exc:
        inverse_kinematics(MACHINE, "left", tips, axes)
    msg = str(exc.value)
    assert "samples 3, 7" in msg and "55.000 deg" in msg and "max_tilt_deg = 40" in msg
    assert list(exc.value.samples) == [3, 7]
    # a right-side axis on the left machine is 180 deg off
    with pytest.raises(MachineError, match="samples 0"):
        inverse_kinematics(MACHINE, "left", tips[:1], axis_w("right", [0.0], [0.0]))


def test_non_unit_and_nan_axes_name_the_samples():
    tips, axes = random_poses("right", 6, seed=4)
    bad = axes.copy()
    bad[2] *= 1.01
    with pytest.raises(MachineError, match="not a unit vector.*samples 2"):
        inverse_kinematics(MACHINE, "right", tips, bad)
    bad = axes.copy()
    bad[4, 1] = np.nan
    with pytest.raises(MachineError, match="not a finite number at samples 4"):
        inverse_kinematics(MACHINE, "right", tips, bad)
    with pytest.raises(MachineError, match="side"):
        inverse_kinematics(MACHINE, "top", tips, axes)
    with pytest.raises(MachineError, match=r"\(n, 3\)"):
        inverse_kinematics(MACHINE, "left", tips[:, :2], axes)


def test_fk_refuses_impossible_legs():
    values = np.zeros((3, 6))
    values[1, 3:] = [-150.0, 0.0, 0.0]  # leg 1 shorter than the offset R_b - r_p: no platform
    with pytest.raises(MachineError, match="samples 1"):
        forward_kinematics(MACHINE, "left", values)


# --- velocities and the shared independent checker -----------------------------------------------------

def test_axis_velocities_are_the_derivative():
    t = np.linspace(0.0, 2000.0, 401)
    values = np.column_stack([np.sin(t / 300.0 + k) * (10 + k) for k in range(6)])
    exact = np.column_stack([np.cos(t / 300.0 + k) * (10 + k) / 300.0 for k in range(6)])
    v = axis_velocities(t, values)
    assert v.shape == (401, 6)
    assert np.abs(v - exact).max() < 1e-6 * np.abs(exact).max()
    two = axis_velocities(t[:2], values[:2])
    np.testing.assert_allclose(two, np.tile((values[1] - values[0]) / 5.0, (2, 1)))
    assert axis_velocities(t[:1], values[:1]).tolist() == [[0.0] * 6]
    with pytest.raises(MachineError, match="increasing"):
        axis_velocities(t[[0, 2, 1]], values[:3])


def smooth_motion(n=301, duration_ms=6000.0):
    """A symmetrical pair's tips and axes along one smooth pass across the chord (the right cutter
    mirrors the left through Z_W = 0 across a 6 mm thick blade)."""
    t = np.linspace(0.0, duration_ms, n)
    s = t / duration_ms
    tips = np.column_stack([120 + 60 * np.sin(np.pi * s), -85 + 170 * s, -3 - 20 * np.sin(2 * np.pi * s)])
    tilt = np.radians(35) * np.sin(np.pi * s) ** 2
    azimuth = 0.5 + 2.0 * s
    left_axes = axis_w("left", tilt, azimuth)
    mirror = np.array([1.0, 1.0, -1.0])
    return t, {"left": (tips, left_axes), "right": (tips * mirror, left_axes * mirror)}


def write_plan_tables(folder, t, poses):
    (folder / "machine.toml").write_text(machine_to_toml(MACHINE))
    cols = "x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3"
    for side, (tips, axes) in poses.items():
        values = inverse_kinematics(MACHINE, side, tips, axes)
        vel = axis_velocities(t, values)
        with open(folder / f"{side}_cl.csv", "w") as fh:
            fh.write("t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k\n")
            for k in range(len(t)):
                row = ",".join(f"{v:.9f}" for v in (*tips[k], *axes[k]))
                fh.write(f"{t[k]:.3f},1,internal,0,1,{row}\n")
        with open(folder / f"{side}_axes.csv", "w") as fh:
            fh.write("t_ms," + cols + "\n")
            for k in range(len(t)):
                fh.write(f"{t[k]:.3f}," + ",".join(f"{v:.9f}" for v in (*values[k], *vel[k])) + "\n")
    return folder


def run_check_axes(folder):
    script = CHECKS / "check_axes.py"
    if not script.is_file():
        pytest.skip("shared check_axes.py not present")
    return subprocess.run([sys.executable, str(script), str(folder)], capture_output=True, text=True,
                          timeout=120)


def test_shared_check_axes_accepts_our_tables(tmp_path):
    t, poses = smooth_motion()
    out = run_check_axes(write_plan_tables(tmp_path, t, poses))
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stdout.strip().splitlines()[-1].startswith("ok")


def test_shared_check_axes_rejects_swapped_legs(tmp_path):
    # the check above is not vacuous: legs 2 and 3 exchanged break its forward kinematics
    t, poses = smooth_motion()
    write_plan_tables(tmp_path, t, poses)
    path = tmp_path / "left_axes.csv"
    rows = [r.split(",") for r in path.read_text().splitlines()]
    for r in rows[1:]:  # data rows only (the header names the columns)
        r[5], r[6] = r[6], r[5]
    path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    out = run_check_axes(tmp_path)
    assert out.returncode == 1
    assert "left: forward kinematics misses the CL tip" in out.stdout
