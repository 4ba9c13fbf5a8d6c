"""The common time column of both cutters (the machine clock's rows, core.machine.timing) and its safety
figures."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.schedule.motion import Samples
from core.schedule.safety import capsule_clearance, tip_spacing, unsafe_samples
from core.util.parallel import both, worth_threads


@dataclass(frozen=True)
class Timeline:
    """t : (n,) ms; left, right : Samples on t."""

    t: np.ndarray
    left: Samples
    right: Samples


@dataclass(frozen=True)
class SafetyProfile:
    """The safety figures of a time column: tip spacing at the rows (n,) and its minimum between them
    (n-1,) (core.schedule.safety.tip_spacing), and the two tool capsules' clearance at the rows (n,),
    mm; ``unsafe`` (n,) bool marks the rows that break the safety rule (core.schedule.safety)."""

    at: np.ndarray
    between: np.ndarray
    clearance: np.ndarray
    unsafe: np.ndarray

    @classmethod
    def of(cls, tl: Timeline, tool_radius: float, stick_out: float, h_safe: float) -> SafetyProfile:
        """The figures of ``tl`` for a tool (mm), the spacing and the clearance in two threads."""
        (at, between), clear = both(
            lambda: tip_spacing(tl.left.tips, tl.right.tips),
            lambda: capsule_clearance(tl.left.tips, tl.left.axes, tl.right.tips, tl.right.axes, tool_radius,
                                      stick_out), parallel=worth_threads(len(tl.t)))
        return cls(at, between, clear, unsafe_samples(at, between, clear, h_safe))
