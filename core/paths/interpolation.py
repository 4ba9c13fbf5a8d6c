"""Double-curve interpolation (paper section 3, Eq. 3-15; SPEC.md section 5).

A machining path is fitted by cubic splines. Where its Y_W is strictly monotonic and the curve is not
too steep in Y (|dx/dy|, |dz/dy| <= STEEP = 2: a steeper x = f(y) is ill-conditioned, and its spline
kinks between knots near a rounded edge), the paper's form is used: y = t, x = f(t), z = g(t)
(Eq. 3-4). Otherwise (real meshes, high skew, and the rounded edges of most sections) x, y and z are
fitted against the cumulative chord length of the points, and the path is reported as an
arc-length fallback.

Arc length is exact: the integrand |dP/dt| of a cubic spline is smooth on each knot interval, and a
8-point Gauss-Legendre rule per interval integrates it to round-off (Eq. 5-6; tested against
adaptive quadrature). Its inverse (the
parameter at a given length, Eq. 10-13) is solved by safeguarded Newton iteration to 1e-10 mm instead
of the paper's fixed-step search.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.errors import PlanningError
from core.util.polyline import interval_turns, sagitta, turn_angles, unit_rows
from core.util.spline import Cubic

STEEP = 2.0
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_GL8 = np.polynomial.legendre.leggauss(8)


@dataclass(frozen=True)
class FittedCurve:
    """A cubic-spline fit of a 3D path.

    mode : 'y' (paper: t = y, x = f(t), z = g(t)) or 'arc' (t = cumulative chord length);
        t : (n,) float knots, increasing; spline : not-a-knot cubic
        (core.util.spline.Cubic) of (n, 3 + m) values over t: the points, then m extra columns fitted
        against the same parameter (normals, tail points); cum : (n,) float, mm, exact arc length
        at the knots; sign : +1/-1, the direction of y along the path in mode 'y'.
    """

    mode: str
    t: np.ndarray
    spline: Cubic
    cum: np.ndarray
    sign: float = 1.0
    knot_speed: np.ndarray | None = None

    @property
    def length(self) -> float:
        """Total arc length, mm."""
        return float(self.cum[-1])

    def point(self, t: np.ndarray) -> np.ndarray:
        """(k,) parameters -> (k, 3) float, mm."""
        return self.spline(t, 0, _XYZ)

    def extra(self, t: np.ndarray) -> np.ndarray:
        """(k,) parameters -> (k, m) the extra columns at t."""
        return self.spline(t, 0, _EXTRA)

    def speed(self, t: np.ndarray) -> np.ndarray:
        """(k,) parameters -> (k,) |dP/dt|."""
        d = self.spline(t, 1, _XYZ)
        return np.sqrt(np.einsum("ij,ij->i", d, d))

    def arc_length(self, t: np.ndarray) -> np.ndarray:
        """(k,) parameters -> (k,) float, mm, exact arc length from the first knot."""
        t = np.clip(np.asarray(t, float), self.t[0], self.t[-1])
        i = self.spline.interval(t)
        return self.cum[i] + _gl_integral(self.spline, i, self.t[i], t)

    def param_at(self, s: np.ndarray) -> np.ndarray:
        """(k,) float, mm, arc lengths -> (k,) parameters with arc_length(t) = s to 1e-9 mm.

        Safeguarded Newton iteration inside the knot interval that holds s (bisection whenever a
        Newton step would leave the bracket); a point is done once its residual is below 1e-10 mm
        or its last Newton correction was below 1e-7 mm (quadratic convergence then leaves an error
        far below 1e-10 mm).
        """
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        i = np.clip(np.searchsorted(self.cum, s, side="right") - 1, 0, len(self.t) - 2)
        lo, hi = self.t[i].copy(), self.t[i + 1].copy()
        base = self.cum[i]
        seg = np.where(self.cum[i + 1] > base, self.cum[i + 1] - base, 1.0)
        x = np.clip((s - base) / seg, 0.0, 1.0)
        # cubic Hermite guess of t(s) from the knot values and slopes dt/ds = 1/|dP/dt|: on the
        # pipeline's curves it is already within ~1e-9 mm, so one residual check usually ends it
        sp = self.knot_speed
        m0 = seg / np.where(sp[i] > 0, sp[i], np.inf)
        m1 = seg / np.where(sp[i + 1] > 0, sp[i + 1], np.inf)
        x2, x3 = x * x, x * x * x
        t = (2 * x3 - 3 * x2 + 1) * lo + (x3 - 2 * x2 + x) * m0 + (-2 * x3 + 3 * x2) * hi + (x3 - x2) * m1
        t = np.where((t > lo) & (t < hi), t, lo + (hi - lo) * x)
        active = np.arange(len(s))
        for _ in range(60):
            ia, ta = i[active], t[active]
            f = base[active] + _gl_integral(self.spline, ia, self.t[ia], ta, _GL8) - s[active]
            keep = np.abs(f) > 1e-9
            active, ia, ta, f = active[keep], ia[keep], ta[keep], f[keep]
            if active.size == 0:
                break
            lo[active] = np.where(f < 0, ta, lo[active])
            hi[active] = np.where(f > 0, ta, hi[active])
            d = self.spline.eval_in(ia, ta, 1, _XYZ)
            sp = np.sqrt(np.einsum("ij,ij->i", d, d))
            t_new = ta - f / np.where(sp > 0, sp, np.inf)
            bad = (t_new <= lo[active]) | (t_new >= hi[active]) | ~np.isfinite(t_new)
            t[active] = np.where(bad, 0.5 * (lo[active] + hi[active]), t_new)
            active = active[bad | (np.abs(f) >= 1e-7)]
            if active.size == 0:
                break
        return t


_XYZ = slice(0, 3)
_EXTRA = slice(3, None)


def _gl_integral(spline: Cubic, i: np.ndarray, a: np.ndarray, b: np.ndarray, rule=None) -> np.ndarray:
    """Integral of |dP/dt| from a to b, both inside knot interval i (arrays), Gauss-Legendre."""
    x, w = rule if rule is not None else (_GL_X, _GL_W)
    half = 0.5 * (b - a)
    nodes = (0.5 * (a + b))[:, None] + half[:, None] * x[None, :]
    return half * (spline.speed_nodes(i, nodes) @ w)


def _build(mode: str, t: np.ndarray, points: np.ndarray, sign: float = 1.0,
           extra: np.ndarray | None = None) -> FittedCurve:
    values = points if extra is None else np.hstack([points, extra])
    spline = Cubic(t, values)
    idx = np.arange(len(t) - 1)
    cum = np.concatenate([[0.0], np.cumsum(_gl_integral(spline, idx, t[:-1], t[1:], _GL8))])
    d = spline(t, 1, _XYZ)
    return FittedCurve(mode, t, spline, cum, sign, np.sqrt(np.einsum("ij,ij->i", d, d)))


def dedupe_mask(points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(n, 3) points, mm -> (n,) bool: False for a point closer than tol to the one before."""
    return np.concatenate([[True], np.linalg.norm(np.diff(points, axis=0), axis=1) > tol])


def fit_curve(points: np.ndarray, allow_y: bool = True, extra: np.ndarray | None = None) -> FittedCurve:
    """Fit a path: the paper's y-parametrisation where possible, else the arc-length fallback.

    points : (n, 3) float, mm, workpiece frame, in path order, n >= 2; extra : optional (n, m) values
    fitted against the same parameter (see FittedCurve.extra). Consecutive duplicate points are
    dropped (with their extra values).
    """
    pts = np.asarray(points, float)
    keep = dedupe_mask(pts)
    pts = pts[keep]
    if extra is not None:
        extra = np.asarray(extra, float)[keep]
    if len(pts) < 2:
        raise PlanningError("a path needs at least two distinct points")
    d = np.diff(pts, axis=0)
    if allow_y and len(pts) >= 4:
        dy = d[:, 1]
        sign = 1.0 if dy[0] > 0 else -1.0
        mono = np.all(sign * dy > 0)
        if mono:
            steep = np.max(np.abs(d[:, [0, 2]]) / np.abs(dy)[:, None])
            if steep <= STEEP:
                # t = sign * y increases along the path
                return _build("y", sign * pts[:, 1], pts, sign, extra)
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(d, axis=1))])
    return _build("arc", t, pts, extra=extra)


@dataclass(frozen=True)
class InterpolatedPath:
    """Equidistant interpolation of one path.

    tips, tails, axes : (N+1, 3) float, mm / unit; s : (N+1,) float, mm, arc length of the tips;
    params : (N+1,) curve parameters of the tips; step : float, mm (<= dd); mode : 'y' | 'arc'
    """

    tips: np.ndarray
    tails: np.ndarray
    axes: np.ndarray
    s: np.ndarray
    params: np.ndarray
    step: float
    mode: str
    curve: FittedCurve | None = None


def equidistant_params(curve: FittedCurve, dd: float) -> tuple[np.ndarray, np.ndarray]:
    """Parameters of points at equal arc length <= dd along a curve, ends included (Eq. 7-8 with the
    step count taken from the tip curve). Returns (params (N+1,), s (N+1,) mm)."""
    if not np.isfinite(dd) or dd <= 0:
        raise PlanningError(f"step dd must be a positive number of mm, got {dd}")
    n = max(int(np.ceil(curve.length / dd - 1e-9)), 1)
    s = np.linspace(0.0, curve.length, n + 1)
    return curve.param_at(s), s


def double_curve_interpolation(tips: np.ndarray, tails: np.ndarray, dd: float,
                               allow_y: bool = True) -> InterpolatedPath:
    """Paper Eq. 3-15: fit tips and tails, interpolate at equal tip arc length, orientation from both.

    tips, tails : (n, 3) float, mm, the original cutter position and tail points in path order.
    The tip curve is fitted as in ``fit_curve``; the tail curve is fitted against the same parameter
    (the tip's y, or the tip's chord length), so tip and tail of one interpolated point always come
    from the same original interval at the same parameter. (The paper divides each tail interval by
    its own arc length, Eq. 9 and 11; that agrees at the original points and keeps orientations
    synchronous between them only approximately.) Step count N = ceil(L / dd) from the tip curve, so
    the tip spacing is L / N <= dd (Eq. 7 takes the larger of the two curves' counts, which would
    shrink the tip spacing wherever the tails sweep a longer curve). Orientation w = unit(p' - p)
    (tip -> spindle; Eq. 14 up to its sign convention).
    """
    ct = fit_curve(tips, allow_y, extra=tails)
    t_tip, s = equidistant_params(ct, dd)
    p, q = ct.point(t_tip), ct.extra(t_tip)
    axes = unit_rows(q - p)
    step = ct.length / max(len(s) - 1, 1)
    return InterpolatedPath(tips=p, tails=q, axes=axes, s=s, params=t_tip, step=step, mode=ct.mode, curve=ct)


#: chord error allowed to the ball centre between two consecutive points (mm), see chord_subdivisions
CHORD_TOLERANCE = 5e-4


def chord_subdivisions(centres: np.ndarray, axes: np.ndarray | None = None,
                       tol: float = CHORD_TOLERANCE) -> np.ndarray:
    """How many pieces each interval of a ball-centre polyline needs so that a controller moving in
    straight lines between points stays within ``tol`` of the curve: (n, 3) mm -> (n-1,) int >= 1.

    The sagitta of an interval of length c on a curve that turns by theta over it is c theta / 8;
    theta is taken as the larger turning angle at the interval's two ends, or the rotation of the tool
    axis over the interval when that is larger (axes (n, 3), optional). Near a rounded edge the ball
    centre turns fast while the tool tip moves dd, so a tip spacing of dd alone is not enough.
    """
    c, theta = interval_turns(centres)
    if axes is not None:
        theta = np.maximum(theta, turn_angles(axes))
    sag = sagitta(c, theta)
    return np.maximum(np.ceil(np.sqrt(sag / tol)), 1).astype(int)


def subdivision_points(values: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """The pieces[k] - 1 equally spaced values inside each interval k of an increasing (n,) array."""
    k = np.repeat(np.arange(len(pieces)), np.maximum(pieces - 1, 0))
    m = pieces[k]
    j = np.arange(len(k)) - np.repeat(np.cumsum(np.maximum(pieces - 1, 0)) - np.maximum(pieces - 1, 0),
                                      np.maximum(pieces - 1, 0)) + 1
    return values[k] + j / m * (values[k + 1] - values[k])
