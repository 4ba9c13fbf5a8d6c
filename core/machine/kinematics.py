"""Kinematics of one XYZ-3RPS side: tool tip and axis in W <-> the six axes x, y, z, d1, d2, d3.

The model is SPEC.md section 9. The 3-RPS base frame is parallel to the machine frame M with origin
o = (x, y, z), which the XYZ stage moves. Base joints b_i = R_b (cos a_i, sin a_i, 0), platform joints
q_i = r_p (cos a_i, sin a_i, 0) in the platform frame, a_i = 0, 120, 240 degrees; the revolute joints
are tangent to the base circle, so leg i stays in the vertical plane through the z axis at angle a_i.
Those three plane constraints leave the platform with three degrees of freedom (theta, phi, h); they
fix the torsion to zero, R = Rz(phi) Ry(theta) Rz(-phi), and the platform centre to the parasitic
c = (-(r_p/2)(1 - cos t) cos 2f, (r_p/2)(1 - cos t) sin 2f, h). The redundancy between z and h is
resolved by h = h_0. The tool tip is p_M = o + c - e w with w = R e_z (tip -> spindle) and the table
values are d_i = |c + R q_i - b_i| - L_0.

``inverse_kinematics`` is the closed form. ``forward_kinematics`` does not use it: it solves the
mechanism itself (each platform joint on a circle of radius L_i about b_i in its leg plane, the three
joints an equilateral triangle of side sqrt(3) r_p) by Newton's method, and reads the platform centre
and tool axis off the triangle; so FK(IK(x)) = x also checks the parasitic-motion and torsion algebra.
"""

from __future__ import annotations

import numpy as np

from core.errors import MachineError
from core.machine.model import Machine

JOINT_ANGLES = np.radians([0.0, 120.0, 240.0])
AXIS_NORM_TOLERANCE = 1e-6  # |w| must be 1 to this
TILT_TOLERANCE = 1e-9  # rad beyond max_tilt_deg still accepted (rounding)
FK_TOLERANCE_MM = 1e-10
FK_MAX_ITERATIONS = 50
_COS_A = np.cos(JOINT_ANGLES)
_SIN_A = np.sin(JOINT_ANGLES)


def _samples(idx: np.ndarray, limit: int = 8) -> str:
    shown = ", ".join(str(int(i)) for i in idx[:limit])
    return shown + (f" (and {len(idx) - limit} more)" if len(idx) > limit else "")


def _fail(message: str, idx: np.ndarray) -> MachineError:
    err = MachineError(message)
    err.samples = idx  # type: ignore[attr-defined]  # sample indices, for the caller to add time/path
    return err


def _check_side(side: str) -> None:
    if side not in ("left", "right"):
        raise MachineError(f"unknown machine side {side!r}: use 'left' or 'right'")


def _as_rows(name: str, a: np.ndarray, width: int) -> np.ndarray:
    arr = np.asarray(a, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != width:
        raise MachineError(f"{name} must be an (n, {width}) array, got shape {arr.shape}")
    return arr


def base_joints(machine: Machine) -> np.ndarray:
    """b_i : (3, 3) float, mm, base frame; row i = R_b (cos a_i, sin a_i, 0)."""
    r = machine.base_radius
    return np.column_stack([r * _COS_A, r * _SIN_A, np.zeros(3)])


def platform_joints(machine: Machine) -> np.ndarray:
    """q_i : (3, 3) float, mm, platform frame; row i = r_p (cos a_i, sin a_i, 0)."""
    r = machine.platform_radius
    return np.column_stack([r * _COS_A, r * _SIN_A, np.zeros(3)])


def tilt_angles(axes_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """theta, phi : (n,) float, rad, of unit tool axes (n, 3) in M: w = (sin t cos f, sin t sin f, cos t).

    theta in [0, pi] (computed with arctan2, accurate near 0), phi in (-pi, pi] (0 where theta = 0).
    """
    s = np.hypot(axes_m[:, 0], axes_m[:, 1])
    return np.arctan2(s, axes_m[:, 2]), np.arctan2(axes_m[:, 1], axes_m[:, 0])


def zero_torsion_rotation(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """R = Rz(phi) Ry(theta) Rz(-phi) : (n, 3, 3) float for theta, phi : (n,) float, rad."""
    ct, st = np.cos(theta), np.sin(theta)
    cf, sf = np.cos(phi), np.sin(phi)
    vers = 2.0 * np.sin(0.5 * theta) ** 2  # 1 - cos(theta), without cancellation
    r = np.empty(np.shape(theta) + (3, 3))
    r[..., 0, 0] = 1.0 - vers * cf * cf
    r[..., 0, 1] = r[..., 1, 0] = -vers * cf * sf
    r[..., 1, 1] = 1.0 - vers * sf * sf
    r[..., 0, 2] = st * cf
    r[..., 1, 2] = st * sf
    r[..., 2, 0] = -st * cf
    r[..., 2, 1] = -st * sf
    r[..., 2, 2] = ct
    return r


def parasitic_centre(theta: np.ndarray, phi: np.ndarray, platform_radius: float,
                     height: np.ndarray | float) -> np.ndarray:
    """Platform centre c : (n, 3) float, mm, base frame, of the 3-RPS at tilt theta, azimuth phi.

    theta, phi : (n,) float, rad; platform_radius : float, mm (r_p); height : float or (n,), mm (h).
    c = (-(r_p/2)(1 - cos t) cos 2f, (r_p/2)(1 - cos t) sin 2f, h): the parasitic motion forced by the
    legs' planes (SPEC.md section 9).
    """
    theta = np.asarray(theta, dtype=float)
    phi = np.asarray(phi, dtype=float)
    k = platform_radius * np.sin(0.5 * theta) ** 2  # (r_p/2)(1 - cos t)
    return np.stack([-k * np.cos(2.0 * phi), k * np.sin(2.0 * phi),
                     np.broadcast_to(np.asarray(height, dtype=float), theta.shape)], axis=-1)


def inverse_kinematics(machine: Machine, side: str, tips_w: np.ndarray, axes_w: np.ndarray,
                       first_sample: int = 0) -> np.ndarray:
    """Axis values : (n, 6) float, mm, columns x, y, z, d1, d2, d3 of one side.

    tips_w : (n, 3) float, mm, tool tips in W; axes_w : (n, 3) float, unit tool axes (tip -> spindle) in W;
    side : 'left' or 'right'. Raises MachineError for a NaN or non-unit axis or a tilt beyond
    max_tilt_deg, naming the sample indices (also on the exception as ``samples``), counted from
    ``first_sample`` (a caller working through a column in blocks gives each block's first row).

    The zero-torsion rotation and the parasitic centre are evaluated in the axis components
    w = (a, b, c) in M rather than in (theta, phi): with a = sin t cos f, b = sin t sin f, c = cos t,
    (1 - cos t) cos^2 f = a^2 / (1 + c) and so on, the same values as ``zero_torsion_rotation`` and
    ``parasitic_centre`` without trigonometry (fast, and exact near theta = 0).
    """
    return _inverse(machine, side, tips_w, axes_w, first_sample, None)[0]


def inverse_kinematics_rates(machine: Machine, side: str, tips_w: np.ndarray, axes_w: np.ndarray,
                             tip_rate: np.ndarray, axis_rate: np.ndarray, first_sample: int = 0
                             ) -> tuple[np.ndarray, np.ndarray]:
    """``inverse_kinematics`` and the axis values' rate of change (n, 6): the Jacobian of the closed
    form times the motion of the pose, the tips moving at ``tip_rate`` (n, 3) in W and the unit axes
    at ``axis_rate`` (n, 3) (its component along the axis, which would change its length, is
    dropped), per whatever unit of time the rates are given in. Exact (no finite difference): the
    derivative of every step of the closed form by the chain rule."""
    return _inverse(machine, side, tips_w, axes_w, first_sample, (tip_rate, axis_rate))


def _inverse(machine: Machine, side: str, tips_w: np.ndarray, axes_w: np.ndarray, first_sample: int,
             rates: tuple | None) -> tuple[np.ndarray, np.ndarray | None]:
    """(values, rates or None): inverse_kinematics and, given (tip_rate, axis_rate), its derivative."""
    _check_side(side)
    tips_w = _as_rows("tool tips", tips_w, 3)
    axes_w = _as_rows("tool axes", axes_w, 3)
    if len(tips_w) != len(axes_w):
        raise MachineError(f"{len(tips_w)} tool tips but {len(axes_w)} tool axes")
    if not (np.isfinite(tips_w).all() and np.isfinite(axes_w).all()):
        bad = np.flatnonzero(~(np.isfinite(tips_w).all(axis=1) & np.isfinite(axes_w).all(axis=1)))
        bad += first_sample
        raise _fail(f"{side}: tool tip or axis is not a finite number at samples {_samples(bad)}", bad)
    t = machine.side(side)
    rot, org = t.rotation, t.origin
    # W -> M with contiguous columns (p_M = R^T (p_W - origin)); faster than an (n, 3) @ (3, 3) product.
    pw = [np.ascontiguousarray(tips_w[:, k]) - org[k] for k in range(3)]
    ww = [np.ascontiguousarray(axes_w[:, k]) for k in range(3)]
    p = [pw[0] * rot[0, i] + pw[1] * rot[1, i] + pw[2] * rot[2, i] for i in range(3)]
    w = [ww[0] * rot[0, i] + ww[1] * rot[1, i] + ww[2] * rot[2, i] for i in range(3)]
    norm = np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if np.abs(norm - 1.0).max(initial=0.0) > AXIS_NORM_TOLERANCE:
        bad = np.flatnonzero(np.abs(norm - 1.0) > AXIS_NORM_TOLERANCE)
        raise _fail(f"{side}: tool axis is not a unit vector (|w| = {norm[bad[0]]:.9g}) at samples "
                    f"{_samples(bad + first_sample)}", bad + first_sample)
    a, b, c = w[0] / norm, w[1] / norm, w[2] / norm
    cos_limit = np.cos(np.radians(machine.max_tilt_deg) + TILT_TOLERANCE)
    if c.min(initial=1.0) < cos_limit:
        bad = np.flatnonzero(c < cos_limit)
        theta = np.degrees(np.arctan2(np.hypot(a[bad], b[bad]), c[bad]))
        raise _fail(f"{side}: tool axis tilted {theta.max():.3f} deg from the spindle axis "
                    f"(limit max_tilt_deg = {machine.max_tilt_deg:g}) at samples "
                    f"{_samples(bad + first_sample)}", bad + first_sample)
    rp, rb, l0 = machine.platform_radius, machine.base_radius, machine.home_leg_length
    k = 1.0 / (1.0 + c)
    aak, abk, bbk = a * a * k, a * b * k, b * b * k
    # R = Rz(phi) Ry(theta) Rz(-phi): first two columns (the q_i are planar).
    r00, r01, r11 = 1.0 - aak, -abk, 1.0 - bbk
    # Parasitic centre c = (-(r_p/2)(a^2 - b^2)/(1 + c), r_p a b/(1 + c), h_0).
    cx = (-0.5 * rp) * (aak - bbk)
    cy = rp * abk
    h0, e = machine.home_height, machine.gauge_length
    out = np.empty((len(c), 6))
    out[:, 0] = p[0] + e * a - cx
    out[:, 1] = p[1] + e * b - cy
    out[:, 2] = p[2] + e * c - h0
    legs = []
    for i in range(3):  # the three legs: L_i = |c + R q_i - b_i|
        ca, sa = _COS_A[i], _SIN_A[i]
        vx = cx + (rp * ca) * r00 + (rp * sa) * r01 - rb * ca
        vy = cy + (rp * ca) * r01 + (rp * sa) * r11 - rb * sa
        vz = h0 - (rp * ca) * a - (rp * sa) * b
        length = np.sqrt(vx * vx + vy * vy + vz * vz)
        out[:, 3 + i] = length - l0
        legs.append((vx, vy, vz, length))
    if rates is None:
        return out, None
    # the same steps differentiated: dp, dw in M; the axis's rate less its part along the axis
    dpw, dww = _as_rows("tip rates", rates[0], 3), _as_rows("axis rates", rates[1], 3)
    dp = [dpw[:, 0] * rot[0, i] + dpw[:, 1] * rot[1, i] + dpw[:, 2] * rot[2, i] for i in range(3)]
    dw = [dww[:, 0] * rot[0, i] + dww[:, 1] * rot[1, i] + dww[:, 2] * rot[2, i] for i in range(3)]
    along = (a * dw[0] + b * dw[1] + c * dw[2]) / norm  # d|w| / |w|
    da, db, dc = dw[0] / norm - a * along, dw[1] / norm - b * along, dw[2] / norm - c * along
    dk = -k * k * dc
    daak = 2.0 * a * da * k + a * a * dk
    dabk = (da * b + a * db) * k + a * b * dk
    dbbk = 2.0 * b * db * k + b * b * dk
    dcx = (-0.5 * rp) * (daak - dbbk)
    dcy = rp * dabk
    vel = np.empty_like(out)
    vel[:, 0] = dp[0] + e * da - dcx
    vel[:, 1] = dp[1] + e * db - dcy
    vel[:, 2] = dp[2] + e * dc
    for i, (vx, vy, vz, length) in enumerate(legs):  # dL = (v . dv) / L; dr00 = -daak, dr01 = -dabk, ...
        ca, sa = _COS_A[i], _SIN_A[i]
        dvx = dcx - (rp * ca) * daak - (rp * sa) * dabk
        dvy = dcy - (rp * ca) * dabk - (rp * sa) * dbbk
        dvz = -(rp * ca) * da - (rp * sa) * db
        vel[:, 3 + i] = (vx * dvx + vy * dvy + vz * dvz) / length
    return out, vel


def forward_kinematics(machine: Machine, side: str, xyz_d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tool tips : (n, 3) float, mm, W, and unit tool axes : (n, 3) float, W, from the axis values.

    xyz_d : (n, 6) float, mm, columns x, y, z, d1, d2, d3; side : 'left' or 'right'. Solves the
    mechanism by Newton's method on the three leg elevation angles (residual below 1e-10 mm); raises
    MachineError naming the samples whose leg lengths no platform can take.
    """
    _check_side(side)
    xyz_d = _as_rows("axis values", xyz_d, 6)
    bad = np.flatnonzero(~np.isfinite(xyz_d).all(axis=1))
    if bad.size:
        raise _fail(f"{side}: axis values are not finite numbers at samples {_samples(bad)}", bad)
    joints = platform_joint_positions(machine, xyz_d[:, 3:], side=side)
    centre = joints.mean(axis=1)
    normal = np.cross(joints[:, 1] - joints[:, 0], joints[:, 2] - joints[:, 0])
    w = normal / np.linalg.norm(normal, axis=1)[:, None]
    bad = np.flatnonzero(w[:, 2] <= 0.0)
    if bad.size:
        raise _fail(f"{side}: the leg values at samples {_samples(bad)} put the platform upside down", bad)
    tips_m = xyz_d[:, :3] + centre - machine.gauge_length * w
    t = machine.side(side)
    return t.to_workpiece(tips_m), t.vectors_to_workpiece(w)


def platform_joint_positions(machine: Machine, d: np.ndarray, side: str = "") -> np.ndarray:
    """P_i : (n, 3, 3) float, mm, base frame (o = 0): the platform joints for leg values d : (n, 3), mm.

    Each P_i = b_i + L_i (cos beta_i u_i + sin beta_i e_z), u_i = -(cos a_i, sin a_i, 0), lies in its
    leg plane at distance L_i = L_0 + d_i from b_i; the elevations beta_i are found by Newton's method
    so that |P_i - P_j| = sqrt(3) r_p for the three pairs, starting from the home pose.
    """
    d = np.asarray(d, dtype=float)
    n = len(d)
    rb, s2 = machine.base_radius, 3.0 * machine.platform_radius ** 2
    lengths = [machine.home_leg_length + d[:, i] for i in range(3)]
    # In its plane leg i reaches P_i = rho_i (cos a_i, sin a_i, 0) + z_i e_z with
    # rho_i = R_b - L_i cos beta_i, z_i = L_i sin beta_i. The planes are 120 deg apart, so
    # |P_i - P_j|^2 = rho_i^2 + rho_j^2 + rho_i rho_j + (z_i - z_j)^2; Newton on
    # F_k = |P_i - P_j|^2 - 3 r_p^2 for the pairs (1,2), (2,3), (3,1).
    beta = [np.full(n, np.arctan2(machine.home_height, rb - machine.platform_radius)) for _ in range(3)]
    pairs = ((0, 1), (1, 2), (2, 0))
    res = np.full(n, np.inf)
    for _ in range(FK_MAX_ITERATIONS):
        cb, sb = [np.cos(x) for x in beta], [np.sin(x) for x in beta]
        rho = [rb - lengths[i] * cb[i] for i in range(3)]
        z = [lengths[i] * sb[i] for i in range(3)]
        drho = [lengths[i] * sb[i] for i in range(3)]  # d rho_i / d beta_i
        dz = [lengths[i] * cb[i] for i in range(3)]
        f, a, b = [], [], []  # residual, dF_k/dbeta_i, dF_k/dbeta_j
        for i, j in pairs:
            dzij = z[i] - z[j]
            f.append(rho[i] * rho[i] + rho[j] * rho[j] + rho[i] * rho[j] + dzij * dzij - s2)
            a.append((2.0 * rho[i] + rho[j]) * drho[i] + 2.0 * dzij * dz[i])
            b.append((2.0 * rho[j] + rho[i]) * drho[j] - 2.0 * dzij * dz[j])
        # distance residual in mm: |P_i - P_j| - sqrt(3) r_p = F / (|P_i - P_j| + sqrt(3) r_p)
        with np.errstate(invalid="ignore"):
            res = np.maximum.reduce([np.abs(fk) / (np.sqrt(np.abs(fk + s2)) + np.sqrt(s2)) for fk in f])
        if n == 0 or not (res >= FK_TOLERANCE_MM).any() and np.isfinite(res).all():
            break
        # J = [[a0, b0, 0], [0, a1, b1], [b2, 0, a2]] (cyclic), solved by Cramer's rule
        with np.errstate(all="ignore"):
            inv_det = 1.0 / (a[0] * a[1] * a[2] + b[0] * b[1] * b[2])
            t12 = f[1] * a[2] - b[1] * f[2]
            beta[0] = beta[0] - (f[0] * a[1] * a[2] - b[0] * t12) * inv_det
            beta[1] = beta[1] - (a[0] * t12 + f[0] * b[1] * b[2]) * inv_det
            beta[2] = beta[2] - (a[0] * a[1] * f[2] + b[0] * b[2] * f[1] - f[0] * a[1] * b[2]) * inv_det
    ok = res < FK_TOLERANCE_MM
    for x in beta:
        ok &= np.abs(x) < np.pi
    bad = np.flatnonzero(~ok)
    if bad.size:
        raise _fail(f"{side or 'machine'}: no platform pose for the leg values at samples {_samples(bad)} "
                    f"(forward kinematics did not converge); check d1..d3", bad)
    pos = np.empty((n, 3, 3))
    for i in range(3):
        pos[:, i, 0] = rho[i] * _COS_A[i]
        pos[:, i, 1] = rho[i] * _SIN_A[i]
        pos[:, i, 2] = z[i]
    return pos


def axis_velocities(t_ms: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Velocities : (n, 6) float, mm/ms, the time derivative of the axis motion.

    t_ms : (n,) float, ms, strictly increasing; values : (n, 6) float, mm (x, y, z, d1, d2, d3; any
    number of columns works). Each column is interpolated by a cubic spline through the samples
    (not-a-knot ends) and differentiated, so the result is smooth and does not depend on rounding of
    the values. Fewer than two samples give zeros.
    """
    t = np.asarray(t_ms, dtype=float)
    v = np.asarray(values, dtype=float)
    if t.ndim != 1 or v.ndim != 2 or len(v) != len(t):
        raise MachineError(f"axis velocities need t (n,) and values (n, k), got {t.shape} and {v.shape}")
    if len(t) < 2:
        return np.zeros_like(v)
    bad = np.flatnonzero(~(np.diff(t) > 0))
    if bad.size:
        raise _fail(f"time column not strictly increasing after samples {_samples(bad)}", bad)
    if len(t) == 2:
        return np.broadcast_to((v[1] - v[0]) / (t[1] - t[0]), v.shape).copy()
    from scipy.interpolate import CubicSpline  # only here: the module loads without scipy.interpolate

    return CubicSpline(t, v, axis=0).derivative()(t)
