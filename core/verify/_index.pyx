# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The build of verify's distance index (core.verify.distance.DistanceIndex, which documents the
index; core.verify._distance answers the queries), compiled: the triangles' extents, their order
(a counting sort by cell, then by quarter-cell), their plain form (a, b - a, c - a: the corners the
distances measure are a and a plus each edge) and oriented boxes in that order, the groups' and blocks' boxes, the cells' boxes, and the coarse field (the cells a triangle's
box overlaps, and their exact Euclidean distance transform: Felzenszwalb and Huttenlocher, Distance
Transforms of Sampled Functions, 2012). Every loop runs without the GIL: the index can be built in a
thread while the caller reads its tables. Nothing here is shared with the planner.
"""

from libc.math cimport sqrt, floor, fabs, INFINITY
from libc.stdint cimport int32_t, int64_t, uint8_t
from libc.stdlib cimport malloc, free


cdef inline double dot(const double* u, const double* v) noexcept nogil:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


cdef void make_box(const double* pts, int npts, const double* c, const double* n, const double* u,
                   float* out) noexcept nogil:
    """The oriented box of axes u, v = n x u, n (unit) round the points pts (npts, 3) mm, about the
    middle of their extents, in float32 (centre and axes rounded first, the half extents measured
    from the rounded ones and rounded up): out (16,) = centre, u, v, n, half extents, half diagonal."""
    cdef double e[3][3]
    cdef double cr[3]
    cdef double q[3]
    cdef double lo, hi, x
    cdef int k, a, j
    for a in range(3):
        e[0][a] = u[a]
        e[2][a] = n[a]
    e[1][0] = n[1] * u[2] - n[2] * u[1]
    e[1][1] = n[2] * u[0] - n[0] * u[2]
    e[1][2] = n[0] * u[1] - n[1] * u[0]
    for k in range(3):  # the centre: the middle of the extents along each axis
        lo = 1e300
        hi = -1e300
        for j in range(npts):
            x = (pts[3 * j] - c[0]) * e[k][0] + (pts[3 * j + 1] - c[1]) * e[k][1] + (pts[3 * j + 2] - c[2]) * e[k][2]
            lo = x if x < lo else lo
            hi = x if x > hi else hi
        q[k] = 0.5 * (lo + hi)
    for a in range(3):
        out[a] = <float>(c[a] + q[0] * e[0][a] + q[1] * e[1][a] + q[2] * e[2][a])
        for k in range(3):
            out[3 + 3 * k + a] = <float>e[k][a]
    for a in range(3):
        cr[a] = out[a]
    for k in range(3):
        hi = 0.0
        for j in range(npts):
            x = fabs((pts[3 * j] - cr[0]) * out[3 + 3 * k] + (pts[3 * j + 1] - cr[1]) * out[4 + 3 * k]
                     + (pts[3 * j + 2] - cr[2]) * out[5 + 3 * k])
            hi = x if x > hi else hi
        out[12 + k] = <float>(hi * (1.0 + 1e-6) + 1e-6)  # (float32 rounds to within 6e-8 of it)
    x = sqrt(<double>out[12] * out[12] + <double>out[13] * out[13] + <double>out[14] * out[14])
    out[15] = <float>(x * (1.0 + 1e-6) + 1e-6)  # (the half diagonal: every point within it of the centre)


cdef void unit_normal(const double* t, double* n) noexcept nogil:
    """The unit normal of the triangle t = (a, ab, ac); (0, 0, 1) for a degenerate one (any axis
    holds it: its box takes the height)."""
    cdef double x
    n[0] = t[4] * t[8] - t[5] * t[7]
    n[1] = t[5] * t[6] - t[3] * t[8]
    n[2] = t[3] * t[7] - t[4] * t[6]
    x = sqrt(dot(n, n))
    if x > 0.0:
        n[0] /= x; n[1] /= x; n[2] /= x
    else:
        n[0] = 0.0; n[1] = 0.0; n[2] = 1.0


cdef void long_edge(const double* t, const double* n, double* u) noexcept nogil:
    """A unit in-plane direction along the triangle's longest edge (any one square to n for a point)."""
    cdef double e[3][3]
    cdef double best = -1.0, x
    cdef int k, a
    for a in range(3):
        e[0][a] = t[3 + a]
        e[1][a] = t[6 + a] - t[3 + a]
        e[2][a] = t[6 + a]
    for k in range(3):
        x = dot(e[k], e[k])
        if x > best:
            best = x
            u[0] = e[k][0]; u[1] = e[k][1]; u[2] = e[k][2]
    x = dot(u, n)
    u[0] -= x * n[0]; u[1] -= x * n[1]; u[2] -= x * n[2]
    x = sqrt(dot(u, u))
    if x > 0.0:
        u[0] /= x; u[1] /= x; u[2] /= x
    else:  # (a point: any direction square to n)
        if fabs(n[0]) < 0.9:
            u[0] = 0.0; u[1] = n[2]; u[2] = -n[1]
        else:
            u[0] = -n[2]; u[1] = 0.0; u[2] = n[0]
        x = sqrt(dot(u, u))
        u[0] /= x; u[1] /= x; u[2] /= x


def build_triangles(const double[:, ::1] v, const int64_t[:, ::1] tris, const int64_t[::1] order,
                    double[:, ::1] tri, float[:, ::1] tbox):
    """In the index's order (triangle order[s] the s-th): tri (T, 9) = a, b - a, c - a mm, and tbox
    (T, 16) the oriented boxes (axes along the longest edge, across it in the plane, and the normal)
    of the triangles tris (T, 3) (indices into the vertices v (V, 3) mm)."""
    cdef Py_ssize_t s, t, n = order.shape[0]
    cdef double pts[9]
    cdef double nrm[3]
    cdef double u[3]
    cdef double c[3]
    cdef int a
    with nogil:
        for s in range(n):
            t = order[s]
            for a in range(3):
                tri[s, a] = v[tris[t, 0], a]
                tri[s, 3 + a] = v[tris[t, 1], a] - tri[s, a]
                tri[s, 6 + a] = v[tris[t, 2], a] - tri[s, a]
            corner_points(tri, s, s + 1, pts)
            for a in range(3):
                c[a] = (pts[a] + pts[3 + a] + pts[6 + a]) / 3.0
            unit_normal(&tri[s, 0], nrm)
            long_edge(&tri[s, 0], nrm, u)
            make_box(pts, 3, c, nrm, u, &tbox[s, 0])


cdef inline void corner_points(const double[:, ::1] tri, Py_ssize_t t0, Py_ssize_t t1, double* pts) noexcept nogil:
    """pts (3 (t1 - t0), 3) mm: the corners a, a + (b - a), a + (c - a) of the triangles t0..t1 - 1 of
    tri (the points the distances measure)."""
    cdef Py_ssize_t t
    cdef int a
    for t in range(t0, t1):
        for a in range(3):
            pts[9 * (t - t0) + a] = tri[t, a]
            pts[9 * (t - t0) + 3 + a] = tri[t, a] + tri[t, 3 + a]
            pts[9 * (t - t0) + 6 + a] = tri[t, a] + tri[t, 6 + a]


def build_groups(const double[:, ::1] tri, const int32_t[::1] gfirst, float[:, ::1] gbox):
    """gbox (G, 16): the oriented box of each group of triangles gfirst[g]..gfirst[g + 1] of tri (a
    group, or a block of groups): its normal the area-weighted mean of its triangles' (turned to agree
    with its first triangle's: a group may hold both sides of a thin edge, whose box then grows in
    height), its first axis its first triangle's long edge made square to it."""
    cdef Py_ssize_t g, ng = gfirst.shape[0] - 1, most = 1
    cdef int32_t t, t0
    cdef double nrm[3]
    cdef double tn[3]
    cdef double u[3]
    cdef double c[3]
    cdef double x
    cdef int a
    cdef double* pts
    for g in range(ng):
        most = max(most, gfirst[g + 1] - gfirst[g])
    pts = <double*>malloc(9 * most * sizeof(double))
    if pts == NULL:
        raise MemoryError()
    with nogil:
        for g in range(ng):
            t0 = gfirst[g]
            corner_points(tri, t0, gfirst[g + 1], pts)
            for a in range(3):
                nrm[a] = 0.0
                c[a] = 0.0
            unit_normal(&tri[t0, 0], u)  # (the first triangle's normal, for the signs)
            for t in range(t0, gfirst[g + 1]):
                tn[0] = tri[t, 4] * tri[t, 8] - tri[t, 5] * tri[t, 7]
                tn[1] = tri[t, 5] * tri[t, 6] - tri[t, 3] * tri[t, 8]
                tn[2] = tri[t, 3] * tri[t, 7] - tri[t, 4] * tri[t, 6]
                x = -1.0 if dot(tn, u) < 0.0 else 1.0
                for a in range(3):
                    nrm[a] += x * tn[a]
                    c[a] += pts[9 * (t - t0) + a] + pts[9 * (t - t0) + 3 + a] + pts[9 * (t - t0) + 6 + a]
            for a in range(3):
                c[a] /= 3.0 * (gfirst[g + 1] - t0)
            x = sqrt(dot(nrm, nrm))
            if x > 0.0:
                nrm[0] /= x; nrm[1] /= x; nrm[2] /= x
            else:
                nrm[0] = 0.0; nrm[1] = 0.0; nrm[2] = 1.0
            long_edge(&tri[t0, 0], nrm, u)
            make_box(pts, 3 * (gfirst[g + 1] - t0), c, nrm, u, &gbox[g, 0])
    free(pts)


def extents(const double[:, ::1] v, const int64_t[:, ::1] tris, double[::1] extent, double[::1] lo,
            double[::1] hi):
    """extent (T,) mm: each triangle's largest extent along x, y or z; lo, hi (3,) mm: the box of all
    of them. IndexError where a triangle names a vertex that is not there (nothing is read then)."""
    cdef Py_ssize_t t, n = tris.shape[0], nv = v.shape[0]
    cdef int k, a
    cdef double x, a_lo, a_hi, big
    cdef int64_t bad = -1
    with nogil:
        for t in range(n):
            for k in range(3):
                if tris[t, k] < 0 or tris[t, k] >= nv:
                    bad = t
        if bad < 0:
            for a in range(3):
                lo[a] = INFINITY
                hi[a] = -INFINITY
            for t in range(n):
                big = 0.0
                for a in range(3):
                    a_lo = a_hi = v[tris[t, 0], a]
                    for k in range(1, 3):
                        x = v[tris[t, k], a]
                        a_lo = x if x < a_lo else a_lo
                        a_hi = x if x > a_hi else a_hi
                    big = a_hi - a_lo if a_hi - a_lo > big else big
                    lo[a] = a_lo if a_lo < lo[a] else lo[a]
                    hi[a] = a_hi if a_hi > hi[a] else hi[a]
                extent[t] = big
    if bad >= 0:
        raise IndexError(f"triangle {bad} names a vertex outside 0..{nv - 1}")


def cell_order(const double[:, ::1] v, const int64_t[:, ::1] tris, const double[::1] origin, double h,
               const int64_t[::1] dims, int64_t[::1] order, int64_t[::1] key):
    """The triangles tris (T, 3) in order of their centroids' cells (the cell (i, j, k) of the grid
    of cells h mm from ``origin``, dims (3,) cells, has key (i dims[1] + j) dims[2] + k), within a
    cell by quarter-cell (the centroid's quarter-cell index along x, then y, then z: 64 of them), ties
    in the order given (a counting sort, by quarter-cell and then, stably, by cell): order (T,) the
    triangles, key (T,) their cells' keys in that order (non-decreasing)."""
    cdef Py_ssize_t t, n = tris.shape[0]
    cdef int64_t ncells = dims[0] * dims[1] * dims[2], j, total, x
    cdef int64_t q[3]
    cdef int a, k, sub
    cdef double c
    cdef int64_t* cell = <int64_t*>malloc(max(n, 1) * sizeof(int64_t))
    cdef uint8_t* quarter = <uint8_t*>malloc(max(n, 1))
    cdef int64_t* first = <int64_t*>malloc((ncells + 1) * sizeof(int64_t))
    cdef int64_t* by_sub = <int64_t*>malloc(max(n, 1) * sizeof(int64_t))
    cdef int64_t start[65]
    if cell == NULL or quarter == NULL or first == NULL or by_sub == NULL:
        free(cell); free(quarter); free(first); free(by_sub)
        raise MemoryError()
    with nogil:
        for t in range(n):
            for a in range(3):
                c = (v[tris[t, 0], a] + v[tris[t, 1], a] + v[tris[t, 2], a]) / 3.0
                c = floor((c - origin[a]) * (4.0 / h))
                x = 4 * dims[a] - 1
                q[a] = 0 if c < 0.0 else (x if c > x else <int64_t>c)
            cell[t] = ((q[0] >> 2) * dims[1] + (q[1] >> 2)) * dims[2] + (q[2] >> 2)
            quarter[t] = <uint8_t>((q[0] & 3) * 16 + (q[1] & 3) * 4 + (q[2] & 3))
        for sub in range(65):
            start[sub] = 0
        for t in range(n):
            start[quarter[t] + 1] += 1
        for sub in range(64):
            start[sub + 1] += start[sub]
        for t in range(n):
            by_sub[start[quarter[t]]] = t
            start[quarter[t]] += 1
        for j in range(ncells + 1):
            first[j] = 0
        for t in range(n):
            first[cell[t] + 1] += 1
        for j in range(ncells):
            first[j + 1] += first[j]
        for j in range(n):
            t = by_sub[j]
            order[first[cell[t]]] = t
            key[first[cell[t]]] = cell[t]
            first[cell[t]] += 1
    free(cell); free(quarter); free(first); free(by_sub)


def cell_boxes(const double[:, ::1] tri, const int64_t[::1] first, double[:, ::1] cbox):
    """cbox (S, 6) mm: lo(3), hi(3) of the corners of each occupied cell's triangles (tri (T, 9) = a,
    b - a, c - a), first[s] to first[s + 1] (S + 1,)."""
    cdef Py_ssize_t s, t, ns = first.shape[0] - 1
    cdef int a, k
    cdef double x
    cdef double pts[9]
    with nogil:
        for s in range(ns):
            for a in range(3):
                cbox[s, a] = INFINITY
                cbox[s, 3 + a] = -INFINITY
            for t in range(first[s], first[s + 1]):
                corner_points(tri, t, t + 1, pts)
                for k in range(3):
                    for a in range(3):
                        x = pts[3 * k + a]
                        if x < cbox[s, a]:
                            cbox[s, a] = x
                        if x > cbox[s, 3 + a]:
                            cbox[s, 3 + a] = x


def mark_cells(const double[:, ::1] tri, const double[::1] origin, double h, uint8_t[:, :, ::1] occupied):
    """occupied[i, j, k] = 1 for every cell (of the grid of cells h mm from ``origin``, which holds
    every corner) that the box of a triangle's corners overlaps (tri (T, 9) = a, b - a, c - a mm)."""
    cdef Py_ssize_t t, n = tri.shape[0]
    cdef int lo[3]
    cdef int hi[3]
    cdef int a, k, i, j, l
    cdef double x0, x1, x
    cdef double pts[9]
    with nogil:
        for t in range(n):
            corner_points(tri, t, t + 1, pts)
            for a in range(3):
                x0 = x1 = pts[a]
                for k in range(1, 3):
                    x = pts[3 * k + a]
                    x0 = x if x < x0 else x0
                    x1 = x if x > x1 else x1
                lo[a] = <int>floor((x0 - origin[a]) / h)
                hi[a] = <int>floor((x1 - origin[a]) / h)
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for l in range(lo[2], hi[2] + 1):
                        occupied[i, j, l] = 1


cdef void envelope(double* f, Py_ssize_t n, Py_ssize_t step, double* g, int* v, double* z) noexcept nogil:
    """In place along the line f[0], f[step], ..., f[(n - 1) step]: f[q] = min over p of (q - p)^2 +
    f[p] (the lower envelope of the parabolas of the finite f[p]; all infinite: left so). g (n,),
    v (n,), z (n + 1,): scratch."""
    cdef Py_ssize_t q, p, k = -1
    cdef double s
    for q in range(n):
        g[q] = f[q * step]
    for q in range(n):
        if g[q] == INFINITY:
            continue
        if k < 0:
            k = 0
            v[0] = q
            z[0] = -INFINITY
            z[1] = INFINITY
            continue
        p = v[k]
        s = ((g[q] + <double>q * q) - (g[p] + <double>p * p)) / (2.0 * (q - p))
        while s <= z[k]:  # (z[0] = -inf: never below the first parabola)
            k -= 1
            p = v[k]
            s = ((g[q] + <double>q * q) - (g[p] + <double>p * p)) / (2.0 * (q - p))
        k += 1
        v[k] = q
        z[k] = s
        z[k + 1] = INFINITY
    if k < 0:
        return
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        p = v[k]
        f[q * step] = (<double>q - p) * (q - p) + g[p]


def distance_field(const uint8_t[:, :, ::1] occupied, double h, float[:, :, ::1] field):
    """field (nx, ny, nz) mm: per cell, a lower bound of the distance from any of its points to
    anything in an occupied cell: the exact distance from its centre to the nearest occupied cell's
    centre (the squared Euclidean distance transform, one axis after the other: Felzenszwalb and
    Huttenlocher), less the cell's diagonal, shrunk by 1e-6 of itself and 1e-6 mm (float32 rounds to
    within 6e-8 of it), at least 0; inf where no cell is occupied."""
    cdef Py_ssize_t nx = occupied.shape[0], ny = occupied.shape[1], nz = occupied.shape[2]
    cdef Py_ssize_t i, j, k, big = max(nx, ny, nz), cells = nx * ny * nz
    cdef double diagonal = h * sqrt(3.0), x
    cdef double* d2 = <double*>malloc(max(cells, 1) * sizeof(double))
    cdef double* g = <double*>malloc(big * sizeof(double))
    cdef double* z = <double*>malloc((big + 1) * sizeof(double))
    cdef int* v = <int*>malloc(big * sizeof(int))
    if d2 == NULL or g == NULL or z == NULL or v == NULL:
        free(d2); free(g); free(z); free(v)
        raise MemoryError()
    with nogil:
        for i in range(nx):
            for j in range(ny):
                for k in range(nz):
                    d2[(i * ny + j) * nz + k] = 0.0 if occupied[i, j, k] else INFINITY
        for i in range(nx):
            for j in range(ny):
                envelope(d2 + (i * ny + j) * nz, nz, 1, g, v, z)
        for i in range(nx):
            for k in range(nz):
                envelope(d2 + i * ny * nz + k, ny, nz, g, v, z)
        for j in range(ny):
            for k in range(nz):
                envelope(d2 + j * nz + k, nx, ny * nz, g, v, z)
        for i in range(nx):
            for j in range(ny):
                for k in range(nz):
                    x = (h * sqrt(d2[(i * ny + j) * nz + k]) - diagonal) * (1.0 - 1e-6) - 1e-6
                    field[i, j, k] = <float>(x if x > 0.0 else 0.0)
    free(d2); free(g); free(z); free(v)


def total_area(const double[:, ::1] tri):
    """mm^2: the area of the triangles tri (T, 9) = a, b - a, c - a, mm: the sum of |ab x ac| / 2."""
    cdef Py_ssize_t t, n = tri.shape[0]
    cdef double x, y, z, total = 0.0
    with nogil:
        for t in range(n):
            x = tri[t, 4] * tri[t, 8] - tri[t, 5] * tri[t, 7]
            y = tri[t, 5] * tri[t, 6] - tri[t, 3] * tri[t, 8]
            z = tri[t, 3] * tri[t, 7] - tri[t, 4] * tri[t, 6]
            total += sqrt(x * x + y * y + z * z)
    return 0.5 * total
