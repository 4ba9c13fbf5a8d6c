"""Golden tests of the paper's first steps on a tiny blade (sections 2, 3 and 4 of Wang, Ge, Guo 2023).

The tiny blade: D = 40 mm, hub ratio 0.5 (span 10 mm, r from 10 to 20 mm), three table rows, a closed
tip; with dR = 2 mm it has five contour paths. Tool radius 0.2 mm, h_safe = 1.25 r = 0.25 mm (the
default), K_max = 0.15 (the default), dd = 0.15 mm (1 mm for the bare interpolation), d_T = 40 mm.

Golden numbers were obtained by running the code as of this file's writing (printed with repr) and are
asserted to 1e-9 relative; each is also checked against a property computed here independently.
"""

import math

import numpy as np
import pytest

from core.blade.frame import workpiece_frame
from core.blade.source import load_blade
from core.errors import PlanningError
from core.paths.alignment import align_single, align_symmetric, sides
from core.paths.contours import contour_path, path_radii, side_assignment
from core.paths.cutter import symmetric_tools, tail_points
from core.paths.interpolation import double_curve_interpolation
from core.paths.regions import divide
from core.util.polyline import ball_centres

TABLE = """# name: tiny blade
# blades: 4
# diameter_mm: 40
# hub_ratio: 0.5
# meanline: NACA a=0.8
# thickness: NACA 66 mod
r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D
0.5,0.35,0.9,0.20,0.02,0.0,0.0
0.75,0.35,1.0,0.15,0.02,2.0,0.0
1.0,0.0,1.0,0.15,0.01,5.0,0.0
"""
DR, DD, TOOL_R, H_SAFE, K_MAX, D_T = 2.0, 0.15, 0.2, 0.25, 0.15, 40.0


def gold(x, rel=1e-9):
    """A golden number: relative 1e-9 (floating point noise), absolute 1e-12 for values near 0."""
    return pytest.approx(x, rel=rel, abs=1e-12)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    path = tmp_path_factory.mktemp("tiny") / "tiny.csv"
    path.write_text(TABLE, encoding="utf-8")
    blade = load_blade(str(path))
    frame = workpiece_frame(blade)
    left_is_back = side_assignment(blade, frame)
    radii = path_radii(blade, DR)
    paths = [contour_path(blade, frame, float(r), i, left_is_back) for i, r in enumerate(radii)]
    pairs = [align_symmetric(p, DD, TOOL_R) for p in paths]
    return blade, frame, left_is_back, radii, paths, pairs


def blade_frame(frame, pts):
    """Workpiece -> blade frame (p_W = R p_B + t, so p_B = (p_W - t) R)."""
    return (pts - frame.translation) @ frame.rotation


def radius(frame, pts):
    """Distance (mm) of workpiece-frame points from the propeller axis."""
    return np.hypot(*blade_frame(frame, pts)[:, :2].T)


def unrolled(frame, pts, r):
    """(r theta, z) of workpiece-frame points on the cylinder of radius r."""
    pb = blade_frame(frame, pts)
    return np.column_stack([r * np.arctan2(pb[:, 1], pb[:, 0]), pb[:, 2]])


def template_tips(pair):
    return pair.left_tip if pair.template == "left" else pair.right_tip


def arclength(pts):
    """(n,) cumulative chord length of a polyline, mm."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])


# ---- section 2: contour tool paths ----------------------------------------------------------------

def test_section2_contour_paths(tiny):
    blade, frame, left_is_back, radii, paths, _ = tiny
    # hub and tip from the table: 0.5 * 20 and 1.0 * 20 mm
    assert (blade.hub_radius, blade.tip_radius) == (10.0, 20.0)
    # reference pitch at 0.7 R = 14 mm, measured on the section (golden); independently, the table's
    # P/D spline through 3 rows is the parabola 1 - 0.8 (x - 0.75)^2 + 0.2 (x - 0.75) -> 0.988 at
    # x = 0.7, and the pitch angle is atan(P/D / (pi x))
    assert frame.reference_pitch_deg == gold(24.193032864156123)
    assert frame.reference_pitch_deg == gold(math.degrees(math.atan2(0.988, 0.7 * math.pi)))
    # radii, tip first: r_i = tip - (i + 1/2) dR (module docstring); the span 10 mm is 5 dR, so these
    # are also hub + (k + 1/2) dR read backwards, and all lie in [hub, tip]
    assert radii.tolist() == [19.0, 17.0, 15.0, 13.0, 11.0]
    k = np.arange(5) + 0.5
    assert np.allclose(radii, 20 - k * DR, atol=1e-12) and np.allclose(radii[::-1], 10 + k * DR, atol=1e-12)
    # the back faces -Z_W, so the left cutter machines the back: every path's left normals point
    # to -Z_W on average and its right normals to +Z_W
    assert left_is_back is True
    for i, (p, r) in enumerate(zip(paths, radii, strict=True)):
        assert (p.index, p.r, p.direction) == (i, r, 1 if i % 2 == 0 else -1)
        # 241 cosine-spaced chordwise stations per side (table.DEFAULT_POINTS)
        assert p.left_cc.shape == p.right_cc.shape == p.left_normals.shape == (241, 3)
        assert p.left_normals[:, 2].mean() < 0 < p.right_normals[:, 2].mean()
        assert np.allclose(np.linalg.norm(np.vstack([p.left_normals, p.right_normals]), axis=1), 1, atol=1e-9)
        # every contact point lies on its cylinder: the section at r
        assert np.allclose(radius(frame, np.vstack([p.left_cc, p.right_cc])), r, rtol=1e-12, atol=0)
        # both sides share the end points (LE and TE)
        assert np.allclose(p.left_cc[[0, -1]], p.right_cc[[0, -1]], rtol=0, atol=1e-12)
        # reciprocating: even paths start at the LE (larger r theta), odd ones at the TE
        a = unrolled(frame, p.left_cc[[0, -1]], r)[:, 0]
        assert (a[0] > a[1]) == (p.direction == 1)
    p2 = paths[2]
    # golden contact points of path 2 (r = 15 mm, LE -> TE): the LE, the mid-chord back point, the
    # mid-chord face point, the back normal there, and the TE
    assert p2.left_cc[0] == gold([13.410785509967388, 7.341084349565501, -0.056416815365507314])
    assert p2.left_cc[120] == gold([14.96383882304009, 0.5422284123748101, -1.3331033062228674])
    assert p2.right_cc[120] == gold([14.998326555595384, 0.5826803894690532, 0.750218893954364])
    assert p2.left_normals[120] == gold([0.004631150800542271, -0.0347592416564838, -0.9993849846589296])
    assert p2.left_cc[-1] == gold([13.846841732894651, -6.290689983089794, 0.07174302165168438])
    # independently: unrolled, LE - TE is the chord c/D * D = 0.35 * 40 = 14 mm at the pitch angle
    # atan(P/D / (pi x)) with P/D = 1.0 at x = 0.75 (a table row)
    d = np.diff(unrolled(frame, p2.left_cc[[-1, 0]], 15.0), axis=0)[0]
    assert math.hypot(*d) == gold(14.0)
    assert math.atan2(d[1], d[0]) == gold(math.atan2(1.0, 0.75 * math.pi))
    # the largest face-back distance at equal chordwise station, unrolled, is the table's thickness
    # t0 = t0/c * c = 0.15 * 14 = 2.1 mm (laid off normal to the camber line; on the 241-point grid)
    t = np.linalg.norm(unrolled(frame, p2.left_cc, 15.0) - unrolled(frame, p2.right_cc, 15.0), axis=1)
    assert t.max() == pytest.approx(2.1, abs=1e-4)


# ---- section 3: cutter location (Eq. 1-2) ---------------------------------------------------------

def test_section3_cutter_location_eq1_2_by_hand():
    r = 0.5
    # rows: a thick place (2 mm), a thin place (0.2 mm), a sharp edge where the balls overlap
    cc_l = np.array([[0.0, 0, -1], [0, 0, -0.1], [0, 0, 0]])
    n_l = np.array([[0.0, 0, -1], [0, 0, -1], [0.6, 0, -0.8]])
    cc_r = np.array([[0.0, 0, 1], [0, 0, 0.1], [0, 0, 0]])
    n_r = np.array([[0.0, 0, 1], [0, 0, 1], [0.6, 0, 0.8]])
    c_l, c_r = ball_centres(cc_l, n_l, r), ball_centres(cc_r, n_r, r)
    # c = CC + r n, by hand
    assert np.allclose(c_l, [[0, 0, -1.5], [0, 0, -0.6], [0.3, 0, -0.4]], rtol=0, atol=1e-15)
    assert np.allclose(c_r, [[0, 0, 1.5], [0, 0, 0.6], [0.3, 0, 0.4]], rtol=0, atol=1e-15)
    p_l, w_l, p_r, w_r, spacing = symmetric_tools(c_l, c_r, r)  # Eq. 1-2, symmetrical pair
    # w_L = unit(c_L - c_R) = -Z, w_R = -w_L; p = c - r w; spacing |c_L - c_R| - 2r = 3-1, 1.2-1, 0.8-1
    assert np.allclose(w_l, [[0, 0, -1]] * 3, rtol=0, atol=1e-15)
    assert np.allclose(w_r, -w_l, rtol=0, atol=0)
    assert np.allclose(p_l, [[0, 0, -1], [0, 0, -0.1], [0.3, 0, 0.1]], rtol=0, atol=1e-15)
    assert np.allclose(p_r, [[0, 0, 1], [0, 0, 0.1], [0.3, 0, -0.1]], rtol=0, atol=1e-15)
    assert np.allclose(spacing, [2.0, 0.2, -0.2], rtol=0, atol=1e-15)
    # signed: the tips have crossed at the sharp edge, (p_L - p_R) . w_L = spacing
    assert np.allclose(np.einsum("ij,ij->i", p_l - p_r, w_l), spacing, rtol=0, atol=1e-15)
    # Eq. 1-2: tail p' = p + d_T w
    assert np.allclose(tail_points(p_l, w_l, D_T)[0], [0, 0, -41.0], rtol=0, atol=1e-15)
    with pytest.raises(PlanningError, match="coincide"):
        symmetric_tools(c_l[:1], c_l[:1], r)


# ---- section 3: double-curve interpolation (Eq. 3-15) --------------------------------------------

def test_section3_double_curve_interpolation(tiny):
    _, frame, _, _, paths, _ = tiny
    tmpl, _, name = sides(paths[2])
    _, cc, n = tmpl.at_knots()
    tails = tail_points(cc, n, D_T)
    assert np.allclose(tails, cc + D_T * n, rtol=0, atol=1e-12)  # Eq. 1-2 with p = CC, w = n
    ip = double_curve_interpolation(cc, tails, 1.0)
    # golden: the arc-length fallback, 16 points, length and step; one point and its axis
    assert (name, ip.mode, len(ip.s)) == ("left", "arc", 16)
    assert ip.curve.length == gold(14.46618461383985)
    assert ip.step == gold(0.9644123075893234)
    assert ip.tips[7] == gold([14.920327710937737, 1.086610415005856, -1.3488849031081391])
    assert ip.axes[7] == gold([-0.008798556865593457, -0.02033721144087744, -0.999754461469361])
    # independently: y is not monotonic (the rounded LE and TE turn back in Y_W), so 'arc' is forced
    dy = np.diff(cc[:, 1])
    assert (dy > 0).any() and (dy < 0).any()
    # the length is the limit of fine chords of the fitted curve, and above the coarse polyline
    t = np.linspace(ip.curve.t[0], ip.curve.t[-1], 200_001)
    assert arclength(ip.curve.point(t))[-1] == pytest.approx(ip.curve.length, abs=1e-6)
    assert arclength(cc)[-1] == pytest.approx(ip.curve.length, rel=1e-3)
    assert arclength(cc)[-1] < ip.curve.length
    # N = ceil(L / dd) equal arc-length steps L / N <= dd (Eq. 7-8), inverted exactly (Eq. 10-13)
    assert len(ip.s) - 1 == math.ceil(ip.curve.length / 1.0)
    assert ip.step == gold(ip.curve.length / 15) and ip.step <= 1.0
    assert np.allclose(ip.s, np.linspace(0, ip.curve.length, 16), rtol=0, atol=1e-12)
    assert np.allclose(ip.curve.arc_length(ip.params), ip.s, rtol=0, atol=1e-9)
    assert np.linalg.norm(np.diff(ip.tips, axis=0), axis=1).max() <= ip.step
    # the tips stay on the section cylinder; orientation w = unit(tail - tip) (Eq. 14-15)
    assert np.allclose(radius(frame, ip.tips), 15.0, rtol=0, atol=1e-7)
    w = (ip.tails - ip.tips) / np.linalg.norm(ip.tails - ip.tips, axis=1, keepdims=True)
    assert np.allclose(ip.axes, w, rtol=0, atol=1e-15)
    assert np.allclose(np.linalg.norm(ip.tails - ip.tips, axis=1), D_T, rtol=1e-5)


# ---- section 3: position data alignment (Eq. 16-21) ----------------------------------------------

def test_section3_position_data_alignment_symmetric(tiny):
    _, _, _, _, paths, pairs = tiny
    # golden per path: template side, fit mode, aligned point count, mean step, largest spacing
    expected = [
        ("left", "arc", 70, 0.0665332138140458, 0.6037408448083775),
        ("left", "arc", 109, 0.10929209648228787, 1.6544478873064872),
        ("left", "arc", 126, 0.11908067066704209, 2.0998411405147515),
        ("left", "arc", 127, 0.11868903207369216, 2.244525151927443),
        ("left", "arc", 127, 0.11976266376592462, 2.590553616498468),
    ]
    for path, pair, (tmpl, mode, n, step, smax) in zip(paths, pairs, expected, strict=True):
        assert (pair.kind, pair.template, pair.mode, len(pair.u)) == ("symmetric", tmpl, mode, n)
        assert pair.n_original == (241, 241)
        assert pair.step == gold(step)
        assert float(pair.spacing.max()) == gold(smax)
        # the template: equal counts, so the longer side (the back, cambered outward) is the template
        assert arclength(path.left_cc)[-1] > arclength(path.right_cc)[-1]
        # equal point counts on both sides, ratios from 0 to 1, non-decreasing
        assert len(pair.left_tip) == len(pair.right_tip) == len(pair.spacing) == n
        assert (pair.u[0], pair.u[-1]) == (0.0, 1.0) and (np.diff(pair.u) >= 0).all()
        # pair k sits at ratio u_k on both contact curves; the tips are Eq. 1-2 recomputed here
        tm, pj, name = sides(path)
        left, right = (tm, pj) if name == "left" else (pj, tm)
        cl, nl = left.at_ratio(pair.u)
        cr, nr = right.at_ratio(pair.u)
        c_l, c_r = cl + TOOL_R * nl, cr + TOOL_R * nr
        dist = np.linalg.norm(c_l - c_r, axis=1)
        w = (c_l - c_r) / dist[:, None]
        assert np.allclose(pair.left_axis, w, rtol=0, atol=1e-12)
        assert np.allclose(pair.right_axis, -w, rtol=0, atol=1e-12)
        assert np.allclose(pair.left_tip, c_l - TOOL_R * w, rtol=0, atol=1e-12)
        assert np.allclose(pair.right_tip, c_r + TOOL_R * w, rtol=0, atol=1e-12)
        assert np.allclose(pair.spacing, dist - 2 * TOOL_R, rtol=0, atol=1e-12)
        # symmetric axes on the tip line, spacing signed along w_L
        d = pair.left_tip - pair.right_tip
        assert np.allclose(np.cross(d, pair.left_axis), 0, rtol=0, atol=1e-12)
        assert np.allclose(np.einsum("ij,ij->i", d, pair.left_axis), pair.spacing, rtol=0, atol=1e-12)
        # template points never more than dd apart (chord subdivision near the edges adds more)
        assert np.linalg.norm(np.diff(template_tips(pair), axis=0), axis=1).max() <= DD * (1 + 1e-9)
        # triangle inequality: spacing <= |CC_L - CC_R| at every pair; the largest is close to the
        # largest face-back distance (within 3 %: the ball centres see the curvature of thin sections)
        assert (pair.spacing <= np.linalg.norm(cl - cr, axis=1) + 1e-12).all()
        thick = np.linalg.norm(path.left_cc - path.right_cc, axis=1).max()
        assert 0.97 * thick < smax <= thick
    pair = pairs[2]
    # golden pair 60 of path 2, and independently: the largest thickness t0 = 0.15 * 14 = 2.1 mm
    assert float(pair.spacing.max()) == pytest.approx(2.1, abs=1e-3)
    assert float(pair.u[60]) == gold(0.3801413378573362)
    assert pair.left_tip[60] == gold([14.763421055351005, 2.333895471327134, -1.3349857941100578])
    assert pair.right_tip[60] == gold([14.88310384828389, 2.330976374134976, 0.7191666938876986])
    assert pair.left_axis[60] == gold([-0.05816512995422181, 0.0014186639814301408, -0.9983059676521604])
    assert float(pair.spacing[60]) == gold(2.0576381936579633)
    assert np.linalg.norm(pair.left_tip[60] - pair.right_tip[60]) == gold(2.0576381936579633)
    # in the internal region the template tips are exactly the equidistant points: N = ceil(L / dd)
    # = 100 steps of L / N (L from the fine polyline, within 1e-5 mm of the fitted curve's length)
    s = arclength(template_tips(pair))
    assert math.ceil(s[-1] / DD) == 100
    reg = divide(pair.spacing, template_tips(pair), H_SAFE, K_MAX)
    seg = np.diff(s)[reg.labels[:-1] == "internal"]
    assert len(seg) == 84
    assert np.allclose(seg, s[-1] / 100, rtol=0, atol=2e-5)


def test_section3_position_data_alignment_single(tiny):
    _, frame, _, radii, paths, pairs = tiny
    # golden for the two tip-region paths: point count, step, the 10th tip of each side
    expected = {
        0: (75, 0.14706015354552326, [18.70377747449422, 3.4780037247474476, -0.4134363423175851],
            [18.714194243223645, 3.481727360983672, -0.2615871190659064]),
        1: (109, 0.1485571960456282, [16.603730486653948, -3.9971057615063934, 0.007535271315299241],
            [16.57725072400588, -3.9593074560401385, 0.38074002758736536]),
    }
    for i, (n, step, tip_l, tip_r) in expected.items():
        path, sym = paths[i], pairs[i]
        pair = align_single(path, DD, TOOL_R, D_T, symmetric=sym)
        assert (pair.kind, pair.template, pair.mode, len(pair.u)) == ("single", "left", "arc", n)
        assert pair.step == gold(step)
        assert pair.left_tip[10] == gold(tip_l)
        assert pair.right_tip[10] == gold(tip_r)
        # step = L / N <= dd; no two template tips further apart than that
        assert pair.step <= DD
        assert np.linalg.norm(np.diff(pair.left_tip, axis=0), axis=1).max() <= pair.step * (1 + 1e-9)
        assert (pair.u[0], pair.u[-1]) == (0.0, 1.0) and (np.diff(pair.u) > 0).all()
        # single-sided: tips are contact points, on the section cylinder on both sides
        for tips in (pair.left_tip, pair.right_tip):
            assert np.allclose(radius(frame, tips), radii[i], rtol=0, atol=1e-7)
        # the projection side (right) sits at the template's ratios, axes on its normals; the
        # template's axes (tip -> fitted tail) are its normals up to the spline error
        tmpl, proj, _ = sides(path)
        pp, pn = proj.at_ratio(pair.u)
        assert np.allclose(pair.right_tip, pp, rtol=0, atol=1e-12)
        assert np.allclose(pair.right_axis, pn, rtol=0, atol=1e-12)
        assert np.allclose(pair.left_axis, tmpl.at_ratio(pair.u)[1], rtol=0, atol=1e-4)
        # the region spacing is the symmetrical one, interpolated at these ratios
        assert np.allclose(pair.spacing, np.interp(pair.u, sym.u, sym.spacing), rtol=0, atol=1e-15)


# ---- section 4: region division (Table 1) ---------------------------------------------------------

def regions_by_hand(spacing, tips, h_safe, k_max):
    """Table 1 with a loop: (is_tip, ratio, a, b), a = first point above h_safe, b = one past the last."""
    s = arclength(tips)
    high = [x > h_safe for x in spacing]
    if not any(high):
        return True, 1.0, None, None
    a = high.index(True)
    b = len(high) - high[::-1].index(True)
    # edge length at each end, up to the first point above h_safe; variable as long again
    ratio = 2 * ((s[a] - s[0]) + (s[-1] - s[b - 1])) / s[-1]
    return (not all(high[a:b])) or ratio >= k_max, ratio, a, b


def runs(labels):
    """Run-length encoding of a label array: [(label, count), ...]."""
    out = []
    for x in labels:
        if out and out[-1][0] == x:
            out[-1][1] += 1
        else:
            out.append([x, 1])
    return [tuple(r) for r in out]


def test_section4_region_division_table1(tiny):
    _, _, _, _, _, pairs = tiny
    # golden per path: is_tip, reason, staggered ratio, boundary indices (S_vl, E_vl, S_vs, E_vs)
    expected = [
        (True, "staggered ratio >= k_max", 0.5592484707924159, None),
        (True, "staggered ratio >= k_max", 0.15848107665017996, None),
        (False, "", 0.11542801698169994, (15, 30, 114, 120)),
        (False, "", 0.11543054452024898, (7, 14, 99, 113)),
        (False, "", 0.09952333714124649, (10, 20, 113, 120)),
    ]
    for pair, (is_tip, reason, ratio, bounds) in zip(pairs, expected, strict=True):
        tips = template_tips(pair)
        reg = divide(pair.spacing, tips, H_SAFE, K_MAX)
        assert (reg.is_tip, reg.reason) == (is_tip, reason)
        assert reg.staggered_ratio == gold(ratio)
        # recomputed by hand from the spacing array
        h_tip, h_ratio, a, b = regions_by_hand(pair.spacing, tips, H_SAFE, K_MAX)
        assert h_tip == is_tip and h_ratio == gold(ratio)
        n = len(pair.spacing)
        if is_tip:
            assert reg.boundaries == {} and set(reg.labels) == {"tip"}
            continue
        sv, ev, ss, es = bounds
        assert reg.boundaries == {"S_vl": sv, "E_vl": ev, "E_ss": ev, "S_vs": ss, "S_sl": ss, "E_vs": es}
        # edge up to the first point above h_safe, variable as many points again, mirrored at the end
        assert (sv, es) == (a, b) and ev == 2 * a and ss == 2 * b - n
        assert runs(reg.labels) == [("edge", a), ("variable", a), ("internal", n - 2 * a - 2 * (n - b)),
                                    ("variable", n - b), ("edge", n - b)]
        assert (pair.spacing[reg.labels == "edge"] <= H_SAFE).all()
        assert (pair.spacing[reg.labels != "edge"] > H_SAFE).all()


def test_section4_divide_hand_made_spacing():
    n, h = 101, 0.25
    tips = np.arange(n)[:, None] * 0.2 * np.array([0.6, 0.8, 0.0])  # a line, s_k = 0.2 k, length 20
    spacing = np.ones(n)
    spacing[:2] = [-0.3, 0.25]           # 0.25 = h_safe is still edge (<= h_safe)
    spacing[98:] = [0.2, 0.1, -0.4]
    reg = divide(spacing, tips, h, 0.15)
    # by hand: a = 2, b = 98; edge lengths s_2 = 0.4 and s_100 - s_97 = 0.6 mm; ratio 2 * 1.0 / 20
    assert not reg.is_tip and reg.reason == ""
    assert reg.staggered_ratio == gold(0.1)
    assert reg.boundaries == {"S_vl": 2, "E_vl": 4, "E_ss": 4, "S_vs": 95, "S_sl": 95, "E_vs": 98}
    assert runs(reg.labels) == [("edge", 2), ("variable", 2), ("internal", 91), ("variable", 3), ("edge", 3)]
    # the ratio is (edge + variable length at both ends) / length: (s_4 + s_100 - s_94) / 20 = 2 / 20
    s = arclength(tips)
    assert (s[4] + s[-1] - s[94]) / s[-1] == gold(reg.staggered_ratio)
    # ratio >= K_max: the whole pair goes to the tip region
    reg = divide(spacing, tips, h, 0.099)
    assert (reg.is_tip, reg.reason, reg.boundaries) == (True, "staggered ratio >= k_max", {})
    assert reg.staggered_ratio == gold(0.1) and set(reg.labels) == {"tip"} and len(reg.labels) == n
    # a thin middle (one point at h_safe) cannot be machined symmetrically either
    thin = spacing.copy()
    thin[50] = h
    reg = divide(thin, tips, h, 0.15)
    assert (reg.is_tip, reg.reason) == (True, "thin middle: spacing <= h_safe inside the path")
    assert reg.staggered_ratio == gold(0.1) and set(reg.labels) == {"tip"}
    # nowhere above h_safe: tip, ratio 1
    reg = divide(np.full(n, 0.2), tips, h, 0.15)
    assert (reg.is_tip, reg.reason, reg.staggered_ratio) == (True, "spacing <= h_safe everywhere", 1.0)
    # an edge at the start only: ratio 2 * 0.4 / 20; the end boundaries both sit at n (no end stretch)
    one = spacing.copy()
    one[98:] = 1.0
    reg = divide(one, tips, h, 0.15)
    assert reg.staggered_ratio == gold(0.04)
    assert reg.boundaries == {"S_vl": 2, "E_vl": 4, "E_ss": 4, "S_vs": n, "S_sl": n, "E_vs": n}
    assert runs(reg.labels) == [("edge", 2), ("variable", 2), ("internal", 97)]
    # uneven tips: the ratio counts length, not points (edge points 0.5 mm apart, the rest 0.1 mm)
    step = np.r_[0.5, 0.5, np.full(96, 0.1), 0.5, 0.5]
    uneven = np.concatenate([[0.0], np.cumsum(step)])[:, None] * np.array([0.0, 1.0, 0.0])
    sp = np.ones(n)
    sp[[0, 1, -2, -1]] = 0.0
    reg = divide(sp, uneven, h, 0.5)
    # by hand: a = 2, b = 99; edge 1.0 + 1.0 mm of a 11.6 mm path, ratio 2 * 2 / 11.6; the variable
    # stretch has as many points as the edge (2), here only 0.2 mm long
    assert reg.staggered_ratio == gold(4.0 / 11.6)
    assert runs(reg.labels) == [("edge", 2), ("variable", 2), ("internal", 93), ("variable", 2), ("edge", 2)]
    assert reg.boundaries == {"S_vl": 2, "E_vl": 4, "E_ss": 4, "S_vs": 97, "S_sl": 97, "E_vs": 99}
