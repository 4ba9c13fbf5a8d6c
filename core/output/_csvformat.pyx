# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The CSV rows of a block of columns, formatted by one compiled loop (core.output.csvio).

Each number is written in fixed point: v * 10**decimals rounded half to even (the same double
product and rounding as numpy's ``rint``) to an integer m, then '-' when m < 0, the digits of |m|
with at least one before the decimal point, and the point before the last ``decimals`` digits; no
padding, no exponent. The loop releases the GIL: the two sides' tables are formatted in two threads.
"""

from libc.math cimport rint, fabs
from libc.stdint cimport int64_t, uint64_t
from libc.stdlib cimport malloc, free
from libc.string cimport memcpy
from cpython.bytes cimport PyBytes_FromStringAndSize, PyBytes_AS_STRING

import numpy as np

cdef enum:
    FLOAT = 0
    INTEGER = 1
    NAMES = 2

#: the largest |v * 10**decimals| written: every integer up to it is a double, and an int64
DEF LIMIT = 9007199254740992.0  # 2**53

cdef char DIGITS2[200]
for _k in range(100):
    DIGITS2[2 * _k] = 48 + _k // 10
    DIGITS2[2 * _k + 1] = 48 + _k % 10


cdef struct Column:
    int kind
    const double* f          # FLOAT: the values (stride in elements)
    const int64_t* i         # INTEGER and NAMES: the values, or the codes into the names
    Py_ssize_t stride
    int decimals
    double scale             # 10.0 ** decimals
    const char* names        # NAMES: the names one after the other
    const Py_ssize_t* starts  # NAMES: (len + 1,) where each name starts in ``names``
    Py_ssize_t count         # NAMES: how many names


cdef inline Py_ssize_t put_number(char* out, uint64_t mag, bint neg, int decimals) noexcept nogil:
    """Write -?digits(.digits) of the integer ``mag`` with ``decimals`` decimals; the bytes written."""
    cdef char tmp[24]
    cdef Py_ssize_t n = 0, k, at = 0
    cdef uint64_t q
    while mag >= 100:
        q = mag // 100
        k = <Py_ssize_t>(mag - q * 100)
        tmp[23 - n] = DIGITS2[2 * k + 1]
        tmp[22 - n] = DIGITS2[2 * k]
        n += 2
        mag = q
    if mag >= 10:
        tmp[23 - n] = DIGITS2[2 * mag + 1]
        tmp[22 - n] = DIGITS2[2 * mag]
        n += 2
    else:
        tmp[23 - n] = <char>(48 + mag)
        n += 1
    while n < decimals + 1:  # (leading zeros: at least one digit before the point)
        tmp[23 - n] = 48
        n += 1
    if neg:
        out[0] = 45
        at = 1
    k = n - decimals
    memcpy(out + at, tmp + 24 - n, k)
    at += k
    if decimals:
        out[at] = 46
        memcpy(out + at + 1, tmp + 24 - decimals, decimals)
        at += decimals + 1
    return at


cdef Py_ssize_t format_block(Column* cols, int ncols, Py_ssize_t n, char* out, int64_t* ends,
                             Py_ssize_t* bad) noexcept nogil:
    """Rows 0..n-1 into ``out``; the end of each row in ``ends``; -1 (and the row in ``bad``) for a
    number beyond LIMIT or not finite, -2 for a code outside the names."""
    cdef Py_ssize_t r, at = 0, length
    cdef int j
    cdef double x
    cdef int64_t v
    cdef Column* c
    for r in range(n):
        for j in range(ncols):
            c = &cols[j]
            if c.kind == FLOAT:
                x = rint(c.f[r * c.stride] * c.scale)
                if not fabs(x) < LIMIT:  # (NaN too)
                    bad[0] = r
                    return -1
                v = <int64_t>x
                at += put_number(out + at, <uint64_t>(-v if v < 0 else v), v < 0, c.decimals)
            elif c.kind == INTEGER:
                v = c.i[r * c.stride]
                if not (-<int64_t>LIMIT < v < <int64_t>LIMIT):
                    bad[0] = r
                    return -1
                at += put_number(out + at, <uint64_t>(-v if v < 0 else v), v < 0, 0)
            else:
                v = c.i[r * c.stride]
                if v < 0 or v >= c.count:
                    bad[0] = r
                    return -2
                length = c.starts[v + 1] - c.starts[v]
                memcpy(out + at, c.names + c.starts[v], length)
                at += length
            out[at] = 10 if j == ncols - 1 else 44
            at += 1
        ends[r] = at
    return at


def format_rows(list columns, Py_ssize_t n):
    """(bytes, row ends (n,) int64) of n CSV rows. ``columns``: one tuple per column,
    ('f', float64 array, decimals), ('i', int64 array, 0) or ('c', int64 codes, names: a list of bytes);
    each array of length n, any stride. ValueError naming the row for a number that cannot be written
    (not finite, or beyond 2**53 once scaled) or a code outside the names."""
    cdef int ncols = len(columns), j
    cdef Column* cols = <Column*>malloc(max(ncols, 1) * sizeof(Column))
    cdef Py_ssize_t width = 0, used, bad = -1, k
    cdef double[:] fview
    cdef int64_t[:] iview
    cdef Py_ssize_t[:] starts
    cdef char* buf
    cdef int64_t[:] ends_view
    keep = []  # (the arrays and names the pointers point into)
    if cols == NULL:
        raise MemoryError()
    try:
        for j in range(ncols):
            kind, values, extra = columns[j]
            if kind == "f":
                fview = values
                if fview.shape[0] != n:
                    raise ValueError("columns of different lengths")
                keep.append(fview)
                cols[j].kind = FLOAT
                cols[j].f = &fview[0] if n else NULL
                cols[j].stride = fview.strides[0] // sizeof(double)
                cols[j].decimals = extra
                cols[j].scale = 10.0 ** extra
                if not 0 <= extra <= 15:
                    raise ValueError(f"{extra} decimals: 0 to 15 are written")
                width += 19 + extra
            else:
                iview = values
                if iview.shape[0] != n:
                    raise ValueError("columns of different lengths")
                keep.append(iview)
                cols[j].i = &iview[0] if n else NULL
                cols[j].stride = iview.strides[0] // sizeof(int64_t)
                cols[j].decimals = 0
                if kind == "i":
                    cols[j].kind = INTEGER
                    width += 18
                else:
                    cols[j].kind = NAMES
                    joined = b"".join(extra)
                    bounds = np.zeros(len(extra) + 1, dtype=np.intp)
                    bounds[1:] = np.cumsum([len(s) for s in extra])
                    starts = bounds
                    keep += [joined, starts]
                    cols[j].names = joined
                    cols[j].starts = &starts[0]
                    cols[j].count = len(extra)
                    width += max([len(s) for s in extra] or [0])
            width += 1
        ends = np.empty(n, dtype=np.int64)
        ends_view = ends
        buf = <char*>malloc(max(n * width, 1))
        if buf == NULL:
            raise MemoryError()
        try:
            with nogil:
                used = format_block(cols, ncols, n, buf, &ends_view[0] if n else NULL, &bad)
            if used == -1:
                raise ValueError(f"row {bad}: a number that cannot be written (not finite, or too large)")
            if used == -2:
                raise ValueError(f"row {bad}: a code outside the names")
            return PyBytes_FromStringAndSize(buf, used), ends
        finally:
            free(buf)
    finally:
        free(cols)
