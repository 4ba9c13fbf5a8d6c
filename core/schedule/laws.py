"""The speed laws, array-based: the one implementation of each law's distance and speed along its
path (the quintic ramps and cruise of core.schedule.motion.RampLaw, the paper's sigmoid stage of Eq.
22-23, core.schedule.sigmoid.SigmoidStage, and the plateau stages of core.schedule.profiles with their
logistic or septic ramps). Each takes its law's parameters as rows (one column per instant), so that a
cutter's whole move list (core.schedule.movetable.MoveTable) or one law over a time column (the laws'
own methods, through ``rows``) is evaluated in one array operation per kind of law, valid on
[0, duration] of each law.

Units: mm, ms, mm/ms.
"""

from __future__ import annotations

import numpy as np
from scipy.special import expit


def rows(params, n: int) -> np.ndarray:
    """One law's parameters as rows for n instants: (len(params), n), read-only broadcast."""
    return np.broadcast_to(np.asarray(params, float)[:, None], (len(params), n))


def softplus_diff(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(k,) x, (k,) y -> (k,) ln(1 + e^x) - ln(1 + e^y), without cancellation when x ~ y.

    Uses ln((1 + e^x) / (1 + e^y)) = log1p(sigma(y) expm1(x - y)) for |x - y| < 30, the plain
    difference of softplus values otherwise (no cancellation there).
    """
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    d = x - y
    near = np.abs(d) < 30.0
    close = np.log1p(expit(y) * np.expm1(np.where(near, d, 0.0)))
    return np.where(near, close, np.logaddexp(0.0, x) - np.logaddexp(0.0, y))


def smooth_int(x: np.ndarray) -> np.ndarray:
    """Integral of the quintic smoothstep from 0 to x (x in [0, 1])."""
    x2 = x * x
    return x2 * x2 * (2.5 - 3.0 * x + x2)


def ramp_distance(p, tau):
    """Distance of ramp v_a -> v_c (t1 ms), cruise (t_cruise), ramp v_c -> v_b (t2); p = (length, v_a, v_c,
    v_b, t1, t_cruise, t2). Each instant's piece is evaluated for that instant only (most are cruising)."""
    length, va, vc, vb, t1, tc, t2 = p
    d1 = 0.5 * (va + vc) * t1
    out = d1 + vc * (tau - t1)                       # cruise
    a = tau <= t1
    i = np.flatnonzero(a)
    if i.size:
        ti = t1[i]
        x1 = tau[i] / np.where(ti > 0, ti, 1.0)
        out[i] = np.where(ti > 0, va[i] * tau[i] + (vc[i] - va[i]) * ti * smooth_int(x1), 0.0)
    i = np.flatnonzero(~a & (tau > t1 + tc))
    if i.size:
        t2i, vci = t2[i], vc[i]
        x2 = (tau[i] - t1[i] - tc[i]) / np.where(t2i > 0, t2i, 1.0)
        dc = d1[i] + vci * tc[i]
        out[i] = np.where(t2i > 0, dc + vci * x2 * t2i + (vb[i] - vci) * t2i * smooth_int(x2), dc)
    return np.minimum(out, length)


def smoothstep(x):
    x2 = x * x
    return x2 * x * (10 - 15 * x + 6 * x2)


def ramp_speed(p, tau):
    """Speed of the ramp law (``ramp_distance``), each instant's piece evaluated for it only."""
    _, va, vc, vb, t1, tc, t2 = p
    out = vc.copy()
    i = np.flatnonzero((tau < t1) & (t1 > 0))
    if i.size:
        out[i] = va[i] + (vc[i] - va[i]) * smoothstep(tau[i] / t1[i])
    i = np.flatnonzero((tau > t1 + tc) & (t2 > 0))
    if i.size:
        out[i] = vc[i] + (vb[i] - vc[i]) * smoothstep((tau[i] - t1[i] - tc[i]) / t2[i])
    return out


def shape_step(tau, a, logistic: bool):
    if logistic:
        return (expit(a * (2.0 * tau - 1.0)) - expit(-a)) / np.tanh(a / 2)
    return tau**4 * (35 + tau * (-84 + tau * (70 - 20 * tau)))


def shape_integral(tau, a, logistic: bool):
    if logistic:
        return (softplus_diff(a * (2.0 * tau - 1.0), -a) / (2 * a) - tau * expit(-a)) / np.tanh(a / 2)
    return tau**5 * (7 + tau * (-14 + tau * (10 - 2.5 * tau)))


def _plateau_pieces(tr, tp, t):
    d = 2 * tr + tp
    r1 = t < tr
    r2 = (t >= d - tr) & ~r1 & (tr > 0)
    scale = np.where(tr > 0, tr, 1.0)
    return d, r1, r2, scale


def plateau_ramp_distance(v0, vl, tr, a, rl, u, logistic):
    """PlateauStage.ramp_distance: mm covered by the first ramp after u ms (u in [0, tr])."""
    scale = np.where(tr > 0, tr, 1.0)
    dv = v0 - vl
    w = tr - u
    tail = vl * w + dv * tr * shape_integral(w / scale, a, logistic)
    head = v0 * u - dv * tr * shape_integral(u / scale, a, logistic)
    return np.where(tr > 0, np.where(u <= tr / 2, head, rl - tail), 0.0)


def plateau_distance(p, t, logistic: bool):
    """core.schedule.profiles.PlateauStage.distance on [0, duration]; p = (v0, v_low, tr, tp, a, length,
    ramp_length)."""
    v0, vl, tr, tp, a, total, rl = p
    d, r1, r2, _ = _plateau_pieces(tr, tp, t)
    a = np.where(a > 0, a, 1.0)
    first = plateau_ramp_distance(v0, vl, tr, a, rl, np.minimum(t, tr), logistic)
    second = total - plateau_ramp_distance(v0, vl, tr, a, rl, np.clip(d - t, 0, tr), logistic)
    return np.where(r1, first, np.where(r2, second, rl + vl * (t - tr)))


def plateau_speed(p, t, logistic: bool):
    """core.schedule.profiles.PlateauStage.speed on [0, duration]."""
    v0, vl, tr, tp, a, _, _ = p
    d, r1, r2, scale = _plateau_pieces(tr, tp, t)
    a = np.where(a > 0, a, 1.0)
    dv = v0 - vl

    def ramp(tau):
        return np.where(tau <= 0.5, v0 - dv * shape_step(tau, a, logistic),
                        vl + dv * shape_step(1 - tau, a, logistic))

    u1, u2 = np.clip(t / scale, 0, 1), np.clip((d - t) / scale, 0, 1)
    return np.where(r1 & (tr > 0), ramp(u1), np.where(r2, ramp(u2), vl))


def sigmoid_distance(p, t):
    """core.schedule.sigmoid.SigmoidStage.distance on [0, 4 K_T]; p = (K_V, K_T, K_a, K, length, -, -)."""
    kv, kt, ka, k, total = p[:5]
    d = 4 * kt
    a = ka * kt

    def half(x):
        return kv / ka * softplus_diff(a, a - ka * x) + k * x

    return np.where(t < 2 * kt, half(t), total - half(d - t))


def sigmoid_speed(p, t):
    """core.schedule.sigmoid.SigmoidStage.speed on [0, 4 K_T]."""
    kv, kt, ka, k = p[:4]
    return np.where(t < 2 * kt, kv * expit(ka * (kt - t)) + k, kv * expit(ka * (t - 3 * kt)) + k)


def knot_distance(s0, v0, a, x):
    """Distance of a profile law (core.schedule.motion.ProfileLaw) x ms after a knot at s0 mm, passed
    at v0 mm/ms, accelerating at a mm/ms^2 to the next knot (u = v^2 linear in s between knots)."""
    return s0 + x * (v0 + 0.5 * a * x)


def knot_speed(v0, a, x):
    """Speed of a profile law x ms after a knot (``knot_distance``)."""
    return v0 + a * x
