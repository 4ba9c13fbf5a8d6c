# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Exact distances from segments (the axes of a tool assembly's parts) to a triangle mesh, through a
uniform grid of cells that lists the triangles whose bounding box overlaps each cell
(core.machine.clearance.MeshGrid builds the grid's geometry and calls these).

A query visits the blocks of cells within reach of its segment, skips a block or cell whose centre lies
farther from the segment than the best distance so far plus its half diagonal, skips a triangle whose
bounding sphere does or whose corners all lie beyond reach along the distance's gradient at its centroid
(the distance from a segment is convex), and measures the rest exactly: the least of the two ends' distances from the triangle,
the segment's from the triangle's three edges, and zero where the segment crosses the triangle (the
closest pair of a segment and a triangle that do not meet has an end of the segment or an edge of
the triangle in it). The loops release the GIL: the two sides are checked in two threads.
"""

from libc.math cimport sqrt, floor, fabs
from libc.stdint cimport int32_t, int64_t, uint8_t

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


def fill_cells(const int64_t[:, ::1] lo, const int64_t[:, ::1] hi, const int64_t[::1] dims):
    """The grid's lists: (start (cells + 1,) int64, triangles int32) such that the triangles whose
    bounding box overlaps cell k (cell index (i * dims[1] + j) * dims[2] + l) are
    triangles[start[k]:start[k + 1]]; lo, hi (m, 3): each triangle's first and last cell per axis."""
    cdef Py_ssize_t m = lo.shape[0], t, i, j, l, k
    cdef int64_t ny = dims[1], nz = dims[2]
    start_arr = np.zeros(dims[0] * ny * nz + 1, np.int64)
    cdef int64_t[::1] start = start_arr
    with nogil:
        for t in range(m):
            for i in range(lo[t, 0], hi[t, 0] + 1):
                for j in range(lo[t, 1], hi[t, 1] + 1):
                    for l in range(lo[t, 2], hi[t, 2] + 1):
                        start[(i * ny + j) * nz + l + 1] += 1
        for k in range(1, start.shape[0]):
            start[k] += start[k - 1]
    tris_arr = np.empty(start[start.shape[0] - 1], np.int32)
    cdef int32_t[::1] tris = tris_arr
    fill_arr = start_arr[:len(start_arr) - 1].copy()
    cdef int64_t[::1] fill = fill_arr
    with nogil:
        for t in range(m):
            for i in range(lo[t, 0], hi[t, 0] + 1):
                for j in range(lo[t, 1], hi[t, 1] + 1):
                    for l in range(lo[t, 2], hi[t, 2] + 1):
                        k = (i * ny + j) * nz + l
                        tris[fill[k]] = <int32_t>t
                        fill[k] += 1
    return start_arr, tris_arr


#: cells per block side: the search skips empty blocks and blocks out of reach whole
DEF BLOCK = 8


cdef double scan(const double[:, ::1] tri, const int64_t[::1] start, const int32_t[::1] cells,
                 const uint8_t[::1] blocks, const double[::1] origin, double h, const int64_t[::1] dims,
                 const double* p, const double* d, double best, double limit, double enough) noexcept nogil:
    """The least of ``best`` and the distances from the segment p + s d to the triangles within
    min(best, limit) of it (the blocks, cells and triangles out of that reach skipped); the first
    distance found at or below ``enough`` ends the search."""
    cdef int64_t lo[3]
    cdef int64_t hi[3]
    cdef int64_t bd[3]
    cdef int64_t bi, bj, bl, ci, cj, cl, cell, k
    cdef Py_ssize_t ax
    cdef double c[3]
    cdef double x, s, g0, g1, g2, ua, uab, uac, reach, dd = dot(d, d), best_sq = best * best
    cdef double near = best if best < limit else limit
    cdef double half_diag = 0.5 * sqrt(3.0) * h, block_half_diag = BLOCK * half_diag
    cdef const double* row
    for ax in range(3):
        x = p[ax] + (d[ax] if d[ax] < 0.0 else 0.0)
        lo[ax] = <int64_t>floor((x - near - origin[ax]) / h)
        x = p[ax] + (d[ax] if d[ax] > 0.0 else 0.0)
        hi[ax] = <int64_t>floor((x + near - origin[ax]) / h)
        if lo[ax] < 0:
            lo[ax] = 0
        if hi[ax] > dims[ax] - 1:
            hi[ax] = dims[ax] - 1
        bd[ax] = (dims[ax] + BLOCK - 1) // BLOCK
    for bi in range(lo[0] // BLOCK, hi[0] // BLOCK + 1):
        for bj in range(lo[1] // BLOCK, hi[1] // BLOCK + 1):
            for bl in range(lo[2] // BLOCK, hi[2] // BLOCK + 1):
                if not blocks[(bi * bd[1] + bj) * bd[2] + bl]:
                    continue
                c[0] = origin[0] + (bi + 0.5) * BLOCK * h - p[0]
                c[1] = origin[1] + (bj + 0.5) * BLOCK * h - p[1]
                c[2] = origin[2] + (bl + 0.5) * BLOCK * h - p[2]
                s = clamp01(dot(c, d) / dd) if dd > 0.0 else 0.0
                g0 = c[0] - s * d[0]; g1 = c[1] - s * d[1]; g2 = c[2] - s * d[2]
                reach = near + block_half_diag
                if g0 * g0 + g1 * g1 + g2 * g2 >= reach * reach:
                    continue
                for ci in range(max(lo[0], bi * BLOCK), min(hi[0], bi * BLOCK + BLOCK - 1) + 1):
                    for cj in range(max(lo[1], bj * BLOCK), min(hi[1], bj * BLOCK + BLOCK - 1) + 1):
                        for cl in range(max(lo[2], bl * BLOCK), min(hi[2], bl * BLOCK + BLOCK - 1) + 1):
                            cell = (ci * dims[1] + cj) * dims[2] + cl
                            if start[cell] == start[cell + 1]:
                                continue
                            # the cell's centre from the segment: beyond the reach and the cell's half
                            # diagonal, nothing in it is nearer
                            c[0] = origin[0] + (ci + 0.5) * h - p[0]
                            c[1] = origin[1] + (cj + 0.5) * h - p[1]
                            c[2] = origin[2] + (cl + 0.5) * h - p[2]
                            s = clamp01(dot(c, d) / dd) if dd > 0.0 else 0.0
                            g0 = c[0] - s * d[0]; g1 = c[1] - s * d[1]; g2 = c[2] - s * d[2]
                            reach = near + half_diag
                            if g0 * g0 + g1 * g1 + g2 * g2 >= reach * reach:
                                continue
                            for k in range(start[cell], start[cell + 1]):
                                row = &tri[cells[k], 0]
                                c[0] = row[9] - p[0]; c[1] = row[10] - p[1]; c[2] = row[11] - p[2]
                                s = clamp01(dot(c, d) / dd) if dd > 0.0 else 0.0
                                g0 = c[0] - s * d[0]; g1 = c[1] - s * d[1]; g2 = c[2] - s * d[2]
                                reach = near + row[12]
                                x = g0 * g0 + g1 * g1 + g2 * g2
                                if x >= reach * reach:
                                    continue
                                # the distance from the segment is convex: at least its value at the
                                # centroid plus its gradient there (g / |g|) times the farthest a corner
                                # lies against it
                                if x > 0.0:
                                    x = sqrt(x)
                                    ua = g0 * (row[0] - row[9]) + g1 * (row[1] - row[10]) + g2 * (row[2] - row[11])
                                    uab = g0 * row[3] + g1 * row[4] + g2 * row[5]
                                    uac = g0 * row[6] + g1 * row[7] + g2 * row[8]
                                    if x + (ua + min(0.0, min(uab, uac))) / x >= near:
                                        continue
                                x = segment_triangle_sq(p, d, row, row + 3, row + 6)
                                if x < best_sq:
                                    best_sq = x
                                    best = sqrt(x)
                                    if best <= enough:
                                        return best
                                    if best < near:
                                        near = best
    return best


def block_cells() -> int:
    """Cells per block side (the grid's ``blocks`` flag each BLOCK^3 cells, the last ones partial)."""
    return BLOCK


def segment_distances(const double[:, ::1] tri, const int64_t[::1] start, const int32_t[::1] cells,
                      const uint8_t[::1] blocks, const double[::1] origin, double h, const int64_t[::1] dims,
                      const double[:, ::1] p0, const double[:, ::1] p1, const double[::1] cutoff,
                      const double[::1] reach, const double[::1] enough, double[::1] out):
    """out[i] = min(distance from segment p0[i]-p1[i] to the mesh, cutoff[i]) (module docstring).
    tri (m, 13): per triangle a, ab, ac, its bounding sphere's centre and radius; start, cells: the
    grid's lists (``fill_cells``) over cells of size h from origin, dims cells per axis; blocks: 1 for
    each block of cells (``block_cells``) that lists a triangle, else 0. The search
    reaches out reach[i] (at least h) from the segment, then h, 2h, 4h ... farther, until it finds a
    triangle within its reach (the nearest then: any nearer one lies within the reach too) or the
    reach passes the cutoff. A distance found at or below enough[i] is returned at once (a bound from
    above: the segment comes at least that close)."""
    cdef Py_ssize_t n = p0.shape[0], i, ax
    cdef double d[3]
    cdef double best, limit, grow
    with nogil:
        for i in range(n):
            for ax in range(3):
                d[ax] = p1[i, ax] - p0[i, ax]
            best = cutoff[i]
            limit = reach[i] if reach[i] > h else h
            grow = h
            while True:
                best = scan(tri, start, cells, blocks, origin, h, dims, &p0[i, 0], d, best, limit, enough[i])
                if best <= limit or best <= enough[i] or limit >= cutoff[i]:
                    break
                limit += grow
                grow *= 2.0
            out[i] = best
