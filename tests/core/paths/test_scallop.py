"""The scallop height (core.paths.scallop) against an independent computation: the material left
between two ball passes found by casting rays across the surface and taking, on each ray, the first
ball it meets; on a flat and on a cylindrical surface (convex and concave), from contact points and
normals laid out as a plan's contour paths are."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from core.paths.scallop import path_scallops, scallop_height

R_TOOL = 1.5


def cast(centres: np.ndarray, r: float, origins: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Per ray (origin (m, 2), common unit direction (2,) pointing into the material), the distance
    along it to the first point inside any ball (circle) of radius r centred at ``centres`` (k, 2)."""
    best = np.full(len(origins), np.inf)
    for c in centres:
        oc = origins - c
        b = oc @ direction
        disc = b * b - (np.einsum("ij,ij->i", oc, oc) - r * r)
        hit = disc >= 0
        s = -b - np.sqrt(np.where(hit, disc, 0.0))
        best = np.where(hit, np.minimum(best, s), best)
    return best


def brute_flat(w: float, r: float) -> float:
    """Two balls touching the plane y = 0 from above at x = 0 and x = w, the material below: the cut
    surface at each x is the first ball point a ray from below meets; the scallop its highest."""
    centres = np.array([[0.0, r], [w, r]])
    x = np.linspace(0.0, w, 20001)
    origins = np.column_stack([x, np.full_like(x, -10 * r)])
    surface = -10 * r + cast(centres, r, origins, np.array([0.0, 1.0]))
    return float(surface.max())


def brute_cylinder(w_chord: float, r: float, rho: float, convex: bool) -> float:
    """Balls touching a circle of radius rho at contact points a chord w_chord apart: outside it on a
    convex surface (the material inside: rays from the axis outwards meet the cut surface), inside it
    on a concave one (the material outside: rays from far outside inwards)."""
    theta = 2 * np.arcsin(w_chord / (2 * rho))
    rc = rho + r if convex else rho - r
    centres = rc * np.array([[1.0, 0.0], [np.cos(theta), np.sin(theta)]])
    heights = []
    for phi in np.linspace(0.0, theta, 20001):
        u = np.array([np.cos(phi), np.sin(phi)])
        if convex:
            heights.append(cast(centres, r, np.zeros((1, 2)), u)[0] - rho)
        else:
            far = 10 * rho
            heights.append(rho - (far - cast(centres, r, (far * u)[None], -u)[0]))
    return float(max(heights))


@pytest.mark.parametrize("w", [0.1, 0.375, 1.0, 2.5])
def test_flat(w):
    assert scallop_height(np.array([w]), R_TOOL, np.array([0.0]))[0] == pytest.approx(brute_flat(w, R_TOOL),
                                                                                      abs=2e-7)


@pytest.mark.parametrize("rho", [5.0, 40.0, 300.0])
@pytest.mark.parametrize("convex", [True, False])
@pytest.mark.parametrize("w", [0.375, 1.2])
def test_cylinder(rho, convex, w):
    kappa = (1 if convex else -1) / rho
    h = scallop_height(np.array([w]), R_TOOL, np.array([kappa]))[0]
    assert h == pytest.approx(brute_cylinder(w, R_TOOL, rho, convex), abs=2e-7)
    # the usual second-order form, to which it tends for a small stepover
    assert h == pytest.approx(w * w / 8 * (1 / R_TOOL + kappa), rel=0.05 if w < 1 else 0.3)


def contours_on(surface: str, rho: float = 40.0, step: float = 0.6) -> list:
    """Contour paths as the planner lays them out (ContourPath's fields): lines along the span (x) of
    a plane z = 0 or of a cylinder of radius rho round the x axis, one every ``step`` mm across, both
    faces given the same contact points and outward normals."""
    paths = []
    x = np.linspace(0.0, 30.0, 61)
    for k in range(6):
        if surface == "flat":
            cc = np.column_stack([x, np.full_like(x, k * step), np.zeros_like(x)])
            n = np.tile([0.0, 0.0, 1.0], (len(x), 1))
        else:
            a = k * step / rho  # arc length k * step along the circle
            cc = np.column_stack([x, np.full_like(x, rho * np.sin(a)), np.full_like(x, rho * np.cos(a))])
            n = np.tile([0.0, np.sin(a), np.cos(a)], (len(x), 1))
        paths.append(SimpleNamespace(index=k, r=100.0 - k, left_cc=cc, left_normals=n, right_cc=cc,
                                     right_normals=n))
    return paths


@pytest.mark.parametrize("surface", ["flat", "cylinder"])
def test_plan_figures_from_contact_points(surface):
    rho, step = 40.0, 0.6
    fig = path_scallops(contours_on(surface, rho, step), R_TOOL)
    chord = step if surface == "flat" else 2 * rho * np.sin(step / (2 * rho))
    want = brute_flat(step, R_TOOL) if surface == "flat" else brute_cylinder(chord, R_TOOL, rho, True)
    assert set(fig["per_path_max_mm"]) == {str(k) for k in range(5)}  # the innermost has no next path
    for v in fig["per_path_max_mm"].values():
        # (the curvature from the normals' turn over a chord: exact to the chord's second order)
        assert v == pytest.approx(want, rel=1e-3)
    assert fig["max_mm"] == pytest.approx(want, rel=1e-3) and fig["mean_mm"] == pytest.approx(want, rel=1e-3)
    # a stepover of more than 2 r: the balls never meet, each strip is left uncut
    wide = path_scallops(contours_on(surface, rho, 3.5), R_TOOL)
    assert wide["uncut_paths"] == list(range(5)) and set(wide["per_path_max_mm"].values()) == {None}


def test_plan_json_carries_the_scallop_figures():
    """A planned sample's figures: the per-path scallops from its own contact points, against the
    closed form on each pair of paths' nearest points; the largest near the paper's r/4 stepover's
    flat value for dR = 1 mm (the blade is gently curved across the paths)."""
    from core.planner import Planner
    from core.records import PlanJob, PlanParameters

    res = Planner().plan(PlanJob(params=PlanParameters(dr=1.0, dd=0.5), axes=False))
    fig = res.figures["scallop"]
    paths = sorted(res.plan.paths, key=lambda p: -p.r)
    assert set(fig["per_path_max_mm"]) == {str(p.index) for p in paths[:-1]} and not fig["uncut_paths"]
    flat = R_TOOL - np.sqrt(R_TOOL ** 2 - 0.25)  # dR = 1 mm on a plane: 0.0858 mm
    assert 0.5 * flat < fig["mean_mm"] < 2 * flat and fig["max_mm"] >= fig["mean_mm"]
    # one path by hand: nearest points by brute force, the curvature from the normals
    a, b = paths[len(paths) // 2], paths[len(paths) // 2 + 1]
    d = np.linalg.norm(a.left_cc[:, None, :] - b.left_cc[None, :, :], axis=2)
    j = d.argmin(axis=1)
    w = d[np.arange(len(j)), j]
    t = (b.left_cc[j] - a.left_cc) / w[:, None]
    kappa = np.einsum("ij,ij->i", b.left_normals[j] - a.left_normals, t) / w
    h_left = scallop_height(w, R_TOOL, kappa)
    assert fig["per_path_max_mm"][str(a.index)] >= np.nanmax(h_left) - 1e-6
