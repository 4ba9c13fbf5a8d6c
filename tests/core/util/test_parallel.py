"""core.util.parallel: per_side gives both sides' results, in two threads, errors raised in the caller;
blocks covers every block once."""

from __future__ import annotations

import threading

import pytest

from core.errors import MachineError
from core.util.parallel import per_side


@pytest.mark.parametrize("parallel", [True, False])
def test_per_side_gives_both_results_and_raises_a_side_error(parallel):
    barrier = threading.Barrier(2, timeout=5) if parallel else None
    names = {}

    def work(side: str) -> str:
        names[side] = threading.current_thread().name
        if barrier is not None:
            barrier.wait()  # both sides run at once (a serial run would time out here)
        return side.upper()

    assert per_side(work, parallel=parallel) == {"left": "LEFT", "right": "RIGHT"}
    assert (names["left"] != names["right"]) == parallel

    def fail(side: str) -> str:
        if side == "right":
            raise MachineError("right: tool axis tilted beyond the head's reach")
        return side

    with pytest.raises(MachineError, match="^right: tool axis tilted"):
        per_side(fail, parallel=parallel)


def test_blocks_and_both_cover_every_block_once_in_either_mode():
    from core.util.parallel import blocks, both

    for n, size in ((0, 4), (1, 4), (4, 4), (5, 4), (17, 4), (100, 7)):
        for parallel in (False, True):
            seen, threads = [], set()

            def fn(lo, seen=seen, threads=threads):
                seen.append(lo)
                threads.add(threading.get_ident())

            blocks(n, fn, parallel=parallel, size=size)
            assert sorted(seen) == list(range(0, n, size)), (n, size, parallel)
            assert len(threads) <= (2 if parallel and n > size else 1)
    assert both(lambda: 1, lambda: 2) == (1, 2) and both(lambda: 1, lambda: 2, parallel=False) == (1, 2)
