"""core.schedule.motion.sync_map: the map from the master's distance to a cutter's own in a symmetrical stretch,
checked against a moving average computed here by numerical quadrature, and its bounds (ends exact,
0 <= f' <= 1, |f''| <= 1 / window) by finite differences."""

import numpy as np
import pytest
from scipy.integrate import quad

from core.schedule.motion import sync_map


def _steps(seed: int, n: int, irregular: bool):
    """(master_cum, left_cum, right_cum): n steps of two cutters, the master taking the larger."""
    rng = np.random.default_rng(seed)
    if irregular:  # faceted: steps from micrometres to 0.2 mm, the two sides' ratio jumping
        dl = 10 ** rng.uniform(-3.5, -0.7, n)
        dr = dl * rng.uniform(0.15, 1.0, n) ** rng.choice([-1, 1], n)
    else:  # smooth: the ratio drifts slowly
        u = np.linspace(0, 1, n)
        dl = 0.2 * np.ones(n)
        dr = 0.2 * (0.5 + 0.4 * np.sin(3 * u))
    cum = lambda d: np.concatenate([[0.0], np.cumsum(d)])  # noqa: E731
    return cum(np.maximum(dl, dr)), cum(dl), cum(dr)


def _reference(master, own, window):
    """The moving average of the broken line, reflected oddly about both ends, by quadrature."""
    m_len = master[-1]
    w = min(window, m_len)

    def g(s):
        if s < 0:
            return 2 * own[0] - np.interp(-s, master, own)
        if s > m_len:
            return 2 * own[-1] - np.interp(2 * m_len - s, master, own)
        return np.interp(s, master, own)

    def f(m):
        lo, hi = m - w / 2, m + w / 2
        knots = np.concatenate([master, -master, 2 * m_len - master])
        pts = knots[(knots > lo) & (knots < hi)]
        if len(pts) > 40:  # quad takes at most 50 break points: integrate piece by piece
            edges = np.concatenate([[lo], np.sort(pts), [hi]])
            return sum(quad(g, a, b)[0] for a, b in zip(edges[:-1], edges[1:], strict=True)) / w
        return quad(g, lo, hi, points=pts, limit=200)[0] / w

    return f, w


@pytest.mark.parametrize("irregular", [True, False])
@pytest.mark.parametrize("window", [0.05, 0.6, 100.0])
def test_sync_map_is_the_moving_average(irregular, window):
    master, left, right = _steps(3, 300, irregular)
    for own in (left, right):
        fmap = sync_map(master, own, window)
        ref, _ = _reference(master, own, window)
        rng = np.random.default_rng(7)
        for m in np.concatenate([[0.0, master[-1]], rng.uniform(0, master[-1], 25)]):
            assert float(fmap(m)) == pytest.approx(ref(m), abs=1e-9)


@pytest.mark.parametrize("irregular", [True, False])
@pytest.mark.parametrize("window", [0.05, 0.6])
def test_sync_map_bounds(irregular, window):
    master, left, right = _steps(11, 400, irregular)
    for own in (left, right):
        fmap = sync_map(master, own, window)
        # both cutters start and end the stretch exactly together
        assert float(fmap(0.0)) == pytest.approx(own[0], abs=1e-12)
        assert float(fmap(master[-1])) == pytest.approx(own[-1], abs=1e-12)
        x = np.linspace(0, master[-1], 400001)
        dx = x[1] - x[0]
        f = fmap(x)
        d1 = np.diff(f) / dx  # slope of each small chord: the speed ratio to the master
        assert d1.min() >= -1e-7 and d1.max() <= 1 + 1e-7  # (round-off of f over dx)
        d2 = np.diff(f, 2) / dx**2
        assert np.abs(d2).max() <= (1 + 1e-3) / window + 1e-6
        # at the ends: no acceleration from the map, and the slope is the mean over the first window / 2
        h = window / 2
        start_slope = (np.interp(h, master, own) - own[0]) / h
        assert float(fmap.derivative()(0.0)) == pytest.approx(start_slope, abs=1e-9)
        end = master[-1]
        assert float(fmap.derivative()(end)) == pytest.approx(
            (own[-1] - np.interp(end - h, master, own)) / h, abs=1e-9)
        assert abs((f[2] - 2 * f[1] + f[0]) / dx**2) <= 1e-3 / window + 1e-6


def test_sync_map_keeps_a_smooth_ratio_close_to_the_pairs():
    """On a smooth blade the cutters reach each pair of points within window^2 |G''| / 24 of the master's
    instant for them (here micrometres)."""
    master, left, right = _steps(0, 500, irregular=False)
    w = 2.2
    for own in (left, right):
        fmap = sync_map(master, own, w)
        ratio = np.diff(own) / np.diff(master)
        curv = np.abs(np.diff(ratio) / np.diff(master)[1:]).max()  # |G''| of the broken line's trend
        inner = (master > w) & (master < master[-1] - w)
        err = np.abs(fmap(master[inner]) - own[inner]).max()
        assert err <= w * w * curv / 24 * 1.5 + 1e-9
        assert err < 5e-3


def test_sync_map_degenerate_stretches():
    fmap = sync_map(np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, 0.5]), 5.0)  # repeated point
    assert float(fmap(1.0)) == pytest.approx(0.5) and float(fmap.derivative()(0.3)) == pytest.approx(0.5)
    still = sync_map(np.array([0.0, 0.0]), np.array([2.0, 2.0]), 1.0)  # no length at all
    assert float(still(0.0)) == 2.0
