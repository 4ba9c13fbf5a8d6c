import numpy as np

from core.schedule.safety import capsule_clearance, segment_distance, tip_spacing


def test_segment_distance_against_brute_force():
    rng = np.random.default_rng(5)
    p0, p1, q0, q1 = (rng.normal(size=(300, 3)) for _ in range(4))
    got = segment_distance(p0, p1, q0, q1)
    s = np.linspace(0, 1, 401)
    for i in range(0, 300, 7):
        a = p0[i] + np.outer(s, p1[i] - p0[i])
        b = q0[i] + np.outer(s, q1[i] - q0[i])
        brute = np.linalg.norm(a[:, None] - b[None], axis=2).min()
        assert got[i] <= brute + 1e-12 and brute - got[i] < 1e-2


def test_tip_spacing_between_samples_finds_the_crossing():
    tl = np.array([[0.0, -1, 0], [0, 1, 0]])
    tr = np.array([[0.0, 1, 0.5], [0, -1, 0.5]])
    at, between = tip_spacing(tl, tr)
    assert np.allclose(at, np.hypot(2, 0.5)) and np.isclose(between[0], 0.5)


def test_capsules_parallel_tools():
    tips_l = np.array([[0.0, 0, -5]]); axes_l = np.array([[0.0, 0, -1]])
    tips_r = np.array([[3.0, 0, -5]]); axes_r = np.array([[0.0, 0, -1]])
    assert np.isclose(capsule_clearance(tips_l, axes_l, tips_r, axes_r, 1.0, 20.0)[0], 1.0)
