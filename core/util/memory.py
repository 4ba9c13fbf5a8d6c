"""Allocator tuning for big array work (glibc only; elsewhere a no-op).

A plan allocates and frees arrays of tens of megabytes thousands of times (a time column of 600k
rows is 15 MB per (n, 3) array). glibc serves blocks above a sliding threshold with fresh mmap()s
and hands freed heap tops back to the kernel, so each such array is faulted in page by page again:
on the sample plan ~430k page faults, a third of the command line's time in the kernel. Keeping
blocks up to MMAP_THRESHOLD on the heap and not trimming it below ``trim`` bytes lets freed memory
be reused: ~285k faults, 0.3-0.8 s less system time on the sample plan (see docs/DECISIONS.md).
"""

from __future__ import annotations

import ctypes
import ctypes.util

#: blocks up to this size come from the heap (every array of a time column); larger ones (the
#: formatted tables) are still mmapped and go back to the system when freed
MMAP_THRESHOLD = 32 << 20
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3


def tune_allocator(trim: int = 2 << 30) -> bool:
    """Keep blocks up to MMAP_THRESHOLD on the heap and up to ``trim`` bytes of freed heap for reuse
    (the command line: the process ends soon; the workbench passes less). Forked workers inherit it.
    Returns whether the C library accepted both settings."""
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError, TypeError):  # not glibc (musl, macOS, Windows): leave it
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return bool(mallopt(_M_TRIM_THRESHOLD, min(int(trim), 2**31 - 1))) and bool(
        mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD))
