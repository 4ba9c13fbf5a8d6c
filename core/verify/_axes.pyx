# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""verify's own forward kinematics of one XYZ-3RPS side, compiled (core.verify.axes calls it; nothing
here is the planner's).

The mechanism (SPEC.md section 9): base joints b_i = R_b (cos a_i, sin a_i, 0), a_i = 0, 120, 240
degrees, each leg in the vertical plane through the z axis at a_i, of length L_i = L_0 + d_i; its
platform joint P_i = rho_i (cos a_i, sin a_i, 0) + z_i e_z, rho_i = R_b - L_i cos beta_i, z_i =
L_i sin beta_i, at the leg's elevation beta_i. The three joints form the platform's equilateral
triangle of side sqrt(3) r_p: |P_i - P_j|^2 = rho_i^2 + rho_j^2 + rho_i rho_j + (z_i - z_j)^2 =
3 r_p^2 for the pairs (0, 1), (1, 2), (2, 0), solved for the beta_i by Newton's method from the home
pose until each side's length is within TOLERANCE of sqrt(3) r_p. The platform centre c is the
triangle's centroid, the tool axis w its unit normal (P_1 - P_0) x (P_2 - P_0), and the tip
o + c - e w in the machine frame (o = (x, y, z), e the gauge length), carried into the workpiece
frame by the side's rigid transform. Row by row, without the GIL.
"""

from libc.math cimport sqrt, cos, sin, atan2, fabs, acos, isfinite, M_PI, NAN
from libc.stdint cimport uint8_t

#: mm: how far each side of the joints' triangle may be from sqrt(3) r_p when Newton's method stops
DEF TOLERANCE = 1e-10
DEF ITERATIONS = 50
#: a row's status (``forward_errors``)
DEF OK = 0
DEF NOT_FINITE = 1
DEF NO_POSE = 2
DEF UPSIDE_DOWN = 3


cdef int joints(const double* d, double rb, double rp, double l0, double h0, double* rho, double* z) noexcept nogil:
    """The platform joints' radii rho (3,) and heights z (3,) mm for the leg values d (3,) mm (module
    docstring); NO_POSE where Newton's method does not converge, or an elevation leaves (-pi, pi)."""
    cdef double beta[3]
    cdef double length[3]
    cdef double drho[3]
    cdef double dz[3]
    cdef double f[3]
    cdef double ja[3]
    cdef double jb[3]
    cdef double s2 = 3.0 * rp * rp, res, x, dzij, inv, t12, b0, b1, b2
    cdef int it, k, i, j
    for k in range(3):
        length[k] = l0 + d[k]
        beta[k] = atan2(h0, rb - rp)
    for it in range(ITERATIONS):
        for k in range(3):
            x = cos(beta[k])
            rho[k] = rb - length[k] * x
            dz[k] = length[k] * x
            z[k] = length[k] * sin(beta[k])
            drho[k] = z[k]
        res = 0.0
        for k in range(3):
            i = k
            j = (k + 1) % 3
            dzij = z[i] - z[j]
            f[k] = rho[i] * rho[i] + rho[j] * rho[j] + rho[i] * rho[j] + dzij * dzij - s2
            ja[k] = (2.0 * rho[i] + rho[j]) * drho[i] + 2.0 * dzij * dz[i]
            jb[k] = (2.0 * rho[j] + rho[i]) * drho[j] - 2.0 * dzij * dz[j]
            x = fabs(f[k]) / (sqrt(fabs(f[k] + s2)) + sqrt(s2))  # (|P_i - P_j| - sqrt(s2), mm)
            if not x <= res:  # (nan as well)
                res = x
        if res < TOLERANCE:
            for k in range(3):
                if not fabs(beta[k]) < M_PI:
                    return NO_POSE
            return OK
        # J = [[a0, b0, 0], [0, a1, b1], [b2, 0, a2]] (cyclic), solved by Cramer's rule
        inv = 1.0 / (ja[0] * ja[1] * ja[2] + jb[0] * jb[1] * jb[2])
        t12 = f[1] * ja[2] - jb[1] * f[2]
        b0 = (f[0] * ja[1] * ja[2] - jb[0] * t12) * inv
        b1 = (ja[0] * t12 + f[0] * jb[1] * jb[2]) * inv
        b2 = (ja[0] * ja[1] * f[2] + jb[0] * jb[2] * f[1] - f[0] * ja[1] * jb[2]) * inv
        beta[0] -= b0
        beta[1] -= b1
        beta[2] -= b2
    return NO_POSE


cdef int pose(const double* row, double rb, double rp, double l0, double h0, double e, const double* ca,
              const double* sa, double* tip, double* w) noexcept nogil:
    """The tip (3,) mm and unit tool axis w (3,), machine frame, for one row's axis values x, y, z,
    d1, d2, d3 (mm); a status (``forward_errors``)."""
    cdef double rho[3]
    cdef double z[3]
    cdef double p[3][3]
    cdef double u[3]
    cdef double v[3]
    cdef double x
    cdef int k, status
    for k in range(6):
        if not isfinite(row[k]):
            return NOT_FINITE
    status = joints(row + 3, rb, rp, l0, h0, rho, z)
    if status != OK:
        return status
    for k in range(3):
        p[k][0] = rho[k] * ca[k]
        p[k][1] = rho[k] * sa[k]
        p[k][2] = z[k]
    for k in range(3):
        u[k] = p[1][k] - p[0][k]
        v[k] = p[2][k] - p[0][k]
    w[0] = u[1] * v[2] - u[2] * v[1]
    w[1] = u[2] * v[0] - u[0] * v[2]
    w[2] = u[0] * v[1] - u[1] * v[0]
    x = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    for k in range(3):
        w[k] /= x
    if not w[2] > 0.0:
        return UPSIDE_DOWN
    for k in range(3):
        tip[k] = row[k] + (p[0][k] + p[1][k] + p[2][k]) / 3.0 - e * w[k]
    return OK


def forward_errors(const double[:, :] values, const double[:, :] tips, const double[:, :] axes, tuple head,
                   const double[:, ::1] rotation, const double[::1] origin, double[::1] tip_error,
                   double[::1] axis_error, uint8_t[::1] status):
    """Row by row, the forward kinematics of the axis values (n, 6) (x, y, z, d1, d2, d3 mm) against
    the CL table's tips (n, 3) mm and axes (n, 3) (workpiece frame W; each axis normalised here):
    tip_error (n,) mm and axis_error (n,) rad between them, status (n,) 0 (a pose), 1 (a value not a
    finite number), 2 (no pose: Newton's method did not converge), 3 (the platform upside down), the
    errors nan where not 0. ``head`` = (R_b, r_p, h_0, e) mm; rotation (3, 3) and origin (3,) mm: the
    side's transform M -> W (p_W = origin + R p_M)."""
    cdef double rb = head[0], rp = head[1], h0 = head[2], e = head[3]
    cdef double l0 = sqrt((rb - rp) * (rb - rp) + h0 * h0), x, dot, nw, err
    cdef double ca[3]
    cdef double sa[3]
    cdef double row[6]
    cdef double tip[3]
    cdef double w[3]
    cdef Py_ssize_t i, n = values.shape[0]
    cdef int k, s
    for k in range(3):
        ca[k] = cos(k * 2.0 * M_PI / 3.0)
        sa[k] = sin(k * 2.0 * M_PI / 3.0)
    with nogil:
        for i in range(n):
            for k in range(6):
                row[k] = values[i, k]
            s = pose(row, rb, rp, l0, h0, e, ca, sa, tip, w)
            status[i] = s
            if s != OK:
                tip_error[i] = NAN
                axis_error[i] = NAN
                continue
            err = 0.0
            dot = 0.0
            nw = 0.0
            for k in range(3):
                x = origin[k] + rotation[k, 0] * tip[0] + rotation[k, 1] * tip[1] + rotation[k, 2] * tip[2] - tips[i, k]
                err += x * x
                dot += (rotation[k, 0] * w[0] + rotation[k, 1] * w[1] + rotation[k, 2] * w[2]) * axes[i, k]
                nw += axes[i, k] * axes[i, k]
            tip_error[i] = sqrt(err)
            x = dot / sqrt(nw)
            axis_error[i] = acos(-1.0 if x < -1.0 else (1.0 if x > 1.0 else x))


cdef inline double derivative_gap(double dt, double x0, double x1, double v0, double v1, double a_lim) noexcept nogil:
    """mm/ms: how far the chord velocity (x1 - x0) / dt lies outside what the velocities v0, v1 at its
    ends allow (core.verify.axes.derivative_slack), 0 inside (nan where dt is 0 or a value is nan)."""
    cdef double c = (x1 - x0) / dt
    cdef double lo = v0 if v0 < v1 else v1, hi = v1 if v0 < v1 else v0
    cdef double room = a_lim * dt + (1e-6 + 1e-6 * fabs(c)) / dt + 2e-9
    cdef double out = (lo - c if lo - c > c - hi else c - hi) - room
    return out if out > 0.0 or out != out else 0.0


def derivative_slacks(const double[::1] t, const double[:] x, const double[:] v, double a_lim, double[::1] out):
    """out (n - 1,) mm/ms: ``derivative_gap`` between each two rows of the times t (n,) ms, positions
    x (n,) mm and velocities v (n,) mm/ms."""
    cdef Py_ssize_t i, n = t.shape[0]
    with nogil:
        for i in range(n - 1):
            out[i] = derivative_gap(t[i + 1] - t[i], x[i], x[i + 1], v[i], v[i + 1], a_lim)


def axis_column(const double[::1] t, const double[:] x, const double[:] v, tuple limits, double[::1] acc,
                double[::1] slack, uint8_t[::1] flags):
    """One axis's positions x (n,) mm and velocities v (n,) mm/ms at the times t (n,) ms against its
    ``limits`` = (stroke min, stroke max mm, speed mm/s, acceleration mm/s^2): acc (n - 1,) mm/s^2 the
    mean acceleration from each row to the next, slack (n - 1,) mm/ms its ``derivative_gap``, and
    flags (n,) per row: 1 outside the stroke (by more than 1e-6 mm), 2 faster than the speed limit (by
    1e-6 of it and 1e-6 mm/s), 4 acceleration to the next row above the limit (by 1e-6 of it and the
    rounding of the written velocities, 1e-9 mm/ms, and times), 8 a slack to the next row above 0."""
    cdef double lo = limits[0], hi = limits[1], speed = limits[2], accel = limits[3]
    cdef double dt, dv, room
    cdef Py_ssize_t i, n = t.shape[0]
    cdef uint8_t f
    with nogil:
        for i in range(n):
            f = 0
            if x[i] < lo - 1e-6 or x[i] > hi + 1e-6:
                f |= 1
            if fabs(v[i]) * 1000.0 > speed * (1.0 + 1e-6) + 1e-6:
                f |= 2
            if i < n - 1:
                dt = t[i + 1] - t[i]
                dv = v[i + 1] - v[i]
                acc[i] = fabs(dv) / dt * 1e6
                room = (2e-9 / dt + fabs(dv) * 2e-6 / (dt * dt)) * 1e6
                if acc[i] > accel * (1.0 + 1e-6) + room:
                    f |= 4
                slack[i] = derivative_gap(dt, x[i], x[i + 1], v[i], v[i + 1], accel / 1e6)
                if slack[i] > 0.0:
                    f |= 8
            flags[i] = f
