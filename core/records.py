"""The plain records every stage of a plan shares, on core's bottom floor (they import nothing of core
but its exceptions): the planning inputs (``PlanParameters``, resolved once at entry, and ``PlanJob``),
a plan's ``Timings`` and the ``Progress`` callback. Each stage's output record lives with its stage
(core.paths.plan.PathPlan; a whole plan: core.result.PlanResult).

Units at this boundary: mm, mm/min, mm/s^2, ms.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, dataclass, field, replace

from core.errors import Cancelled, PlanningError

#: progress(fraction 0..1, message); returning False cancels the work (core.errors.Cancelled)
Progress = Callable[[float, str], object]


def sub_progress(progress: Progress | None, lo: float, hi: float) -> Progress | None:
    """``progress`` for a part of the work: its fractions 0..1 reported as lo..hi."""
    if progress is None:
        return None
    return lambda f, msg: progress(lo + (hi - lo) * f, msg)


def check_progress(progress: Progress | None, fraction: float, message: str) -> None:
    """Report ``fraction``; Cancelled when ``progress`` returns False."""
    if progress is not None and progress(fraction, message) is False:
        raise Cancelled()


def cancel_at(progress: Progress | None, fraction: float, message: str) -> Callable[[], bool] | None:
    """A ``cancel()`` for work that polls (True: stop), reporting ``fraction`` each time it is asked."""
    if progress is None:
        return None
    return lambda: progress(fraction, message) is False

MODES = ("collaborative", "symmetric", "single")
PROFILES = ("sigmoid", "smooth")

#: machine limits that refuse a plan without --force: strokes, and the axis speeds and accelerations
#: that the machine clock (core.machine.timing) keeps
ENFORCED_LIMITS = ("stroke", "speed", "acceleration")
#: the feed's sane range, mm/min: below 1 mm/min a blade takes years, above 100 m/min no ball-end finishing
FEED_RANGE = (1.0, 100_000.0)
#: a_max's sane range, mm/s^2: below 1 a stop at the feed takes metres, above 100,000 (10 g) no machine
#: follows and the motion laws lose their precision (a stage's duration rounds to nothing)
A_MAX_RANGE = (1.0, 100_000.0)
#: the default minimum cutting feed, a share of the feed (PlanParameters.min_feed)
MIN_FEED_SHARE = 0.3
#: h_safe's sane range in tool radii: below a quarter radius the speed stages that keep it are too short
#: for any acceleration (the planner then fails on a_max), above 10 radii no path is collaborative
H_SAFE_RADII = (0.25, 10.0)


@dataclass(frozen=True)
class PlanParameters:
    """Planning inputs. None means the default derived from the tool radius.

    tool_radius : mm (ball radius; the paper's 3 mm ball nose mill has 1.5); dr : mm (default r/4);
    dd : mm, interpolation step; h_safe : mm (default 1.25 r); k_max : staggered-ratio limit;
    tool_length : mm, d_T of Eq. 1-2 (tip to tail point, the tool's stick-out);
    feed : mm/min; a_max : mm/s^2; mode : 'collaborative' | 'symmetric' | 'single';
    min_feed : mm/min, the slowest a cutting cutter should run (default MIN_FEED_SHARE of the feed; the
    operator sets it from the tool's minimum chip thickness): the plan reports where and why a cutter
    cuts slower (core.machine.job_figures)
    """

    tool_radius: float = 1.5
    dr: float | None = None
    dd: float = 0.2
    h_safe: float | None = None
    k_max: float = 0.15
    tool_length: float = 40.0
    feed: float = 1000.0
    a_max: float = 500.0
    mode: str = "collaborative"
    min_feed: float | None = None

    def resolved(self) -> PlanParameters:
        """The same parameters with the defaults filled in, validated (PlanningError)."""
        r = self.tool_radius
        if not isinstance(r, (int, float)) or not math.isfinite(r) or r <= 0:
            raise PlanningError(f"tool radius must be a positive number of mm, got {r}")
        p = replace(self, dr=r / 4 if self.dr is None else self.dr,
                    h_safe=1.25 * r if self.h_safe is None else self.h_safe)
        if self.min_feed is None and isinstance(self.feed, (int, float)):
            p = replace(p, min_feed=MIN_FEED_SHARE * self.feed)
        labels = {"dr": "dR (mm)", "dd": "dd (mm)", "tool_length": "tool length (mm)",
                  "feed": "feed (mm/min)", "a_max": "a_max (mm/s^2)"}
        for name, label in labels.items():
            v = getattr(p, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise PlanningError(f"{label} must be a positive number, got {v}")
        lo, hi = H_SAFE_RADII
        if not isinstance(p.h_safe, (int, float)) or not math.isfinite(p.h_safe) or not lo * r <= p.h_safe <= hi * r:
            raise PlanningError(f"h_safe = {p.h_safe} mm is outside the sane range [{lo * r:g}, {hi * r:g}] mm "
                                f"({lo:g} to {hi:g} tool radii); the paper recommends 1 to 1.5 tool radii")
        if not A_MAX_RANGE[0] <= p.a_max <= A_MAX_RANGE[1]:
            raise PlanningError(f"a_max = {p.a_max:g} mm/s^2 is outside the sane range {A_MAX_RANGE[0]:g} to "
                                f"{A_MAX_RANGE[1]:g} mm/s^2 (the paper's is 500)")
        if not FEED_RANGE[0] <= p.feed <= FEED_RANGE[1]:
            raise PlanningError(f"feed = {p.feed:g} mm/min is outside the sane range {FEED_RANGE[0]:g} to "
                                f"{FEED_RANGE[1]:g} mm/min (the paper's is 1000)")
        if not (isinstance(p.min_feed, (int, float)) and math.isfinite(p.min_feed) and 0 <= p.min_feed <= p.feed):
            raise PlanningError(f"the minimum cutting feed (--min-feed) must be a number of mm/min from 0 to the "
                                f"feed {p.feed:g}, got {p.min_feed}")
        if not isinstance(p.k_max, (int, float)) or not math.isfinite(p.k_max) or not 0 < p.k_max < 1:
            raise PlanningError(f"k_max = {p.k_max} is outside the sane range (0, 1); the paper recommends "
                                "0.1-0.2")
        if p.dd > 5 * r:
            raise PlanningError(f"dd = {p.dd} mm is more than 5 tool radii: the path would be too coarse")
        if p.mode not in MODES:
            raise PlanningError(f"mode must be collaborative, symmetric or single, got {p.mode!r}")
        return p

    def warnings(self) -> list[str]:
        out = []
        if self.dr is not None and self.dr > self.tool_radius / 4 + 1e-12:
            out.append(f"dR = {self.dr} mm is above tool_radius/4 = {self.tool_radius / 4:g} mm "
                       "(paper section 2): expect larger scallops")
        if self.h_safe is not None and not (1.0 - 1e-9 <= self.h_safe / self.tool_radius <= 1.5 + 1e-9):
            out.append(f"h_safe = {self.h_safe} mm is outside the paper's 1-1.5 tool radii")
        if not 0.1 - 1e-12 <= self.k_max <= 0.2 + 1e-12:
            out.append(f"k_max = {self.k_max} is outside the paper's 0.1-0.2")
        return out

    def as_dict(self) -> dict:
        return asdict(self)


#: how far the straight line between two rows may stray from the planned path by default (mm): the
#: gouge tolerance; below MIN the rows' own digits (1e-6 mm) would not hold it, above MAX it is no longer
#: a finishing tolerance
DEFAULT_CHORD_TOL = 1e-3
MIN_CHORD_TOL, MAX_CHORD_TOL = 1e-5, 0.5


def default_period(params: PlanParameters) -> float:
    """The CL tables' time step, ms: one interpolation step dd at the feed."""
    p = params.resolved()
    return p.dd / (p.feed / 60000.0)


@dataclass(frozen=True)
class PlanJob:
    """What to plan: the blade source ('sample', a table, a mesh or 'face.stl,back.stl') and its
    propeller axis, the parameters, the speed profile, the controller's period (ms; None = dd at the
    feed), the chord tolerance (mm: how far the straight line between two rows may stray from the
    planned path), the two machines' machine.toml (None: the shipped one), whether the result
    carries their axis tables (the job is timed for the machines either way), and the tool file
    (tool.toml; None: the shipped assembly with the parameters' tool radius and length; with one, they
    must be its ball radius and stick-out: core.machine.tool.resolve_tool)."""

    source: str = "sample"
    axis: str = "z"
    params: PlanParameters = field(default_factory=PlanParameters)
    profile: str = "sigmoid"
    period: float | None = None
    axes: bool = True
    machine: str | None = None
    chord_tol: float = DEFAULT_CHORD_TOL
    tool: str | None = None

    def resolved_period(self) -> float:
        """The time step, ms (PlanningError for one that is not a positive number)."""
        if self.period is None:  # (dd at the feed: the parameters' own check names a bad dd or feed)
            return float(default_period(self.params))
        period = self.period
        if not (isinstance(period, (int, float)) and math.isfinite(period) and 0 < period < 1e6):
            raise PlanningError(f"the time step (--period-ms) must be a positive number of ms below 1e6, got {period}")
        return float(period)

    def resolved_chord_tol(self) -> float:
        """The chord tolerance, mm (PlanningError for one out of range)."""
        tol = self.chord_tol
        if not (isinstance(tol, (int, float)) and math.isfinite(tol) and MIN_CHORD_TOL <= tol <= MAX_CHORD_TOL):
            raise PlanningError(f"the chord tolerance (--chord-tol) must be a number of mm from {MIN_CHORD_TOL:g} "
                                f"to {MAX_CHORD_TOL:g}, got {tol}")
        return float(tol)


@dataclass(frozen=True)
class Timings(Mapping):
    """Seconds per step of a plan (and a few counts, such as the path workers), in the order they
    ran; read like a dict, extended by ``plus`` into a new record (never changed in place)."""

    items_: tuple[tuple[str, float], ...] = ()

    @classmethod
    def of(cls, values: Mapping) -> Timings:
        return cls(tuple((str(k), v) for k, v in values.items()))

    def plus(self, **more: float) -> Timings:
        merged = dict(self.items_)
        merged.update(more)
        return Timings.of(merged)

    def __getitem__(self, key: str) -> float:
        return dict(self.items_)[key]

    def __iter__(self) -> Iterator[str]:
        return iter(k for k, _ in self.items_)

    def __len__(self) -> int:
        return len(self.items_)
