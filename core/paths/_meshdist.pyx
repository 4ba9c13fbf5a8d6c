# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Exact distances from segments (the axes of a tool assembly's parts) to a triangle mesh, through a
uniform grid of cells each listing the triangles whose centroid it holds, and the grid's distance
fields (core.paths.meshgrid.MeshGrid builds the grid's geometry and calls these).

A query visits the blocks of cells within reach of its segment, skips a block or cell whose centre lies
farther from the segment than the best distance so far plus its half diagonal and the largest bounding
sphere of its triangles, skips a triangle whose bounding sphere does or whose corners all lie beyond
reach along the distance's gradient at its centroid (the distance from a segment is convex), and
measures the rest exactly: the least of the two ends' distances from the triangle, the segment's from
the triangle's three edges, and zero where the segment crosses the triangle (the closest pair of a
segment and a triangle that do not meet has an end of the segment or an edge of the triangle in it).
Queries in a row are usually close together: the previous query's distance plus how far the segment
moved since is an upper bound of the next one's, and the search reaches no farther. The loops release
the GIL: the two sides are checked in two threads.
"""

from libc.math cimport sqrt, floor, fabs, nextafterf, INFINITY
from libc.stdint cimport int64_t, uint8_t

import numpy as np


cdef inline double dot(const double* u, const double* v) noexcept nogil:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


cdef double point_triangle_sq(const double* p, const double* a, const double* ab, const double* ac) noexcept nogil:
    """Squared distance from p to triangle (a, a + ab, a + ac) (Ericson 5.1.5)."""
    cdef double ap[3]
    cdef double d1, d2, d3, d4, d5, d6, va, vb, vc, v, w, denom, g0, g1, g2
    ap[0] = p[0] - a[0]; ap[1] = p[1] - a[1]; ap[2] = p[2] - a[2]
    d1 = dot(ab, ap); d2 = dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return dot(ap, ap)
    cdef double e00 = dot(ab, ab), e01 = dot(ab, ac), e11 = dot(ac, ac)
    d3 = d1 - e00; d4 = d2 - e01          # (p - b) . ab, (p - b) . ac
    if d3 >= 0.0 and d4 <= d3:
        v = 1.0; w = 0.0
    else:
        d5 = d1 - e01; d6 = d2 - e11      # (p - c) . ab, (p - c) . ac
        if d6 >= 0.0 and d5 <= d6:
            v = 0.0; w = 1.0
        else:
            vc = d1 * d4 - d3 * d2
            vb = d5 * d2 - d1 * d6
            va = d3 * d6 - d5 * d4
            if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
                v = d1 / (d1 - d3); w = 0.0
            elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
                v = 0.0; w = d2 / (d2 - d6)
            elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
                w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); v = 1.0 - w
            else:
                denom = va + vb + vc
                if denom == 0.0:
                    v = 0.0; w = 0.0
                else:
                    v = vb / denom; w = vc / denom
    g0 = ap[0] - v * ab[0] - w * ac[0]
    g1 = ap[1] - v * ab[1] - w * ac[1]
    g2 = ap[2] - v * ab[2] - w * ac[2]
    return g0 * g0 + g1 * g1 + g2 * g2


cdef inline double clamp01(double x) noexcept nogil:
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


cdef double segment_segment_sq(const double* p1, const double* d1, const double* p2, const double* d2) noexcept nogil:
    """Squared distance between segments p1 + s d1 and p2 + t d2, s, t in [0, 1] (Ericson 5.1.9)."""
    cdef double r[3]
    cdef double a, e, f, b, c, denom, s, t, g0, g1, g2
    r[0] = p1[0] - p2[0]; r[1] = p1[1] - p2[1]; r[2] = p1[2] - p2[2]
    a = dot(d1, d1); e = dot(d2, d2); f = dot(d2, r)
    if a <= 1e-300 and e <= 1e-300:
        return dot(r, r)
    if a <= 1e-300:
        s = 0.0
        t = clamp01(f / e)
    else:
        c = dot(d1, r)
        if e <= 1e-300:
            t = 0.0
            s = clamp01(-c / a)
        else:
            b = dot(d1, d2)
            denom = a * e - b * b
            s = clamp01((b * f - c * e) / denom) if denom > 1e-12 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = clamp01(-c / a)
            elif t > 1.0:
                t = 1.0
                s = clamp01((b - c) / a)
    g0 = r[0] + s * d1[0] - t * d2[0]
    g1 = r[1] + s * d1[1] - t * d2[1]
    g2 = r[2] + s * d1[2] - t * d2[2]
    return g0 * g0 + g1 * g1 + g2 * g2


cdef bint crosses(const double* p, const double* d, const double* a, const double* ab, const double* ac) noexcept nogil:
    """Whether the segment p + s d, s in [0, 1], meets the triangle (Moller-Trumbore)."""
    cdef double h[3]
    cdef double q[3]
    cdef double s[3]
    cdef double det, inv, u, v, t
    h[0] = d[1] * ac[2] - d[2] * ac[1]
    h[1] = d[2] * ac[0] - d[0] * ac[2]
    h[2] = d[0] * ac[1] - d[1] * ac[0]
    det = dot(ab, h)
    if fabs(det) < 1e-300:
        return False  # (parallel: the ends and edges measure it)
    inv = 1.0 / det
    s[0] = p[0] - a[0]; s[1] = p[1] - a[1]; s[2] = p[2] - a[2]
    u = inv * dot(s, h)
    if u < 0.0 or u > 1.0:
        return False
    q[0] = s[1] * ab[2] - s[2] * ab[1]
    q[1] = s[2] * ab[0] - s[0] * ab[2]
    q[2] = s[0] * ab[1] - s[1] * ab[0]
    v = inv * dot(d, q)
    if v < 0.0 or u + v > 1.0:
        return False
    t = inv * dot(ac, q)
    return 0.0 <= t <= 1.0


cdef double segment_triangle_sq(const double* p, const double* d, const double* a, const double* ab,
                                const double* ac) noexcept nogil:
    """Squared distance from the segment p + s d (s in [0, 1]) to the triangle (a, a + ab, a + ac)."""
    cdef double q[3]
    cdef double b[3]
    cdef double bc[3]
    cdef double best, x
    if crosses(p, d, a, ab, ac):
        return 0.0
    q[0] = p[0] + d[0]; q[1] = p[1] + d[1]; q[2] = p[2] + d[2]
    b[0] = a[0] + ab[0]; b[1] = a[1] + ab[1]; b[2] = a[2] + ab[2]
    bc[0] = ac[0] - ab[0]; bc[1] = ac[1] - ab[1]; bc[2] = ac[2] - ab[2]
    best = point_triangle_sq(p, a, ab, ac)
    x = point_triangle_sq(q, a, ab, ac)
    if x < best:
        best = x
    x = segment_segment_sq(p, d, a, ab)
    if x < best:
        best = x
    x = segment_segment_sq(p, d, a, ac)
    if x < best:
        best = x
    x = segment_segment_sq(p, d, b, bc)
    if x < best:
        best = x
    return best


#: cells per block side: the search skips empty blocks and blocks out of reach whole
DEF BLOCK = 8


def block_cells() -> int:
    """Cells per block side (the grid's ``blocks`` cover BLOCK^3 cells each, the last ones partial)."""
    return BLOCK


cdef inline int64_t axis_cell(double x, double origin, double h, int64_t n) noexcept nogil:
    """The cell index along one axis of coordinate x, clamped to the grid's n cells."""
    cdef int64_t k = <int64_t>floor((x - origin) / h)
    return 0 if k < 0 else (n - 1 if k > n - 1 else k)


cdef inline float float_up(double x) noexcept nogil:
    """x rounded up to a float."""
    cdef float f = <float>x
    return nextafterf(f, INFINITY) if f < x else f


cdef inline float float_down(double x) noexcept nogil:
    """x rounded down to a float."""
    cdef float f = <float>x
    return nextafterf(f, -INFINITY) if f > x else f


def centroid_cells(const double[:, ::1] a, const double[:, ::1] ab, const double[:, ::1] ac,
                   const double[::1] origin, double h, const int64_t[::1] dims):
    """start (cells + 1,) int64: the triangles a, ab, ac ((3, m) mm each) counted by the cell of their
    centroid (cell index (i * dims[1] + j) * dims[2] + l), cumulated: cell k's triangles are the
    start[k]th to the start[k + 1]th in the order of their cells (``fill_grid``)."""
    cdef Py_ssize_t m = a.shape[1], t, k
    cdef int64_t cell
    start_arr = np.zeros(dims[0] * dims[1] * dims[2] + 1, np.int64)
    cdef int64_t[::1] start = start_arr
    with nogil:
        for t in range(m):
            cell = 0
            for k in range(3):
                cell = cell * dims[k] + axis_cell(a[k, t] + (ab[k, t] + ac[k, t]) / 3.0, origin[k], h, dims[k])
            start[cell + 1] += 1
        for k in range(1, start.shape[0]):
            start[k] += start[k - 1]
    return start_arr


def fill_grid(const double[:, ::1] a, const double[:, ::1] ab, const double[:, ::1] ac,
              const double[::1] origin, double h, const int64_t[::1] dims, const int64_t[::1] start,
              double[:, ::1] tri, float[::1] cell_reach, double[::1] blocks, uint8_t[::1] occupied):
    """Fills the grid's arrays from the triangles a, ab, ac ((3, m) mm each) and ``start``
    (``centroid_cells``): tri (m, 13) per triangle a, ab, ac, its bounding sphere's centre (the
    centroid) and radius, in the order of the centroids' cells (within a cell, as given); cell_reach
    (cells,): the largest radius of a cell's triangles (rounded up); blocks (blocks,): the largest of a
    block's (``block_cells``), -1 where it holds none; occupied (cells,): 1 where a triangle's bounding
    box overlaps the cell. cell_reach, blocks and occupied come in as 0, -1 and 0."""
    cdef Py_ssize_t m = a.shape[1], t, k
    cdef int64_t cell, pos, i, j, l, blk
    cdef int64_t lo[3]
    cdef int64_t hi[3]
    cdef int64_t nb[3]
    cdef double c[3]
    cdef double x, y, z, r2, lo_x, hi_x
    cdef float rf
    fill_arr = np.asarray(start[:start.shape[0] - 1]).copy()
    cdef int64_t[::1] fill = fill_arr
    for k in range(3):
        nb[k] = (dims[k] + BLOCK - 1) // BLOCK
    with nogil:
        for t in range(m):
            cell = 0
            for k in range(3):
                c[k] = a[k, t] + (ab[k, t] + ac[k, t]) / 3.0
                cell = cell * dims[k] + axis_cell(c[k], origin[k], h, dims[k])
                lo_x = a[k, t] + (ab[k, t] if ab[k, t] < 0.0 else 0.0)
                lo_x = min(lo_x, a[k, t] + ac[k, t])
                hi_x = a[k, t] + (ab[k, t] if ab[k, t] > 0.0 else 0.0)
                hi_x = max(hi_x, a[k, t] + ac[k, t])
                lo[k] = axis_cell(lo_x, origin[k], h, dims[k])
                hi[k] = axis_cell(hi_x, origin[k], h, dims[k])
            pos = fill[cell]
            fill[cell] += 1
            r2 = 0.0
            for k in range(3):
                tri[pos, k] = a[k, t]
                tri[pos, 3 + k] = ab[k, t]
                tri[pos, 6 + k] = ac[k, t]
                tri[pos, 9 + k] = c[k]
            x = a[0, t] - c[0]; y = a[1, t] - c[1]; z = a[2, t] - c[2]
            r2 = max(r2, x * x + y * y + z * z)
            x += ab[0, t]; y += ab[1, t]; z += ab[2, t]
            r2 = max(r2, x * x + y * y + z * z)
            x += ac[0, t] - ab[0, t]; y += ac[1, t] - ab[1, t]; z += ac[2, t] - ab[2, t]
            r2 = max(r2, x * x + y * y + z * z)
            tri[pos, 12] = sqrt(r2)
            rf = float_up(tri[pos, 12])
            if rf > cell_reach[cell]:
                cell_reach[cell] = rf
            blk = ((axis_cell(c[0], origin[0], h, dims[0]) // BLOCK * nb[1]
                    + axis_cell(c[1], origin[1], h, dims[1]) // BLOCK) * nb[2]
                   + axis_cell(c[2], origin[2], h, dims[2]) // BLOCK)
            if tri[pos, 12] > blocks[blk]:
                blocks[blk] = tri[pos, 12]
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for l in range(lo[2], hi[2] + 1):
                        occupied[(i * dims[1] + j) * dims[2] + l] = 1


cdef void envelope(double* g, Py_ssize_t n, Py_ssize_t stride, double* f, Py_ssize_t* v, double* z) noexcept nogil:
    """In place along one line of n cells (``stride`` apart) of a field of squared distances (cell
    units, INFINITY where unknown): g[q] = min over r of g[r] + (q - r)^2, the lower envelope of the
    parabolas (Felzenszwalb and Huttenlocher, Distance Transforms of Sampled Functions, 2012)."""
    cdef Py_ssize_t q, k = -1, j = 0
    cdef double s = 0.0
    for q in range(n):
        f[q] = g[q * stride]
    for q in range(n):
        if f[q] == INFINITY:
            continue
        while k >= 0:
            s = ((f[q] + <double>(q * q)) - (f[v[k]] + <double>(v[k] * v[k]))) / (2.0 * (q - v[k]))
            if s <= z[k]:
                k -= 1
            else:
                break
        k += 1
        v[k] = q
        z[k] = s if k > 0 else -INFINITY
        z[k + 1] = INFINITY
    if k < 0:
        return
    for q in range(n):
        while z[j + 1] < q:
            j += 1
        g[q * stride] = <double>((q - v[j]) * (q - v[j])) + f[v[j]]


cdef void squared_distances(double* g, const int64_t* dims, double* f, Py_ssize_t* v, double* z) noexcept nogil:
    """In place over the grid (dims cells, C order): g, 0 at the cells measured from and INFINITY
    elsewhere, becomes each cell's squared distance (cell units) from the nearest of them."""
    cdef Py_ssize_t i, j, l, nx = dims[0], ny = dims[1], nz = dims[2]
    for i in range(nx):
        for j in range(ny):
            envelope(g + (i * ny + j) * nz, nz, 1, f, v, z)
    for i in range(nx):
        for l in range(nz):
            envelope(g + i * ny * nz + l, ny, nz, f, v, z)
    for j in range(ny):
        for l in range(nz):
            envelope(g + j * nz + l, nx, ny * nz, f, v, z)


def distance_fields(const uint8_t[::1] occupied, const int64_t[::1] start, const int64_t[::1] dims, double h,
                    float[::1] floor_out, float[::1] ceiling_out):
    """The grid's fields (core.paths.meshgrid.MeshGrid): floor_out, per cell, h times the distance
    from its centre to the nearest occupied cell's, less half a cell's diagonal (rounded down: a
    lower bound of the distance from the centre to the occupied cells' boxes); ceiling_out, h times
    that to the nearest cell holding a centroid (start[k + 1] > start[k]), plus half a diagonal
    (rounded up: an upper bound of the distance from the centre to that centroid). Exact Euclidean
    distance transforms of the cells (squared distances in whole cells: sums of squares of integers)."""
    cdef Py_ssize_t n = occupied.shape[0], k, longest = max(dims[0], dims[1], dims[2])
    cdef double half_diag = 0.5 * h * sqrt(3.0)
    g_arr = np.empty(n)
    f_arr, z_arr = np.empty(longest), np.empty(longest + 1)
    v_arr = np.empty(longest, np.intp)
    cdef double[::1] g = g_arr, f = f_arr, z = z_arr
    cdef Py_ssize_t[::1] v = v_arr
    with nogil:
        for k in range(n):
            g[k] = 0.0 if occupied[k] else INFINITY
        squared_distances(&g[0], &dims[0], &f[0], &v[0], &z[0])
        for k in range(n):
            floor_out[k] = float_down(h * sqrt(g[k]) - half_diag)
        for k in range(n):
            g[k] = 0.0 if start[k + 1] > start[k] else INFINITY
        squared_distances(&g[0], &dims[0], &f[0], &v[0], &z[0])
        for k in range(n):
            ceiling_out[k] = float_up(h * sqrt(g[k]) + half_diag)


cdef inline double field_bound(const float* field, const double* o, double h, const int64_t* n, const double* p,
                               bint upper) noexcept nogil:
    """A bound of the distance of the point p from the mesh from a field (``distance_fields``): with
    q p's projection onto the grid and c the centre of q's cell, from below max(floor - |q - c|, 0)
    combined with |p - q| at a right angle (the mesh lies inside the grid), from above
    ceiling + |q - c| + |p - q|."""
    cdef double off2 = 0.0, dc2 = 0.0, x, q, b
    cdef int64_t cell = 0, k
    cdef Py_ssize_t ax
    for ax in range(3):
        x = p[ax]
        q = min(max(x, o[ax]), o[ax] + n[ax] * h)
        off2 += (x - q) * (x - q)
        k = axis_cell(q, o[ax], h, n[ax])
        x = q - (o[ax] + (k + 0.5) * h)
        dc2 += x * x
        cell = cell * n[ax] + k
    if upper:
        return field[cell] + sqrt(dc2) + sqrt(off2)
    b = field[cell] - sqrt(dc2)
    return sqrt(off2 + b * b) if b > 0.0 else sqrt(off2)


def segment_bounds(const float[::1] field, const double[::1] origin, double h, const int64_t[::1] dims,
                   const double[:, ::1] p0, const double[:, ::1] p1, Py_ssize_t n_s, bint upper, double[::1] out):
    """out[i]: a bound of the distance of the segment p0[i]-p1[i] from the mesh from the grid's
    field (``field_bound`` at n_s + 1 points evenly along it): from below the least less half their
    spacing (every point of the segment lies within it of one), at least 0; with ``upper``, from
    above the least."""
    cdef Py_ssize_t n = p0.shape[0], i, j, ax
    cdef double p[3]
    cdef double f, x, least, half
    cdef int64_t nd[3]
    cdef double o[3]
    for ax in range(3):
        nd[ax], o[ax] = dims[ax], origin[ax]
    with nogil:
        for i in range(n):
            least = INFINITY
            for j in range(n_s + 1):
                f = <double>j / n_s
                for ax in range(3):
                    p[ax] = p0[i, ax] + f * (p1[i, ax] - p0[i, ax])
                x = field_bound(&field[0], o, h, nd, p, upper)
                if x < least:
                    least = x
            if not upper:
                half = 0.0
                for ax in range(3):
                    half += (p1[i, ax] - p0[i, ax]) * (p1[i, ax] - p0[i, ax])
                least -= 0.5 * sqrt(half) / n_s
                least = least if least > 0.0 else 0.0
            out[i] = least


cdef struct Grid:
    const double* tri       # (m, 13): a, ab, ac, bounding sphere's centre and radius, by centroid cell
    const int64_t* start    # (cells + 1,): cell k's triangles are tri[start[k]:start[k + 1]]
    const float* cell_reach  # (cells,): the largest radius of a cell's triangles
    const double* blocks    # (blocks,): the largest radius of a block's triangles, -1 for none
    double reach            # the largest radius of any
    double o[3]
    double h
    int64_t n[3]
    int64_t nb[3]


cdef inline double centre_sq(const double* c, const double* p, const double* d, double dd) noexcept nogil:
    """The squared distance of the point c from the segment p + s d (dd = d . d)."""
    cdef double g0, g1, g2, s
    g0 = c[0] - p[0]; g1 = c[1] - p[1]; g2 = c[2] - p[2]
    s = clamp01((g0 * d[0] + g1 * d[1] + g2 * d[2]) / dd) if dd > 0.0 else 0.0
    g0 -= s * d[0]; g1 -= s * d[1]; g2 -= s * d[2]
    return g0 * g0 + g1 * g1 + g2 * g2


cdef double cell_scan(const Grid* m, int64_t cell, const double* p, const double* d, double dd,
                      double* best, double* near, double enough) noexcept nogil:
    """The triangles of one cell against the segment p + s d (``scan``): best and near lowered to
    any distance found below them; returns the distance found at or below enough, else -1."""
    cdef int64_t k
    cdef double c[3]
    cdef double x, s, g0, g1, g2, ua, uab, uac, reach
    cdef const double* row
    for k in range(m.start[cell], m.start[cell + 1]):
        row = m.tri + 13 * k
        c[0] = row[9] - p[0]; c[1] = row[10] - p[1]; c[2] = row[11] - p[2]
        s = clamp01(dot(c, d) / dd) if dd > 0.0 else 0.0
        g0 = c[0] - s * d[0]; g1 = c[1] - s * d[1]; g2 = c[2] - s * d[2]
        reach = near[0] + row[12]
        x = g0 * g0 + g1 * g1 + g2 * g2
        if x >= reach * reach:
            continue
        # the distance from the segment is convex: at least its value at the centroid plus its
        # gradient there (g / |g|) times the farthest a corner lies against it
        if x > 0.0:
            x = sqrt(x)
            ua = g0 * (row[0] - row[9]) + g1 * (row[1] - row[10]) + g2 * (row[2] - row[11])
            uab = g0 * row[3] + g1 * row[4] + g2 * row[5]
            uac = g0 * row[6] + g1 * row[7] + g2 * row[8]
            if x + (ua + min(0.0, min(uab, uac))) / x >= near[0]:
                continue
        x = segment_triangle_sq(p, d, row, row + 3, row + 6)
        if x < best[0] * best[0]:
            best[0] = sqrt(x)
            if best[0] <= enough:
                return best[0]
            if best[0] < near[0]:
                near[0] = best[0]
    return -1.0


cdef double scan(const Grid* m, const double* p, const double* d, double best, double limit,
                 double enough) noexcept nogil:
    """The least of ``best`` and the distances from the segment p + s d to the triangles within
    min(best, limit) of it (the blocks, cells and triangles out of that reach skipped); the first
    distance found at or below ``enough`` ends the search."""
    cdef int64_t lo[3]
    cdef int64_t hi[3]
    cdef int64_t bi, bj, bl, ci, cj, cl, cell
    cdef Py_ssize_t ax
    cdef double c[3]
    cdef double x, reach, found, dd = dot(d, d), h = m.h
    cdef double near = best if best < limit else limit
    cdef double half_diag = 0.5 * sqrt(3.0) * h, block_half_diag = BLOCK * half_diag
    for ax in range(3):  # (a triangle within near has its centroid within near + its radius)
        x = p[ax] + (d[ax] if d[ax] < 0.0 else 0.0)
        lo[ax] = axis_cell(x - near - m.reach, m.o[ax], h, m.n[ax])
        x = p[ax] + (d[ax] if d[ax] > 0.0 else 0.0)
        hi[ax] = axis_cell(x + near + m.reach, m.o[ax], h, m.n[ax])
    for bi in range(lo[0] // BLOCK, hi[0] // BLOCK + 1):
        for bj in range(lo[1] // BLOCK, hi[1] // BLOCK + 1):
            for bl in range(lo[2] // BLOCK, hi[2] // BLOCK + 1):
                x = m.blocks[(bi * m.nb[1] + bj) * m.nb[2] + bl]
                if x < 0.0:
                    continue
                c[0] = m.o[0] + (bi + 0.5) * BLOCK * h
                c[1] = m.o[1] + (bj + 0.5) * BLOCK * h
                c[2] = m.o[2] + (bl + 0.5) * BLOCK * h
                reach = near + block_half_diag + x
                if centre_sq(c, p, d, dd) >= reach * reach:
                    continue
                for ci in range(max(lo[0], bi * BLOCK), min(hi[0], bi * BLOCK + BLOCK - 1) + 1):
                    for cj in range(max(lo[1], bj * BLOCK), min(hi[1], bj * BLOCK + BLOCK - 1) + 1):
                        for cl in range(max(lo[2], bl * BLOCK), min(hi[2], bl * BLOCK + BLOCK - 1) + 1):
                            cell = (ci * m.n[1] + cj) * m.n[2] + cl
                            if m.start[cell] == m.start[cell + 1]:
                                continue
                            # the cell's centre from the segment: beyond the reach, the cell's half
                            # diagonal and its triangles' largest radius, nothing in it is nearer
                            c[0] = m.o[0] + (ci + 0.5) * h
                            c[1] = m.o[1] + (cj + 0.5) * h
                            c[2] = m.o[2] + (cl + 0.5) * h
                            reach = near + half_diag + m.cell_reach[cell]
                            if centre_sq(c, p, d, dd) >= reach * reach:
                                continue
                            found = cell_scan(m, cell, p, d, dd, &best, &near, enough)
                            if found >= 0.0:
                                return found
    return best


def segment_distances(const double[:, ::1] tri, const int64_t[::1] start, const float[::1] cell_reach,
                      const double[::1] blocks, double tri_reach, const double[::1] origin, double h,
                      const int64_t[::1] dims, const double[:, ::1] p0, const double[:, ::1] p1, const double[::1] cutoff,
                      const double[::1] reach, const double[::1] enough, double[::1] out):
    """out[i] = min(distance from segment p0[i]-p1[i] to the mesh, cutoff[i]) (module docstring).
    tri, start, cell_reach, blocks: the grid's arrays (``fill_grid``) over cells of size h from
    origin, dims cells per axis; tri_reach: the largest radius of any triangle. The search reaches out reach[i] (at least h) from the segment, then
    h, 2h, 4h ... farther, until it finds a triangle within its reach (the nearest then: any nearer
    one lies within the reach too) or the reach passes the cutoff; it reaches no farther than the
    previous segment's distance plus the most either end moved since (an upper bound, slightly
    raised for rounding). A distance found at or below enough[i] is returned at once (a bound from
    above: the segment comes at least that close)."""
    cdef Py_ssize_t n = p0.shape[0], i, ax
    cdef double d[3]
    cdef double best, limit, grow, hint, move, x, y, prev = INFINITY
    cdef Grid m
    cdef int64_t k
    if tri.shape[0] == 0:
        out[:] = cutoff
        return
    m.tri, m.start, m.cell_reach, m.blocks = &tri[0, 0], &start[0], &cell_reach[0], &blocks[0]
    m.reach, m.h = tri_reach, h
    for k in range(3):
        m.o[k], m.n[k], m.nb[k] = origin[k], dims[k], (dims[k] + BLOCK - 1) // BLOCK
    with nogil:
        for i in range(n):
            for ax in range(3):
                d[ax] = p1[i, ax] - p0[i, ax]
            hint = INFINITY
            if prev < INFINITY:
                x = y = 0.0
                for ax in range(3):
                    move = p0[i, ax] - p0[i - 1, ax]
                    x += move * move
                    move = p1[i, ax] - p1[i - 1, ax]
                    y += move * move
                hint = (prev + sqrt(max(x, y))) * (1.0 + 1e-12) + 1e-12
            best = cutoff[i]
            limit = reach[i] if reach[i] > h else h
            grow = h
            if hint < limit + grow:  # (one search to the bound instead of one short of it, then another)
                limit = hint
            while True:
                best = scan(&m, &p0[i, 0], d, best, limit, enough[i])
                if best <= limit or best <= enough[i] or limit >= cutoff[i]:
                    break
                x = limit + grow
                if limit < hint < x:
                    x = hint
                limit = x
                grow *= 2.0
            out[i] = best
            prev = best if best < cutoff[i] else INFINITY
