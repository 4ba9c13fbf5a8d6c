# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""verify's table reader: the rows of a plan folder's CSV table parsed by one compiled loop.

Each cell is '-'? digits ('.' digits)?, or a lowercase word of the ``words`` table (a region name,
read as its code). A number with d decimals is read as the integer m of its digits divided by 10**d:
both are exact doubles, so the quotient is the double nearest to the decimal, the same one strtod
gives, and the same one ``rint(v * 10**d) / 10**d`` gives for the value v the writer formatted
(core.output.csvio.as_written): the in-memory rows a plan verifies before writing are bit-identical
to what this reader makes of the file. Written independently of the writer (core.output._csvformat).
"""

from libc.stdint cimport uint64_t
from libc.string cimport memcmp

import numpy as np

cdef double POW10[19]
POW10[0] = 1.0
for _k in range(1, 19):
    POW10[_k] = POW10[_k - 1] * 10.0

#: the most digits a cell may hold (every integer below 10**18 is exact in a uint64)
DEF MAX_DIGITS = 18
DEF MAX_WORDS = 16
DEF MAX_WORD = 16


cdef Py_ssize_t parse(const unsigned char* s, Py_ssize_t n, double* out, Py_ssize_t rows, int ncols,
                      const unsigned char* words, const Py_ssize_t* lengths, const double* codes,
                      int nwords) noexcept nogil:
    """Parse ``rows`` rows of ``ncols`` cells from s[0:n] into out (row-major); -1 when all parsed,
    else the row (0-based) where a cell or the row's shape is not as the module docstring says."""
    cdef Py_ssize_t i = 0, r, start, length
    cdef int j, w, digits, decimals, dot, neg
    cdef uint64_t m
    cdef unsigned char ch
    for r in range(rows):
        for j in range(ncols):
            if i >= n:
                return r
            if 97 <= s[i] <= 122:  # a word
                start = i
                while i < n and 97 <= s[i] <= 122:
                    i += 1
                length = i - start
                w = 0
                while w < nwords and not (lengths[w] == length and
                                          memcmp(s + start, words + w * MAX_WORD, length) == 0):
                    w += 1
                if w == nwords:
                    return r
                out[r * ncols + j] = codes[w]
            else:
                neg = 0
                if s[i] == 45:
                    neg = 1
                    i += 1
                m = 0
                digits = decimals = dot = 0
                while i < n:
                    ch = s[i]
                    if 48 <= ch <= 57:
                        m = m * 10 + (ch - 48)
                        digits += 1
                        decimals += dot
                    elif ch == 46 and not dot:
                        dot = 1
                    else:
                        break
                    i += 1
                if digits == 0 or digits > MAX_DIGITS or (dot and decimals == 0):
                    return r
                out[r * ncols + j] = (-(<double>m) if neg else <double>m) / POW10[decimals]
            if i >= n or s[i] != (10 if j == ncols - 1 else 44):
                return r
            i += 1
    return -1 if i == n else rows


def parse_rows(const unsigned char[::1] body, int ncols, dict words):
    """(rows (n, ncols) float64, bad): the rows of a table's body (the text after its header line,
    each row ending in '\\n'), bad = -1 when every row parsed, else the 0-based row that did not (the
    caller's general parser then names the line and the cause). ``words``: {bytes: code} for the
    cells that are words (at most 16 words of at most 16 letters)."""
    cdef Py_ssize_t n = body.shape[0], rows = 0, i, bad
    cdef unsigned char table[MAX_WORDS * MAX_WORD]
    cdef Py_ssize_t lengths[MAX_WORDS]
    cdef double codes[MAX_WORDS]
    cdef int nwords = 0
    if len(words) > MAX_WORDS:
        raise ValueError(f"at most {MAX_WORDS} words")
    for word, code in words.items():
        if not 0 < len(word) <= MAX_WORD:
            raise ValueError(f"a word of 1 to {MAX_WORD} letters, not {word!r}")
        for i in range(len(word)):
            table[nwords * MAX_WORD + i] = word[i]
        lengths[nwords] = len(word)
        codes[nwords] = code
        nwords += 1
    cdef const unsigned char* s = &body[0] if n else NULL
    with nogil:
        for i in range(n):
            rows += s[i] == 10
    out = np.empty((rows, ncols), dtype=np.float64)
    cdef double[:, ::1] view = out
    if rows == 0:
        return out, (-1 if n == 0 else 0)
    with nogil:
        bad = parse(s, n, &view[0, 0], rows, ncols, table, lengths, codes, nwords)
    return out, bad
