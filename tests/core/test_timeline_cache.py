"""A timeline's spacing and clearance arrays are computed once (core's figures and the workbench's
views share them), equal to core.schedule.safety's, and the same arrays for two threads asking at once."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from core.schedule.motion import Samples
from core.schedule.safety import capsule_clearance, tip_spacing
from core.schedule.timeline import Timeline


def _samples(rng, n):
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    return Samples(rng.normal(size=(n, 3)) * 10, axes, np.ones(n, np.int64), np.zeros(n, np.int64),
                   np.ones(n, bool), np.zeros(n, np.int8))


def test_spacing_and_clearance_are_core_safety_computed_once():
    rng = np.random.default_rng(3)
    n = 5000
    tl = Timeline(np.arange(n, dtype=float), _samples(rng, n), _samples(rng, n))
    with ThreadPoolExecutor(2) as pool:
        a, b = pool.submit(tl.spacing).result(), pool.submit(tl.spacing).result()
        c1, c2 = pool.submit(tl.clearance, 1.5, 40.0), pool.submit(tl.clearance, 1.5, 40.0)
        c1, c2 = c1.result(), c2.result()
    assert a[0] is b[0] and a[1] is b[1] and c1 is c2
    at, between = tip_spacing(tl.left.tips, tl.right.tips)
    np.testing.assert_array_equal(a[0], at)
    np.testing.assert_array_equal(a[1], between)
    np.testing.assert_array_equal(c1, capsule_clearance(tl.left.tips, tl.left.axes, tl.right.tips,
                                                        tl.right.axes, 1.5, 40.0))
    other = tl.clearance(2.0, 40.0)  # another tool: its own arrays
    assert other is not c1 and not np.array_equal(other, c1)


def test_different_figures_are_computed_side_by_side():
    """Two threads asking for two different figures compute them at the same time (the workbench's
    views ask for the clearance while core's figures compute the spacing); one figure asked twice is
    still computed once."""
    import threading

    rng = np.random.default_rng(4)
    tl = Timeline(np.arange(10, dtype=float), _samples(rng, 10), _samples(rng, 10))
    meet = threading.Barrier(2, timeout=10)  # (both computations must be under way at once)
    calls = []

    def compute(name):
        def run():
            calls.append(name)
            meet.wait()
            return name
        return run

    with ThreadPoolExecutor(3) as pool:
        a = pool.submit(tl._cached, "a", compute("a"))
        b = pool.submit(tl._cached, "b", compute("b"))
        assert (a.result(), b.result()) == ("a", "b")
        again = pool.submit(tl._cached, "a", compute("a-again")).result()
    assert again == "a" and sorted(calls) == ["a", "b"]
