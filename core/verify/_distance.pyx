# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""verify's own distances from points and segments to the blade's triangles, compiled (the index's
arrays are built by core.verify._index and core.verify.distance, which documents the index; nothing
here is shared with the planner).

The triangles lie in cells of a uniform grid (each in the cell of its centroid), stored column by
column (one x, y index) in order of z; within a cell, in groups of up to 8 triangles near each other,
the groups in blocks of up to 8. Every block, group and triangle carries an oriented bounding box
(centre c, unit axes e_k: u, v and n, half extents a_k, and its half diagonal): a point p is at least
sqrt(sum_k max(|(p - c).e_k| - a_k, 0)^2) from anything in it; a segment at least the larger of that
sum with each axis' term at its least over the segment (the three least separately: a lower bound
still) and its distance from c less the half diagonal. Thin triangles (the slivers of a closing tip)
have thin boxes. The boxes are kept in float32, each made to hold its points as rounded
(``make_box``), the bounds shrunk by 1e-6 of themselves for the rounded axes.
A query:
- takes as a first upper bound the exact distance of the group of the triangle nearest to the
  previous query (``hint``: queries along a path are close, so it usually holds the answer);
- when none of those lies within the query's cutoff, asks the coarse field first (a lower bound per
  cell: core.verify.distance) and stops where it already lies beyond the cutoff;
- otherwise visits the columns and cells that can hold a point nearer than the best so far, keeps
  the groups whose box is nearer (of the blocks whose box is), and searches them nearest box first,
  leaving the rest once their boxes are no nearer than the best; within a group, a triangle whose box
  is no nearer is skipped, the rest measured exactly: a point to a triangle by the closest point's
  region (Ericson, Real-Time Collision Detection, 5.1.5), a segment to a triangle as 0 where it
  crosses it, else the least of its two ends to the triangle and of it to the three edges (segment
  to segment, Ericson 5.1.9): the closest pair of a segment and a triangle that do not meet has an
  end of the segment or an edge of the triangle in it.
The result is exact (to rounding) wherever it is at most the cutoff, and a lower bound above it.
The sweeps along rows (``step_rows``) measure few rows and bound the rest. Every loop runs without
the GIL: the two sides are measured in two threads.
"""

from libc.math cimport sqrt, floor, fabs, atan2
from libc.stdint cimport int32_t, int64_t, uint8_t
from libc.stdlib cimport malloc, free


cdef struct Mesh:
    const double* tri      # (T, 9): a, b - a, c - a
    const float* tbox      # (T, 16): the triangle's box c(3), u(3), v(3), n(3), half extents(3), 0
    const float* gbox      # (G, 16): the group's box
    const int32_t* gfirst  # (G + 1): first triangle of each group
    const int32_t* tgroup  # (T,): the group of each triangle
    const double* cbox     # (S, 6): box of each occupied cell's triangles, lo(3), hi(3)
    const float* bbox      # (B, 16): the box of each block of up to 8 groups of one cell
    const int32_t* bfirst  # (B + 1): first group of each block
    const int32_t* cfirst  # (S + 1): first block of each occupied cell
    const int32_t* ciz     # (S,): z index of each occupied cell
    const int32_t* colfirst  # (nx ny + 1): first occupied cell of each column
    const float* field     # (nx, ny, nz): lower bound of the distance from the cell to the mesh
    double o[3]
    double h
    int n[3]
    double ext             # how far a cell's box of triangles reaches beyond the cell


cdef inline double dot(const double* u, const double* v) noexcept nogil:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


cdef inline double lesser(double a, double b) noexcept nogil:
    return a if a < b else b


cdef inline double greater(double a, double b) noexcept nogil:
    return a if a > b else b


cdef inline double clamp01(double x) noexcept nogil:
    return 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)


cdef inline int cell(const Mesh* m, double x, int k) noexcept nogil:
    """The index along axis k of the cell holding coordinate x, clamped to the grid (in floating point
    first: x may be far outside)."""
    cdef double f = floor((x - m.o[k]) / m.h)
    if f < 0.0:
        return 0
    if f > m.n[k] - 1:
        return m.n[k] - 1
    return <int>f


cdef double point_triangle2(const double* p, const double* t) noexcept nogil:
    """Squared distance from p to the triangle t = (a, ab, ac) (Ericson 5.1.5's regions in order)."""
    cdef const double* ab = t + 3
    cdef const double* ac = t + 6
    cdef double ap[3]
    cdef double g[3]
    cdef double d1, d2, d3, d4, d5, d6, va, vb, vc, v, w, s
    ap[0] = p[0] - t[0]; ap[1] = p[1] - t[1]; ap[2] = p[2] - t[2]
    d1 = dot(ab, ap); d2 = dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return dot(ap, ap)                         # corner a
    cdef double e01 = dot(ab, ac)
    d3 = d1 - dot(ab, ab); d4 = d2 - e01           # (p - b).ab, (p - b).ac
    if d3 >= 0.0 and d4 <= d3:
        v = 1.0; w = 0.0                           # corner b
    else:
        vc = d1 * d4 - d3 * d2
        d5 = d1 - e01; d6 = d2 - dot(ac, ac)       # (p - c).ab, (p - c).ac
        if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            v = d1 / (d1 - d3); w = 0.0            # edge ab
        elif d6 >= 0.0 and d5 <= d6:
            v = 0.0; w = 1.0                       # corner c
        else:
            vb = d5 * d2 - d1 * d6
            va = d3 * d6 - d5 * d4
            if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
                v = 0.0; w = d2 / (d2 - d6)        # edge ac
            elif va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
                w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); v = 1.0 - w   # edge bc
            else:
                s = va + vb + vc
                if s == 0.0:                       # (a degenerate triangle: its corner a)
                    return dot(ap, ap)
                v = vb / s; w = vc / s             # inside
    g[0] = ap[0] - v * ab[0] - w * ac[0]
    g[1] = ap[1] - v * ab[1] - w * ac[1]
    g[2] = ap[2] - v * ab[2] - w * ac[2]
    return dot(g, g)


cdef double segment_segment2(const double* p, const double* d, const double* q, const double* e) noexcept nogil:
    """Squared distance between the segments p + s d and q + u e, s, u in [0, 1] (Ericson 5.1.9)."""
    cdef double r[3]
    cdef double g[3]
    cdef double a, c, b, f, ee, den, s, u
    r[0] = p[0] - q[0]; r[1] = p[1] - q[1]; r[2] = p[2] - q[2]
    a = dot(d, d); ee = dot(e, e); f = dot(e, r)
    if a <= 1e-300 and ee <= 1e-300:
        return dot(r, r)
    if a <= 1e-300:
        s = 0.0; u = clamp01(f / ee)
    else:
        c = dot(d, r)
        if ee <= 1e-300:
            u = 0.0; s = clamp01(-c / a)
        else:
            b = dot(d, e)
            den = a * ee - b * b
            s = clamp01((b * f - c * ee) / den) if den > 1e-14 * a * ee else 0.0
            u = (b * s + f) / ee
            if u < 0.0:
                u = 0.0; s = clamp01(-c / a)
            elif u > 1.0:
                u = 1.0; s = clamp01((b - c) / a)
    g[0] = r[0] + s * d[0] - u * e[0]
    g[1] = r[1] + s * d[1] - u * e[1]
    g[2] = r[2] + s * d[2] - u * e[2]
    return dot(g, g)


cdef bint crosses(const double* p, const double* d, const double* t) noexcept nogil:
    """Whether the segment p + s d, s in [0, 1], meets the triangle t (Moller-Trumbore); a segment in
    the triangle's plane is left to its ends and the edges."""
    cdef const double* ab = t + 3
    cdef const double* ac = t + 6
    cdef double hv[3]
    cdef double sv[3]
    cdef double qv[3]
    cdef double det, inv, u, v, s
    hv[0] = d[1] * ac[2] - d[2] * ac[1]
    hv[1] = d[2] * ac[0] - d[0] * ac[2]
    hv[2] = d[0] * ac[1] - d[1] * ac[0]
    det = dot(ab, hv)
    if fabs(det) < 1e-300:
        return False
    inv = 1.0 / det
    sv[0] = p[0] - t[0]; sv[1] = p[1] - t[1]; sv[2] = p[2] - t[2]
    u = inv * dot(sv, hv)
    if u < 0.0 or u > 1.0:
        return False
    qv[0] = sv[1] * ab[2] - sv[2] * ab[1]
    qv[1] = sv[2] * ab[0] - sv[0] * ab[2]
    qv[2] = sv[0] * ab[1] - sv[1] * ab[0]
    v = inv * dot(d, qv)
    if v < 0.0 or u + v > 1.0:
        return False
    s = inv * dot(ac, qv)
    return 0.0 <= s <= 1.0


cdef double segment_triangle2(const double* p, const double* d, bint point, const double* t) noexcept nogil:
    """Squared distance from the segment p + s d (a point where ``point``) to the triangle t. A segment
    wholly on one side of the triangle's plane is at least its nearer end's height h from it; where
    that end's own distance is h (it lies over the triangle), that is the answer."""
    cdef double q[3]
    cdef double b[3]
    cdef double bc[3]
    cdef double nv[3]
    cdef double best, x, h0, h1, nn
    if point:
        return point_triangle2(p, t)
    q[0] = p[0] + d[0]; q[1] = p[1] + d[1]; q[2] = p[2] + d[2]
    nv[0] = t[4] * t[8] - t[5] * t[7]
    nv[1] = t[5] * t[6] - t[3] * t[8]
    nv[2] = t[3] * t[7] - t[4] * t[6]
    nn = dot(nv, nv)
    if nn > 0.0:
        h0 = (p[0] - t[0]) * nv[0] + (p[1] - t[1]) * nv[1] + (p[2] - t[2]) * nv[2]
        h1 = h0 + dot(d, nv)
        if h0 * h1 > 0.0:
            if fabs(h0) <= fabs(h1):
                x = point_triangle2(p, t)
            else:
                x = point_triangle2(q, t)
                h0 = h1
            if x <= h0 * h0 / nn * (1.0 + 1e-12):
                return x
    if crosses(p, d, t):
        return 0.0
    best = point_triangle2(p, t)
    x = point_triangle2(q, t)
    if x < best: best = x
    x = segment_segment2(p, d, t, t + 3)
    if x < best: best = x
    x = segment_segment2(p, d, t, t + 6)
    if x < best: best = x
    b[0] = t[0] + t[3]; b[1] = t[1] + t[4]; b[2] = t[2] + t[5]
    bc[0] = t[6] - t[3]; bc[1] = t[7] - t[4]; bc[2] = t[8] - t[5]
    x = segment_segment2(p, d, b, bc)
    if x < best: best = x
    return best


cdef inline double pos(double x) noexcept nogil:
    return x if x > 0.0 else 0.0


cdef inline double box_point2(const float* b, const double* p) noexcept nogil:
    """Squared distance from the point p to the oriented box b (less its float32 slack: a bound)."""
    cdef double ux = p[0] - b[0], uy = p[1] - b[1], uz = p[2] - b[2]
    cdef double g0 = pos(fabs(ux * b[3] + uy * b[4] + uz * b[5]) - b[12])
    cdef double g1 = pos(fabs(ux * b[6] + uy * b[7] + uz * b[8]) - b[13])
    cdef double g2 = pos(fabs(ux * b[9] + uy * b[10] + uz * b[11]) - b[14])
    return (g0 * g0 + g1 * g1 + g2 * g2) * (1.0 - 1e-6)  # (float32 axes: unit and square to 1e-7)


cdef inline double oriented_bound2(const float* b, const double* p, const double* d, bint point) noexcept nogil:
    """Squared lower bound of the distance from the segment p + s d (a point where ``point``) to
    anything in the oriented box b (module docstring): for a point, its distance from the box; for a
    segment, the larger of the sum over the axes of each one's least |x| - half over the segment
    (x = (p + s d - c).e_k, linear in s) and the segment's distance from the box's centre less its
    half diagonal (b[15]; the axes' terms reach their least at different points of a slanted
    segment)."""
    if point:
        return box_point2(b, p)
    cdef double ux = p[0] - b[0], uy = p[1] - b[1], uz = p[2] - b[2]
    cdef double x0 = ux * b[3] + uy * b[4] + uz * b[5]
    cdef double x1 = ux * b[6] + uy * b[7] + uz * b[8]
    cdef double x2 = ux * b[9] + uy * b[10] + uz * b[11]
    cdef double y0, y1, y2, g0, g1, g2, dd, t, sphere
    y0 = x0 + d[0] * b[3] + d[1] * b[4] + d[2] * b[5]
    y1 = x1 + d[0] * b[6] + d[1] * b[7] + d[2] * b[8]
    y2 = x2 + d[0] * b[9] + d[1] * b[10] + d[2] * b[11]
    g0 = pos(lesser(x0, y0) - b[12]) + pos(-b[12] - greater(x0, y0))
    g1 = pos(lesser(x1, y1) - b[13]) + pos(-b[13] - greater(x1, y1))
    g2 = pos(lesser(x2, y2) - b[14]) + pos(-b[14] - greater(x2, y2))
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    t = clamp01(-(ux * d[0] + uy * d[1] + uz * d[2]) / dd) if dd > 0.0 else 0.0
    ux += t * d[0]; uy += t * d[1]; uz += t * d[2]
    sphere = pos(sqrt(ux * ux + uy * uy + uz * uz) - b[15])
    return greater(g0 * g0 + g1 * g1 + g2 * g2, sphere * sphere) * (1.0 - 1e-6)


cdef inline double box_bound2(const double* box, const double* lo, const double* hi) noexcept nogil:
    """Squared gap between a box (lo(3), hi(3)) and the box lo..hi of a segment (a lower bound of the
    distance between anything in them)."""
    cdef double g, s = 0.0
    cdef int k
    for k in range(3):
        g = box[k] - hi[k]
        if g < lo[k] - box[3 + k]:
            g = lo[k] - box[3 + k]
        if g > 0.0:
            s += g * g
    return s


cdef double field_point(const Mesh* m, const double* p) noexcept nogil:
    """Lower bound of the distance from p to the mesh: the field of its cell, and outside the grid,
    sqrt(|p - q|^2 + field(q)^2) for q the nearest point of the grid (which holds the whole mesh: the
    angle at q between p and any point of the mesh is at least a right angle)."""
    cdef double off = 0.0, x, q
    cdef int k
    cdef int idx[3]
    for k in range(3):
        q = p[k]
        if q < m.o[k]:
            q = m.o[k]
        elif q > m.o[k] + m.n[k] * m.h:
            q = m.o[k] + m.n[k] * m.h
        off += (p[k] - q) * (p[k] - q)
        idx[k] = <int>floor((q - m.o[k]) / m.h)
        if idx[k] < 0:
            idx[k] = 0
        elif idx[k] >= m.n[k]:
            idx[k] = m.n[k] - 1
    x = m.field[(<long>idx[0] * m.n[1] + idx[1]) * m.n[2] + idx[2]]
    return sqrt(off + x * x)


cdef double field_segment(const Mesh* m, const double* p, const double* d) noexcept nogil:
    """Lower bound of the distance from the segment p + s d to the mesh: the least field_point at
    points at most h apart along it, less half their spacing."""
    cdef double length = sqrt(dot(d, d)), best = 1e300, x, f
    cdef int k, steps = <int>(length / m.h) + 1
    cdef double q[3]
    if length == 0.0:
        return field_point(m, p)
    for k in range(steps + 1):
        f = <double>k / steps
        q[0] = p[0] + f * d[0]; q[1] = p[1] + f * d[1]; q[2] = p[2] + f * d[2]
        x = field_point(m, q)
        if x < best:
            best = x
    best -= 0.5 * length / steps
    return best if best > 0.0 else 0.0


cdef bint column_span(const Mesh* m, int ix, int iy, const double* p, const double* d, double r,
                      double* zlo, double* zhi) noexcept nogil:
    """Whether the segment p + s d comes within r (per axis) of column (ix, iy)'s cells, and the z
    range its points that do span (zlo, zhi, widened by r)."""
    cdef double s0 = 0.0, s1 = 1.0, lo, hi, a, b, t0, t1
    cdef int k
    for k in range(2):
        lo = m.o[k] + (ix if k == 0 else iy) * m.h - r
        hi = lo + m.h + 2.0 * r
        if fabs(d[k]) < 1e-300:
            if p[k] < lo or p[k] > hi:
                return False
            continue
        t0 = (lo - p[k]) / d[k]
        t1 = (hi - p[k]) / d[k]
        if t0 > t1:
            t0, t1 = t1, t0
        if t0 > s0: s0 = t0
        if t1 < s1: s1 = t1
        if s0 > s1:
            return False
    a = p[2] + s0 * d[2]
    b = p[2] + s1 * d[2]
    zlo[0] = (a if a < b else b) - r
    zhi[0] = (b if a < b else a) + r
    return True


DEF HEAP = 2048


cdef struct Heap:
    int n
    double key[HEAP]
    int32_t item[HEAP]


cdef inline void heap_push(Heap* q, double key, int32_t item) noexcept nogil:
    cdef int i = q.n, up
    q.n += 1
    while i > 0:
        up = (i - 1) >> 1
        if q.key[up] <= key:
            break
        q.key[i] = q.key[up]
        q.item[i] = q.item[up]
        i = up
    q.key[i] = key
    q.item[i] = item


cdef inline int32_t heap_pop(Heap* q, double* key) noexcept nogil:
    """The item of least key (its key in key[0]); the heap must not be empty."""
    cdef int32_t top = q.item[0]
    cdef double last_key
    cdef int32_t last_item
    cdef int i = 0, child
    key[0] = q.key[0]
    q.n -= 1
    last_key = q.key[q.n]
    last_item = q.item[q.n]
    while True:
        child = 2 * i + 1
        if child >= q.n:
            break
        if child + 1 < q.n and q.key[child + 1] < q.key[child]:
            child += 1
        if q.key[child] >= last_key:
            break
        q.key[i] = q.key[child]
        q.item[i] = q.item[child]
        i = child
    q.key[i] = last_key
    q.item[i] = last_item
    return top


cdef inline double group_search(const Mesh* m, int32_t g, const double* p, const double* d, bint point,
                                double best2, int32_t* found) noexcept nogil:
    """The least squared distance of the group's triangles below best2 (best2 where none is), the
    triangle in found[0]."""
    cdef int32_t t
    cdef double e2
    for t in range(m.gfirst[g], m.gfirst[g + 1]):
        if oriented_bound2(m.tbox + 16 * <long>t, p, d, point) >= best2:
            continue
        e2 = segment_triangle2(p, d, point, m.tri + 9 * <long>t)
        if e2 < best2:
            best2 = e2
            found[0] = t
    return best2


cdef void collect(const Mesh* m, const double* p, const double* d, bint point, int32_t skip, Heap* heap,
                  double* best2, int32_t* found) noexcept nogil:
    """Push onto ``heap`` every group (but ``skip``) whose box lies nearer than sqrt(best2) to the
    segment p + s d, keyed by its squared bound; where the heap is full, search the group at once
    (best2, found: the best so far, updated)."""
    cdef double r = sqrt(best2[0]) + m.ext, zlo, zhi, key, gx, gy
    cdef double lo[3]
    cdef double hi[3]
    cdef int32_t s, b, g
    cdef int k, ix, iy, ix0, ix1, iy0, iy1, iz0 = 0, iz1 = 0, col
    for k in range(3):
        lo[k] = p[k] if d[k] >= 0.0 else p[k] + d[k]
        hi[k] = p[k] + d[k] if d[k] >= 0.0 else p[k]
    ix0 = cell(m, lo[0] - r, 0)
    ix1 = cell(m, hi[0] + r, 0)
    iy0 = cell(m, lo[1] - r, 1)
    iy1 = cell(m, hi[1] + r, 1)
    if point:  # (a point: one z range for every column, and only the columns within r of it)
        iz0 = cell(m, p[2] - r, 2)
        iz1 = cell(m, p[2] + r, 2)
    for ix in range(ix0, ix1 + 1):
        gx = pos(greater(m.o[0] + ix * m.h - p[0], p[0] - m.o[0] - (ix + 1) * m.h))
        for iy in range(iy0, iy1 + 1):
            if point:
                gy = pos(greater(m.o[1] + iy * m.h - p[1], p[1] - m.o[1] - (iy + 1) * m.h))
                if gx * gx + gy * gy > r * r:
                    continue
            else:
                if not column_span(m, ix, iy, p, d, r, &zlo, &zhi):
                    continue
                iz0 = cell(m, zlo, 2)
                iz1 = cell(m, zhi, 2)
            col = ix * m.n[1] + iy
            for s in range(m.colfirst[col], m.colfirst[col + 1]):
                if m.ciz[s] < iz0:
                    continue
                if m.ciz[s] > iz1:
                    break
                if box_bound2(m.cbox + 6 * <long>s, lo, hi) >= best2[0]:
                    continue
                for b in range(m.cfirst[s], m.cfirst[s + 1]):
                    if oriented_bound2(m.bbox + 16 * <long>b, p, d, point) >= best2[0]:
                        continue
                    for g in range(m.bfirst[b], m.bfirst[b + 1]):
                        key = oriented_bound2(m.gbox + 16 * <long>g, p, d, point)
                        if key >= best2[0] or g == skip:
                            continue
                        if heap.n < HEAP:
                            heap_push(heap, key, g)
                        else:
                            best2[0] = group_search(m, g, p, d, point, best2[0], found)


cdef double nearest(const Mesh* m, const double* p, const double* d, double cutoff, int32_t* hint,
                    Heap* heap) noexcept nogil:
    """Distance from the segment p + s d (a point where d = 0) to the mesh: exact where at most
    ``cutoff``, else a lower bound above it (module docstring). ``hint``: a triangle near the last
    query (-1: none), replaced by the nearest found; ``heap``: scratch."""
    cdef bint point = d[0] == 0.0 and d[1] == 0.0 and d[2] == 0.0
    cdef double limit = cutoff * (1.0 + 1e-12) + 1e-12
    cdef double best2 = limit * limit, f, key
    cdef int32_t found = -1, g, hg = -1
    if hint[0] >= 0:  # the last nearest triangle's group first: a tight start
        hg = m.tgroup[hint[0]]
        best2 = group_search(m, hg, p, d, point, best2, &found)
    if found < 0:
        f = field_segment(m, p, d) if not point else field_point(m, p)
        if f >= limit:
            return f
    heap.n = 0
    collect(m, p, d, point, hg, heap, &best2, &found)
    while heap.n > 0:
        g = heap_pop(heap, &key)
        if key >= best2:
            break
        best2 = group_search(m, g, p, d, point, best2, &found)
    if found < 0:
        return limit
    hint[0] = found
    return sqrt(best2)


cdef class Kernel:
    """The index's arrays (built by core.verify.distance.DistanceIndex) behind the compiled queries."""

    cdef Mesh m
    cdef object arrays

    def __init__(self, const double[:, ::1] tri, const float[:, ::1] tbox, const float[:, ::1] gbox,
                 const int32_t[::1] gfirst, const int32_t[::1] tgroup, const float[:, ::1] bbox,
                 const int32_t[::1] bfirst, const double[:, ::1] cbox, const int32_t[::1] cfirst, const int32_t[::1] ciz, const int32_t[::1] colfirst,
                 const float[:, :, ::1] field, const double[::1] origin, double h, double ext):
        cdef int k
        self.arrays = (tri, tbox, gbox, gfirst, tgroup, bbox, bfirst, cbox, cfirst, ciz, colfirst, field)
        self.m.bbox = &bbox[0, 0]
        self.m.bfirst = &bfirst[0]
        self.m.tri = &tri[0, 0]
        self.m.tbox = &tbox[0, 0]
        self.m.gbox = &gbox[0, 0]
        self.m.gfirst = &gfirst[0]
        self.m.tgroup = &tgroup[0]
        self.m.cbox = &cbox[0, 0]
        self.m.cfirst = &cfirst[0]
        self.m.ciz = &ciz[0]
        self.m.colfirst = &colfirst[0]
        self.m.field = &field[0, 0, 0]
        for k in range(3):
            self.m.o[k] = origin[k]
            self.m.n[k] = field.shape[k]
        self.m.h = h
        self.m.ext = ext

    def distances(self, const double[:, ::1] p0, const double[:, ::1] p1, const double[::1] cutoff,
                  double[::1] out):
        """out (n,) mm: the distance of each segment p0-p1 (n, 3) mm (a point where p0 = p1) from the
        mesh, exact where at most cutoff (n,) mm, else a lower bound above it. The queries are taken
        in order, each starting from the nearest triangle of the one before (put neighbours together)."""
        cdef Py_ssize_t i, n = p0.shape[0]
        cdef int32_t hint = -1
        cdef double d[3]
        cdef Heap* heap = <Heap*>malloc(sizeof(Heap))
        if heap == NULL:
            raise MemoryError()
        try:
            with nogil:
                for i in range(n):
                    d[0] = p1[i, 0] - p0[i, 0]; d[1] = p1[i, 1] - p0[i, 1]; d[2] = p1[i, 2] - p0[i, 2]
                    out[i] = nearest(&self.m, &p0[i, 0], d, cutoff[i], &hint, heap)
        finally:
            free(heap)

    def field_bounds(self, const double[:, ::1] p0, const double[:, ::1] p1, double[::1] out):
        """out (n,) mm: the coarse field's lower bound of each segment's distance from the mesh."""
        cdef Py_ssize_t i, n = p0.shape[0]
        cdef double d[3]
        with nogil:
            for i in range(n):
                d[0] = p1[i, 0] - p0[i, 0]; d[1] = p1[i, 1] - p0[i, 1]; d[2] = p1[i, 2] - p0[i, 2]
                out[i] = field_segment(&self.m, &p0[i, 0], d)

    def sweep(self, const double[:, ::1] c, const double[:, ::1] w, double s0, double s1, double radius,
              const double[::1] reach, double exact, double cap, double tolerance, double[::1] out,
              uint8_t[::1] measured):
        """One part (the capsule of radius ``radius`` round c + s w, s0 <= s <= s1) along the rows:
        out (n,) mm its clearance from the mesh at each row (exact where measured and at most
        ``exact``), measured[i] = 1 where measured (``step_rows``)."""
        cdef Probe pr
        pr.kind = 0
        pr.m = &self.m
        pr.c = &c[0, 0]
        pr.w = &w[0, 0]
        pr.s0 = s0
        pr.s1 = s1
        pr.radius = radius
        pr.exact = exact
        pr.hint = -1
        pr.heap = <Heap*>malloc(sizeof(Heap))
        if pr.heap == NULL:
            raise MemoryError()
        try:
            with nogil:
                step_rows(&pr, reach, cap, tolerance, out, measured)
        finally:
            free(pr.heap)


#: the least share of the values measured either side a far stretch's bounds keep (``step_rows``)
cdef double KEEP = 0.5


cdef struct Probe:
    int kind            # 0: a part against the mesh, 1: two parts (the two sides), 2: a part against a box
    const Mesh* m
    const double* c     # (n, 3) ball centres, mm
    const double* w     # (n, 3) unit axes
    double s0, s1, radius
    const double* c2    # the other side's (kind 1)
    const double* w2
    double t0, t1, radius2
    double lo[3]        # the box (kind 2)
    double hi[3]
    double exact
    int32_t hint
    Heap* heap


cdef double probe(Probe* pr, Py_ssize_t i) noexcept nogil:
    """The clearance of row i (mm): the part's capsule from the mesh (exact up to pr.exact), from the
    other side's part's capsule, or from the box (exact)."""
    cdef double p[3]
    cdef double d[3]
    cdef double q[3]
    cdef double e[3]
    cdef int a
    for a in range(3):
        p[a] = pr.c[3 * i + a] + pr.s0 * pr.w[3 * i + a]
        d[a] = (pr.s1 - pr.s0) * pr.w[3 * i + a]
    if pr.kind == 0:
        return nearest(pr.m, p, d, pr.radius + pr.exact, &pr.hint, pr.heap) - pr.radius
    if pr.kind == 1:
        for a in range(3):
            q[a] = pr.c2[3 * i + a] + pr.t0 * pr.w2[3 * i + a]
            e[a] = (pr.t1 - pr.t0) * pr.w2[3 * i + a]
        return sqrt(segment_segment2(p, d, q, e)) - pr.radius - pr.radius2
    return box_segment(p, d, pr.lo, pr.hi) - pr.radius


cdef void step_rows(Probe* pr, const double[::1] reach, double cap, double tolerance, double[::1] out,
                    uint8_t[::1] measured) noexcept nogil:
    """A clearance along n rows from few measurements (rows, mm): from a measured row a of value v, the
    next row measured is the first b whose motion since a (reach, cumulative, mm) exceeds 2 (v -
    floor); every row between is then at least max(v_a - M(a, k), v_b - M(k, b)), and where that is
    below the floor the row halfway is measured and both halves looked at again. The floor: the least
    value measured so far or ``cap``, the lesser, but not below -tolerance. So every value is a lower
    bound, a row that collides is measured, and the least is exact where below cap. Where the values
    either side exceed twice the cap, the floor is at least KEEP of them: far parts keep bounds that
    say how far they are."""
    cdef Py_ssize_t n = reach.shape[0], a = 0, b, k, lo, hi, mid
    cdef Py_ssize_t stack[128]
    cdef int top
    cdef double least, floor_, x
    if n == 0:
        return
    out[0] = probe(pr, 0)
    measured[0] = 1
    least = out[0]
    while a < n - 1:
        floor_ = greater(lesser(least, cap), -tolerance)
        if out[a] > 2.0 * cap:
            floor_ = greater(floor_, KEEP * out[a])
        x = reach[a] + 2.0 * (out[a] - floor_)
        b = a + 1
        while b < n - 1 and reach[b + 1] <= x:  # (a guess: the next row as clear as this one)
            b += 1
        out[b] = probe(pr, b)
        measured[b] = 1
        least = lesser(least, out[b])
        top = 0
        stack[0] = a
        stack[1] = b
        top = 2
        while top > 0:  # the stretches a..b to look at: bound the rows in them, or halve them
            hi = stack[top - 1]
            lo = stack[top - 2]
            top -= 2
            floor_ = greater(lesser(least, cap), -tolerance)
            if lesser(out[lo], out[hi]) > 2.0 * cap:  # (far: no bound below half the values either side)
                floor_ = greater(floor_, KEEP * lesser(out[lo], out[hi]))
            if hi - lo < 2:
                continue
            if out[lo] + out[hi] - (reach[hi] - reach[lo]) >= 2.0 * floor_ or top >= 124:
                for k in range(lo + 1, hi):
                    out[k] = greater(out[lo] - (reach[k] - reach[lo]), out[hi] - (reach[hi] - reach[k]))
                if out[lo] + out[hi] - (reach[hi] - reach[lo]) >= 2.0 * floor_:
                    continue
                for k in range(lo + 1, hi):  # (the stack is full: these rows measured one by one)
                    if out[k] < floor_:
                        out[k] = probe(pr, k)
                        measured[k] = 1
                        least = lesser(least, out[k])
                continue
            mid = (lo + hi) // 2
            out[mid] = probe(pr, mid)
            measured[mid] = 1
            least = lesser(least, out[mid])
            stack[top] = lo
            stack[top + 1] = mid
            stack[top + 2] = mid
            stack[top + 3] = hi
            top += 4
        a = b


def pair_sweep(const double[:, ::1] c, const double[:, ::1] w, double s0, double s1, double radius,
               const double[:, ::1] c2, const double[:, ::1] w2, tuple other, const double[::1] reach,
               double cap, double tolerance, double[::1] out, uint8_t[::1] measured):
    """Two parts along the rows (one on each side: the capsule of ``radius`` round c + s w, s0 <= s
    <= s1, and ``other`` = (s0, s1, radius) round c2 + s w2): out (n,) mm their clearance, exact in
    closed form where measured (``step_rows``)."""
    cdef Probe pr
    pr.kind = 1
    pr.c = &c[0, 0]
    pr.w = &w[0, 0]
    pr.s0 = s0
    pr.s1 = s1
    pr.radius = radius
    pr.c2 = &c2[0, 0]
    pr.w2 = &w2[0, 0]
    pr.t0, pr.t1, pr.radius2 = other
    with nogil:
        step_rows(&pr, reach, cap, tolerance, out, measured)


def box_sweep(const double[:, ::1] c, const double[:, ::1] w, double s0, double s1, double radius,
              const double[::1] lo, const double[::1] hi, const double[::1] reach, double cap, double tolerance,
              double[::1] out, uint8_t[::1] measured):
    """A part along the rows against the box lo..hi (3,) mm (+-1e300 for a side without a face):
    out (n,) mm its clearance, exact in closed form where measured (``step_rows``)."""
    cdef Probe pr
    cdef int k
    pr.kind = 2
    pr.c = &c[0, 0]
    pr.w = &w[0, 0]
    pr.s0 = s0
    pr.s1 = s1
    pr.radius = radius
    for k in range(3):
        pr.lo[k] = lo[k]
        pr.hi[k] = hi[k]
    with nogil:
        step_rows(&pr, reach, cap, tolerance, out, measured)


def segment_distances(const double[:, ::1] a0, const double[:, ::1] a1, const double[:, ::1] b0,
                      const double[:, ::1] b1, double[::1] out):
    """out (n,) mm: the distance between the segments a0-a1 and b0-b1 (each (n, 3) mm), row by row,
    in closed form (Ericson 5.1.9)."""
    cdef Py_ssize_t i, n = a0.shape[0]
    cdef int k
    cdef double d[3]
    cdef double e[3]
    with nogil:
        for i in range(n):
            for k in range(3):
                d[k] = a1[i, k] - a0[i, k]
                e[k] = b1[i, k] - b0[i, k]
            out[i] = sqrt(segment_segment2(&a0[i, 0], d, &b0[i, 0], e))


cdef double box_segment(const double* p, const double* d, const double* lo, const double* hi) noexcept nogil:
    """Distance from the segment p + s d to the box lo..hi (an infinite bound: +-1e300): the squared
    distance is a convex quadratic between the parameters where a coordinate crosses a face, each
    piece minimised in closed form."""
    cdef double cuts[8]
    cdef int nc = 0, k, a, b
    cdef double x, sa, sb, mid, alpha, beta, num, den, s, best = 1e300, f, v
    cuts[nc] = 0.0; nc += 1
    cuts[nc] = 1.0; nc += 1
    for k in range(3):
        if fabs(d[k]) > 1e-300:
            s = (lo[k] - p[k]) / d[k]
            if 0.0 < s < 1.0:
                cuts[nc] = s; nc += 1
            s = (hi[k] - p[k]) / d[k]
            if 0.0 < s < 1.0:
                cuts[nc] = s; nc += 1
    for a in range(1, nc):  # (insertion sort of at most 8)
        x = cuts[a]
        b = a - 1
        while b >= 0 and cuts[b] > x:
            cuts[b + 1] = cuts[b]
            b -= 1
        cuts[b + 1] = x
    for a in range(nc - 1):
        sa = cuts[a]; sb = cuts[a + 1]
        mid = 0.5 * (sa + sb)
        num = 0.0; den = 0.0
        for k in range(3):  # the faces outside of which the piece lies: gap alpha + beta s
            x = p[k] + mid * d[k]
            if x < lo[k]:
                alpha = lo[k] - p[k]; beta = -d[k]
            elif x > hi[k]:
                alpha = p[k] - hi[k]; beta = d[k]
            else:
                continue
            num += alpha * beta; den += beta * beta
        s = -num / den if den > 0.0 else sa
        s = sa if s < sa else (sb if s > sb else s)
        f = 0.0
        for k in range(3):
            x = p[k] + s * d[k]
            v = lo[k] - x if x < lo[k] else (x - hi[k] if x > hi[k] else 0.0)
            f += v * v
        if f < best:
            best = f
    return sqrt(best)


def box_distances(const double[:, ::1] p0, const double[:, ::1] p1, const double[::1] lo,
                  const double[::1] hi, double[::1] out):
    """out (n,) mm: the distance of each segment p0-p1 (n, 3) mm from the box lo..hi (3,) mm (use
    +-1e300 for a side without a face), exact."""
    cdef Py_ssize_t i, n = p0.shape[0]
    cdef int k
    cdef double d[3]
    with nogil:
        for i in range(n):
            for k in range(3):
                d[k] = p1[i, k] - p0[i, k]
            out[i] = box_segment(&p0[i, 0], d, &lo[0], &hi[0])


def turn_angles(const double[:, ::1] w, double[::1] out):
    """out (n - 1,) rad: the angle between consecutive unit axes w (n, 3) (the arc an axis point at
    unit distance travels when the axis turns from one row to the next along a great circle)."""
    cdef Py_ssize_t i, n = w.shape[0]
    cdef const double* a
    cdef const double* b
    cdef double x[3]
    with nogil:
        for i in range(n - 1):
            a = &w[i, 0]
            b = &w[i + 1, 0]
            x[0] = a[1] * b[2] - a[2] * b[1]
            x[1] = a[2] * b[0] - a[0] * b[2]
            x[2] = a[0] * b[1] - a[1] * b[0]
            out[i] = atan2(sqrt(dot(x, x)), dot(a, b))
