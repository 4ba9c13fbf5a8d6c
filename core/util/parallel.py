"""The two cutters' work side by side: one thread per side.

Most of the per-side work (sampling the moves, inverse kinematics, smoothing the tool axes, checking
the axis limits) is numpy operations on long arrays, which release the GIL; two threads then use the
machine's two cores (a forked process would have to send the results back: hundreds of MB).
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")
U = TypeVar("U")

SIDES = ("left", "right")

#: columns shorter than this are done side after side: starting two threads costs more than it saves
MIN_PARALLEL_ROWS = 20000
#: rows per block where work over a whole time column goes a block at a time (core.schedule.safety,
#: core.schedule.movetable, core.machine.tables): each block's temporaries are a few MB that the
#: allocator hands back for the next block, instead of fresh arrays of the whole column
ROW_BLOCK = 1 << 16


def worth_threads(rows: int) -> bool:
    """Whether work over ``rows`` rows per side is long enough for one thread per side."""
    return rows >= MIN_PARALLEL_ROWS


def per_side(fn: Callable[[str], T], parallel: bool = True) -> dict[str, T]:
    """{side: fn(side)} for the left and right sides, the two in parallel threads unless
    ``parallel`` is False (short work, where starting threads costs more than it saves). An exception
    in either is raised here, after both have finished."""
    if not parallel:
        return {side: fn(side) for side in SIDES}
    with ThreadPoolExecutor(2, thread_name_prefix="bladecam-side") as pool:
        futures = {side: pool.submit(fn, side) for side in SIDES}
        return {side: f.result() for side, f in futures.items()}


def both(first: Callable[[], T], second: Callable[[], U], parallel: bool = True) -> tuple[T, U]:
    """(first(), second()), the two in parallel threads unless ``parallel`` is False (as per_side)."""
    if not parallel:
        return first(), second()
    with ThreadPoolExecutor(2, thread_name_prefix="bladecam-both") as pool:
        a, b = pool.submit(first), pool.submit(second)
        return a.result(), b.result()


def blocks(n: int, fn: Callable[[int], None], parallel: bool = True, size: int = ROW_BLOCK) -> None:
    """fn(lo) for lo = 0, size, 2 size, ... < n: the first half of the blocks in one thread and the
    second half in another (unless ``parallel`` is False or there is one block). fn writes its own
    block's slice of the outputs, so the order does not matter."""
    starts = list(range(0, n, size))
    if not parallel or len(starts) < 2:
        for lo in starts:
            fn(lo)
        return
    half = len(starts) // 2

    def run(part):
        for lo in part:
            fn(lo)

    both(lambda: run(starts[:half]), lambda: run(starts[half:]))
