"""core.parallel.per_side: both sides' results, in two threads, errors raised in the caller."""

from __future__ import annotations

import threading

import pytest

from core.errors import MachineError
from core.parallel import per_side


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
