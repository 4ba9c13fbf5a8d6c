"""Motion primitives for the schedule: timed moves of one cutter along polylines, and their sampling.

A cutter's whole job is a list of ``Move``s, back to back in time. Each move follows a polyline of
tool tips (with tool axes at its vertices) and has a distance law s(tau), tau in ms from the move's
start, s in mm along the polyline. Laws:
- ``ramp_law``: from speed v_a up (or down) to a cruise speed and on to v_b, speed changes by a
  quintic smoothstep (continuous acceleration, peak |a| = 1.875 dv / T <= a_max);
- ``wait_law``: standing still;
- any object with ``distance(tau)`` and ``duration`` (the sigmoid stages of core.schedule.sigmoid).
Units inside: mm, ms, mm/ms, mm/ms^2.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from core.errors import PlanningError
from core.paths.regions import REGION_NAMES, REGION_NAMES_ARRAY, region_codes
from core.schedule.laws import ramp_distance, ramp_speed, rows
from core.util.polyline import cumulative_length
from core.util.rowwise import row_norm
from core.util.spline import Curve1D, hermite

SMOOTH_PEAK = 1.875  # peak of d/dx of the quintic smoothstep 10x^3 - 15x^4 + 6x^5


@dataclass(frozen=True)
class RampLaw:
    """Speed v_a -> v_c (ramp T1), cruise, v_c -> v_b (ramp T2); mm, ms."""

    length: float
    v_a: float
    v_c: float
    v_b: float
    t1: float
    t_cruise: float
    t2: float

    @property
    def duration(self) -> float:
        return self.t1 + self.t_cruise + self.t2

    def _rows(self, n: int) -> np.ndarray:
        return rows((self.length, self.v_a, self.v_c, self.v_b, self.t1, self.t_cruise, self.t2), n)

    def distance(self, tau: np.ndarray) -> np.ndarray:
        """(k,) ms -> (k,) mm (core.schedule.laws.ramp_distance), constant outside [0, duration]."""
        tau = np.clip(np.asarray(tau, float), 0.0, self.duration)
        return ramp_distance(self._rows(tau.size), tau.ravel()).reshape(tau.shape)

    def speed(self, tau: np.ndarray) -> np.ndarray:
        """(k,) ms -> (k,) mm/ms (core.schedule.laws.ramp_speed), the end speeds outside."""
        tau = np.clip(np.asarray(tau, float), 0.0, self.duration)
        return ramp_speed(self._rows(tau.size), tau.ravel()).reshape(tau.shape)


def ramp_time(dv: float, a: float) -> float:
    """ms a quintic smoothstep ramp takes to change the speed by dv (mm/ms) at peak acceleration a
    (mm/ms^2): its peak is SMOOTH_PEAK |dv| / T."""
    return SMOOTH_PEAK * abs(dv) / a


def stop_distance(v: float, a: float) -> float:
    """mm a quintic smoothstep ramp takes from speed v (mm/ms) to rest, or from rest to v, at peak
    acceleration a (mm/ms^2): the mean speed v / 2 over ramp_time(v, a)."""
    return 0.5 * v * SMOOTH_PEAK * v / a


def ramp_law(length: float, v_cruise: float, a_max: float, v_a: float = 0.0, v_b: float = 0.0) -> RampLaw:
    """The fastest smooth law covering ``length`` from speed v_a to v_b with cruise speed <= v_cruise
    and |acceleration| <= a_max (mm, mm/ms, mm/ms^2)."""
    if length < 0 or v_cruise <= 0 or a_max <= 0:
        raise PlanningError(f"bad move: length {length}, speed {v_cruise}, a_max {a_max}")
    if length == 0:
        return RampLaw(0.0, v_a, v_a, v_b, 0.0, 0.0, 0.0)

    def ramps(vc: float) -> tuple[float, float, float]:
        t1 = ramp_time(vc - v_a, a_max)
        t2 = ramp_time(vc - v_b, a_max)
        return t1, t2, 0.5 * (v_a + vc) * t1 + 0.5 * (vc + v_b) * t2

    t1, t2, d = ramps(v_cruise)
    if d <= length:
        return RampLaw(length, v_a, v_cruise, v_b, t1, (length - d) / v_cruise, t2)
    if ramps(max(v_a, v_b))[2] > length:
        # too short even to reach the larger end speed: the end speeds are the caller's to fix
        raise PlanningError(f"a move of {length:.4f} mm cannot change speed from {v_a * 60000:.1f} to "
                            f"{v_b * 60000:.1f} mm/min within a_max = {a_max * 1e6:g} mm/s^2: lower the feed "
                            "or raise a_max")
    # no cruise: for v_c >= v_a, v_b the two ramps cover (K / 2)(2 v_c^2 - v_a^2 - v_b^2), K = SMOOTH_PEAK / a_max
    k = SMOOTH_PEAK / a_max
    vc = min(max(float(np.sqrt((2.0 * length / k + v_a * v_a + v_b * v_b) / 2.0)), v_a, v_b), v_cruise)
    t1, t2, d = ramps(vc)
    return RampLaw(length, v_a, vc, v_b, t1, max((length - d) / vc, 0.0) if vc > 0 else 0.0, t2)


@dataclass(frozen=True)
class WaitLaw:
    duration: float
    length: float = 0.0

    def distance(self, tau: np.ndarray) -> np.ndarray:
        return np.zeros_like(np.asarray(tau, float))

    def speed(self, tau: np.ndarray) -> np.ndarray:
        return np.zeros_like(np.asarray(tau, float))


#: share of a_max that the change of a cutter's speed ratio to the master may take in a symmetrical
#: stretch (core.schedule.motion.sync_map); the master's own ramps keep to the rest
SYNC_ACCEL_SHARE = 0.25


def sync_window(v: float, a: float) -> float:
    """mm of master distance over which sync_map averages the cutters' speed ratios at cruise speed v
    (mm/ms) and acceleration a (mm/ms^2): the ratio then changes by at most 1 / window per mm, so the
    cutter's acceleration from it, f'' v^2, stays within SYNC_ACCEL_SHARE * a."""
    return v * v / (SYNC_ACCEL_SHARE * a)


def sync_map(master_cum: np.ndarray, own_cum: np.ndarray, window: float) -> Curve1D:
    """A cutter's own distance as a function of the master's in a symmetrical stretch: a C1 piecewise
    quadratic through both ends, the moving average over ``window`` (mm of master distance) of the
    broken line G through (master_cum, own_cum) reflected oddly about each end.

    G's slope (own step / master step, the cutter's share of the master's speed) lies in [0, 1] but
    jumps from one pair of points to the next: on a faceted blade by factors of 5 between steps of a
    few micrometres. An interpolant through every vertex (PCHIP) then overshoots the feed by up to 20 %
    and turns the jumps into accelerations of 10^5 mm/s^2. The average instead has
    - f(0) = G(0) and f(M) = G(M): both cutters start and end the stretch together, exactly;
    - 0 <= f' <= 1 (a mean of G's slopes): no cutter outruns the master;
    - |f''| <= 1 / window (a difference of two slopes in [0, 1] over the window): bounded acceleration;
    - f'' = 0 at both ends (the reflection is symmetric there), and f'(0) the mean slope over the first
      window / 2 (the end speed a neighbouring stage starts or ends at depends on that part only);
    at the price of the two cutters reaching a pair's points within a fraction of the window of each
    other rather than at the same instant (on a smooth blade, about window^2 |G''| / 24).
    The window shrinks to the stretch's length M where that is shorter."""
    x = np.asarray(master_cum, float)
    y = np.asarray(own_cum, float)
    keep = np.concatenate([[True], np.diff(x) > 0])  # a zero master step is a zero own step
    x, y = x[keep], y[keep]
    m_len = float(x[-1] - x[0])
    x = x - x[0]
    if len(x) < 2 or m_len <= 0:
        return hermite(np.array([0.0, 1.0]), np.array([y[0], y[0]]), np.zeros(2))
    w = min(float(window), m_len)
    h = 0.5 * w
    # G reflected oddly about both ends (h <= M / 2: one reflection each side covers the window)
    xe = np.concatenate([-x[:0:-1], x, 2 * m_len - x[-2::-1]])
    ye = np.concatenate([2 * y[0] - y[:0:-1], y, 2 * y[-1] - y[-2::-1]])
    slope = np.diff(ye) / np.diff(xe)

    def g(s: np.ndarray) -> np.ndarray:
        i = np.clip(np.searchsorted(xe, s, side="right") - 1, 0, len(xe) - 2)
        return ye[i] + slope[i] * (s - xe[i])

    # f' is linear between the points where m - h or m + h crosses a knot (f quadratic there)
    b = np.concatenate([[0.0, m_len], xe - h, xe + h])
    b = np.unique(b[(b > 0) & (b < m_len)])
    b = np.concatenate([[0.0], b[np.diff(b, prepend=0.0) > 1e-9 * max(1.0, m_len)], [m_len]])
    if b[-1] - b[-2] <= 1e-9 * max(1.0, m_len) and len(b) > 2:
        b = np.delete(b, -2)
    df = np.clip((g(b + h) - g(b - h)) / w, 0.0, None)
    # f from f' by the trapezoid rule (exact for a linear f'), so that the values and slopes handed to
    # the Hermite pieces agree to round-off even on pieces of a nanometre; scaled by 1 +- 1e-13 so
    # that f(M) = G(M) exactly (which the reflection gives analytically)
    rise = np.concatenate([[0.0], np.cumsum(0.5 * (df[1:] + df[:-1]) * np.diff(b))])
    if rise[-1] > 0:
        scale = (y[-1] - y[0]) / rise[-1]
        rise, df = rise * scale, df * scale
    f = y[0] + rise
    f[-1] = y[-1]
    return hermite(b, f, df)


@dataclass(frozen=True)
class MappedLaw:
    """A cutter's distance law through a master law: own = f(master(t)), f the cutter's sync_map for
    the stretch (C1, 0 <= f' <= 1, bounded f''). Symmetrical machining drives both cutters by one
    master law on the larger of their two steps, each through its own map."""

    master: RampLaw
    f: Curve1D

    #: f' (derived from f when the law is made)
    df: Curve1D = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "df", self.f.derivative())

    @property
    def duration(self) -> float:
        return self.master.duration

    @property
    def length(self) -> float:
        return float(self.f(self.master.length))

    def distance(self, tau):
        return self.f(self.master.distance(tau))

    def speed(self, tau):
        return self.df(self.master.distance(tau)) * self.master.speed(tau)




@dataclass(frozen=True)
class Move:
    """One timed move of a cutter.

    t0 : ms; law : distance law with ``duration``; points : (m, 3) mm tips; axes : (m, 3) unit;
    step : 1..7; path : path index (-1 for none); cutting : bool;
    regions : (m,) int, the region at each vertex as an index into REGION_NAMES
    """

    t0: float
    law: object
    points: np.ndarray
    axes: np.ndarray
    step: int
    path: int
    cutting: bool
    regions: np.ndarray
    cum: np.ndarray = field(default=None)

    @property
    def t1(self) -> float:
        return self.t0 + self.law.duration


#: a vertex where the path turns by more than this (degrees) ...
CORNER_TURN_DEG = 2.0
#: ... next to a segment shorter than this (mm) is a tight corner: the cutter stops there
CORNER_SEGMENT = 2e-3


def tight_corners(points: np.ndarray) -> np.ndarray:
    """Inner vertex indices of a polyline (m, 3) mm where it turns by more than CORNER_TURN_DEG next to
    a segment shorter than CORNER_SEGMENT (zero-length segments skipped). On a faceted (mesh) blade
    the contact path of the tip region turns back and forth by tens of nanometres where the ball
    rolls over a facet edge; passing such a corner at the feed changes the direction of motion
    within microseconds, and no time column can hold a row at every such vertex (rows keep 5
    microseconds apart), so its chords read as speed dips of 10^5-10^6 mm/s^2. The cutter stops at
    these corners instead (a few milliseconds each). Elsewhere the machine clock slows the cutter
    where the straight lines between rows would stray from the path (core.machine.caps)."""
    d = np.diff(points, axis=0)
    length = row_norm(d)
    real = np.flatnonzero(length > 1e-12)
    if real.size < 2:
        return np.empty(0, int)
    u = d[real] / length[real, None]
    turn = np.einsum("ij,ij->i", u[:-1], u[1:]) < np.cos(np.radians(CORNER_TURN_DEG))
    short = np.minimum(length[real[:-1]], length[real[1:]]) < CORNER_SEGMENT
    return real[1:][turn & short]  # the vertex that starts the second segment


_CODE_OF = {name: np.int64(k) for k, name in enumerate(REGION_NAMES)}


@dataclass(frozen=True)
class MoveTag:
    """What a move is: its schedule step (1..7), its path (-1 for none), whether it cuts, and its
    regions: a region name, an array of names per vertex, or their codes (core.paths.regions)."""

    step: int
    path: int
    cutting: bool
    regions: object


def make_move(t0: float, law, points: np.ndarray, axes: np.ndarray, tag: MoveTag,
              cum: np.ndarray | None = None) -> Move:
    """A move starting at t0 ms along ``law`` over the polyline ``points`` (m, 3) mm with unit ``axes``
    (m, 3), tagged by ``tag``; cum : the polyline's cumulative lengths (mm) when the caller has them."""
    points = np.atleast_2d(np.asarray(points, float))
    axes = np.atleast_2d(np.asarray(axes, float))
    regions = tag.regions
    if isinstance(regions, str) and regions in _CODE_OF:
        codes = np.asarray(_CODE_OF[regions])
    else:
        codes = np.asarray(regions)
    if codes.dtype.kind not in "iu":
        codes = region_codes(codes)
    elif codes.size and (codes.min() < 0 or codes.max() >= len(REGION_NAMES)):
        raise PlanningError(f"region codes must lie in 0..{len(REGION_NAMES) - 1}, got {np.unique(codes)}")
    codes = np.full(len(points), codes) if codes.ndim == 0 else np.broadcast_to(codes, (len(points),))
    cum = cumulative_length(points) if cum is None else cum
    return Move(t0, law, points, axes, tag.step, tag.path, tag.cutting, codes, cum)


@dataclass(frozen=True)
class Samples:
    """One cutter sampled on a time column: tips (n, 3) mm, axes (n, 3), step/path (n,) int,
    cutting (n,) bool, code (n,) int8 region index into REGION_NAMES (``region``: the names)."""

    tips: np.ndarray
    axes: np.ndarray
    step: np.ndarray
    path: np.ndarray
    cutting: np.ndarray
    code: np.ndarray

    @property
    def region(self) -> np.ndarray:
        """(n,) str region names."""
        return REGION_NAMES_ARRAY[self.code]

    def take(self, index) -> Samples:
        """The samples at ``index`` (indices or a boolean mask)."""
        return Samples(*(getattr(self, f.name)[index] for f in fields(self)))
