# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The time-optimal solver's compiled passes (core.machine.optimum.profile), one knot at a time.

The speed is u = v^2 at knots s; between two knots u is linear in s (a constant tangential acceleration
a = (u1 - u0) / 2h). At each knot the acceleration rows bound a by w_j - r_j u from above and by
-w_j - r_j u from below (an axis: r = q''/|q'|, w = A/|q'|; the tip: r = 0, w = a_tip; a row with
w = inf bounds nothing), and the caps bound u itself. Both knots of an interval keep their rows.

- ``row_caps``: the largest u at each knot at which some a meets every row (the maximum velocity
  curve of the accelerations): the least (w_j + w_k) / (r_j - r_k) over the pairs with r_j > r_k.
- ``solve``: per run of knots, backward: the largest u_i from which the most negative a the interval
  allows (its rows at both knots) still reaches the next knot's bound; then forward: the largest a
  the interval allows, within the next knot's bound (the bang-bang profile). It records which row
  set each knot where the passes lowered it below its cap.
"""

from libc.math cimport INFINITY, fabs, isfinite
from libc.stdint cimport int8_t, int32_t, int64_t


def row_caps(const double[:, ::1] r, const double[:, ::1] w, double[::1] out, int32_t[::1] which):
    """out[i]: the maximum velocity curve at knot i (INFINITY: the rows never meet); which[i]: the row
    of its upper bound (-1 where none)."""
    cdef Py_ssize_t n = r.shape[0], m = r.shape[1], i, j, k
    cdef double best, coef, got
    cdef int32_t at
    with nogil:
        for i in range(n):
            best = INFINITY
            at = -1
            for j in range(m):
                if not isfinite(w[i, j]):
                    continue
                for k in range(m):
                    if k == j or not isfinite(w[i, k]):
                        continue
                    coef = r[i, j] - r[i, k]
                    if coef > 0:
                        got = (w[i, j] + w[i, k]) / coef
                        if got < best:
                            best = got
                            at = j
            out[i] = best
            which[i] = at


#: bounds an interval can have on a: each row at both knots, the next knot's bound and its floor
DEF MAX_BOUNDS = 64


cdef struct Bounds:
    # the admissible a of an interval: lower bounds a >= lo_p + lo_q u and upper a <= up_p + up_q u, in u
    # = u_i (the tag of each: its row, or ``m`` for the next knot's bound and ``m + 1`` for its floor);
    # ``cap``: what bounds u_i itself (a row at the next knot that bounds u alone)
    int n_lo, n_up
    double lo_p[MAX_BOUNDS]
    double lo_q[MAX_BOUNDS]
    int32_t lo_tag[MAX_BOUNDS]
    double up_p[MAX_BOUNDS]
    double up_q[MAX_BOUNDS]
    int32_t up_tag[MAX_BOUNDS]
    double cap


cdef inline void add(Bounds* b, bint upper, double p, double q, int32_t tag) noexcept nogil:
    if upper:
        b.up_p[b.n_up] = p
        b.up_q[b.n_up] = q
        b.up_tag[b.n_up] = tag
        b.n_up += 1
    else:
        b.lo_p[b.n_lo] = p
        b.lo_q[b.n_lo] = q
        b.lo_tag[b.n_lo] = tag
        b.n_lo += 1


cdef void interval_bounds(const double[:, ::1] r, const double[:, ::1] w, Py_ssize_t i, double two_h,
                          double next_bound, Bounds* b) noexcept nogil:
    """The bounds on a over interval i from u_i: knot i's rows (|a + r u| <= w), knot i + 1's through
    u_{i+1} = u + 2 h a (|a (1 + 2 h r') + r' u| <= w'), and 0 <= u + 2 h a <= next_bound."""
    cdef Py_ssize_t m = r.shape[1], j
    cdef double d
    b.n_lo = 0
    b.n_up = 0
    b.cap = INFINITY
    for j in range(m):
        if isfinite(w[i, j]):
            add(b, True, w[i, j], -r[i, j], <int32_t>j)
            add(b, False, -w[i, j], -r[i, j], <int32_t>j)
        if isfinite(w[i + 1, j]):
            d = 1.0 + two_h * r[i + 1, j]
            if d != 0.0:
                add(b, d > 0, w[i + 1, j] / d, -r[i + 1, j] / d, <int32_t>j)
                add(b, d < 0, -w[i + 1, j] / d, -r[i + 1, j] / d, <int32_t>j)
            elif r[i + 1, j] != 0.0:
                b.cap = lesser(b.cap, w[i + 1, j] / fabs(r[i + 1, j]))
    add(b, True, next_bound / two_h, -1.0 / two_h, <int32_t>m)
    add(b, False, 0.0, -1.0 / two_h, <int32_t>(m + 1))


cdef inline double lesser(double a, double b) noexcept nogil:
    return a if a < b else b


cdef double largest_u(const Bounds* b, int32_t* tag) noexcept nogil:
    """The largest u >= 0 at which the interval admits some a (every lower bound below every upper one
    there), and the tag of the bound that limits it (the lower one of the pair, or the upper one where
    the lower is the next knot's floor); INFINITY where nothing limits it."""
    cdef int p, q
    cdef double coef, got, best = b.cap
    tag[0] = -1
    for p in range(b.n_lo):
        for q in range(b.n_up):
            coef = b.lo_q[p] - b.up_q[q]
            if coef > 0:
                got = (b.up_p[q] - b.lo_p[p]) / coef
                if got < best:
                    best = got
                    tag[0] = b.up_tag[q] if b.lo_tag[p] > b.up_tag[q] else b.lo_tag[p]
    return best


cdef double largest_a(const Bounds* b, double u, int32_t* tag) noexcept nogil:
    """The largest a the interval admits from u (the least upper bound there) and its tag."""
    cdef int q
    cdef double got, best = INFINITY
    for q in range(b.n_up):
        got = b.up_p[q] + b.up_q[q] * u
        if got < best:
            best = got
            tag[0] = b.up_tag[q]
    return best


def solve(const double[::1] s, const double[::1] u_cap, const double[:, ::1] r, const double[:, ::1] w,
          const int64_t[::1] first, const int64_t[::1] size, const double[::1] u_start,
          const double[::1] u_end, double[::1] u, int32_t[::1] row, int8_t[::1] phase):
    """The time-optimal u (module docstring) of runs of knots (run k: knots first[k] .. first[k] +
    size[k] - 1, from u_start[k] to u_end[k]) into ``u``; per knot the row that set it (-1: none, or
    the number of rows for the next knot's bound) and the pass (phase: 0 its cap or the run's end
    speeds, 1 braking, 2 speeding up)."""
    cdef Py_ssize_t k, i, a, b, m = r.shape[1]
    cdef double two_h, got, step
    cdef int32_t at
    cdef Bounds bounds
    if 2 * m + 2 > MAX_BOUNDS:
        raise ValueError(f"at most {(MAX_BOUNDS - 2) // 2} acceleration rows, not {m}")
    with nogil:
        for k in range(first.shape[0]):
            if size[k] <= 0:
                continue
            a = first[k]
            b = a + size[k] - 1
            for i in range(a, b + 1):
                u[i] = u_cap[i]
                row[i] = -1
                phase[i] = 0
            if u_end[k] < u[b]:
                u[b] = u_end[k]
            for i in range(b - 1, a - 1, -1):  # backward: u holds each knot's bound
                two_h = 2.0 * (s[i + 1] - s[i])
                if two_h <= 0.0:
                    continue
                interval_bounds(r, w, i, two_h, u[i + 1], &bounds)
                at = -1
                got = largest_u(&bounds, &at)
                if got < u[i]:
                    u[i] = got
                    row[i] = at
                    phase[i] = 1
            if u_start[k] < u[a]:
                u[a] = u_start[k]
                row[a] = -1
                phase[a] = 0
            for i in range(a, b):  # forward: the largest a within the next knot's bound
                two_h = 2.0 * (s[i + 1] - s[i])
                if two_h <= 0.0:
                    if u[i] < u[i + 1]:
                        u[i + 1] = u[i]
                        row[i + 1] = row[i]
                        phase[i + 1] = phase[i]
                    continue
                interval_bounds(r, w, i, two_h, u[i + 1], &bounds)
                at = -1
                step = u[i] + two_h * largest_a(&bounds, u[i], &at)
                if step < 0.0:
                    step = 0.0
                if step < u[i + 1] and at != m:
                    u[i + 1] = step
                    row[i + 1] = at
                    phase[i + 1] = 2
