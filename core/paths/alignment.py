"""Position data alignment (paper section 3, Eq. 16-21; SPEC.md section 5).

The template side is the one with more original points (ties: the longer path); the other is the
projection side. Pair k of an aligned path sits at the same path-length ratio u_k of the contact curves
of both sides, so both sides get the same number of points.

Symmetrical pairs: for each original template point and its projection partner at the same ratio, the
cutter locations follow core.paths.cutter (axes on the ball-centre line). Those tool tips and tails are the
"original cutter position points" of the double-curve interpolation (core.paths.interpolation), which puts
the template tips at equal arc length dd; the ratio of every new point is mapped back through the
original points and the cutter locations are recomputed exactly there, so axes stay exactly on the
tip-to-tip line. Single-sided pairs (tip region): tips are the contact points and the axes the
normals, interpolated by the paper's double curve (tips and tails) on the template side and mapped by
the same ratios onto the projection side.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.paths.contours import ContourPath
from core.paths.cutter import symmetric_tools, tail_points
from core.paths.interpolation import (
    FittedCurve,
    chord_subdivisions,
    double_curve_interpolation,
    equidistant_params,
    fit_curve,
    subdivision_points,
)
from core.util.polyline import ball_centres, unit_rows

#: refinement passes of the original points of a symmetrical pair (see align_symmetric)
REFINE_PASSES = 3


@dataclass(frozen=True)
class SideCurve:
    """The contact curve of one side: CC points fitted with their normals as extra columns."""

    curve: FittedCurve
    n_original: int

    def at_ratio(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(k,) path-length ratios 0..1 -> (contact points (k, 3) mm, unit normals (k, 3))."""
        t = self.curve.param_at(np.asarray(u, float) * self.curve.length)
        v = self.curve.spline(t)
        return v[:, :3], unit_rows(v[:, 3:])

    def at_knots(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ratios (n,), contact points (n, 3) and unit normals (n, 3) at the original points."""
        v = self.curve.spline(self.curve.t)
        return self.curve.cum / self.curve.length, v[:, :3], unit_rows(v[:, 3:])


def side_curve(cc: np.ndarray, normals: np.ndarray) -> SideCurve:
    """Fit one side's contact points (n, 3) mm and unit normals (n, 3)."""
    return SideCurve(curve=fit_curve(cc, extra=normals), n_original=len(cc))


@dataclass(frozen=True)
class AlignedPair:
    """One aligned symmetrical pair of paths, N points per side, in machining order.

    u : (N,) path-length ratio of the contact points (same on both sides)
    left_tip, right_tip : (N, 3) float, mm, workpiece frame; left_axis, right_axis : (N, 3) unit
    spacing : (N,) float, mm, signed tip spacing of the symmetrical configuration (|c_L - c_R| - 2r)
    kind : 'symmetric' or 'single'; template : 'left' or 'right'; mode : fit of the template's
    original points, 'y' (the paper's) or 'arc' (fallback)
    """

    index: int
    r: float
    direction: int
    kind: str
    template: str
    mode: str
    u: np.ndarray
    left_tip: np.ndarray
    left_axis: np.ndarray
    right_tip: np.ndarray
    right_axis: np.ndarray
    spacing: np.ndarray
    n_original: tuple[int, int]
    step: float
    #: the surface normals at the contacts (N, 3) unit, per side (symmetrical pairs; on a single-sided
    #: pair the axes are the normals)
    left_normal: np.ndarray | None = None
    right_normal: np.ndarray | None = None


def sides(path: ContourPath) -> tuple[SideCurve, SideCurve, str]:
    """Fitted contact curves (template, projection) of a path and the template's name."""
    left = side_curve(path.left_cc, path.left_normals)
    right = side_curve(path.right_cc, path.right_normals)
    if (left.n_original, left.curve.length) >= (right.n_original, right.curve.length):
        return left, right, "left"
    return right, left, "right"


def _symmetric_at(left: SideCurve, right: SideCurve, u: np.ndarray, tool_radius: float):
    """Tips, axes and signed spacing of the symmetrical pairs at contact ratios u (``symmetric_tools``),
    then the contact normals of both sides."""
    cl, nl = left.at_ratio(u)
    cr, nr = right.at_ratio(u)
    tools = symmetric_tools(ball_centres(cl, nl, tool_radius), ball_centres(cr, nr, tool_radius), tool_radius)
    return (*tools, nl, nr)


def align_symmetric(path: ContourPath, dd: float, tool_radius: float, fitted=None) -> AlignedPair:
    """Aligned symmetrical pair of one contour path (axes on the ball-centre line).

    fitted : the result of ``sides(path)`` when the caller already has it.
    """
    tmpl, proj, name = fitted or sides(path)
    left, right = (tmpl, proj) if name == "left" else (proj, tmpl)
    u0, c_t, n_t = tmpl.at_knots()
    c_p, n_p = proj.at_ratio(u0)
    ct, cp = ball_centres(c_t, n_t, tool_radius), ball_centres(c_p, n_p, tool_radius)
    if name == "left":
        tips = symmetric_tools(ct, cp, tool_radius)[0]
    else:
        tips = symmetric_tools(cp, ct, tool_radius)[2]
    # near a rounded edge the tips sweep round the nose while the contacts barely move: refine the
    # original points there where neighbouring tips are more than dd/2 apart and move faster than
    # 1.5 times their contacts (elsewhere the tip curve is as smooth as the contacts), inserting as
    # many points as the gap needs in one go
    length = tmpl.curve.length
    for _ in range(REFINE_PASSES):
        d_tip = np.linalg.norm(np.diff(tips, axis=0), axis=1)
        gap = np.nonzero((d_tip > 0.5 * dd) & (d_tip > 1.5 * np.diff(u0) * length))[0]
        if gap.size == 0:
            break
        m = np.minimum(np.ceil(d_tip[gap] / (0.25 * dd)).astype(int), 64)
        frac = np.concatenate([np.arange(1, k) / k for k in m])
        owner = np.repeat(gap, m - 1)
        u_new = u0[owner] + frac * (u0[owner + 1] - u0[owner])
        pl_, _, pr_, *_ = _symmetric_at(left, right, u_new, tool_radius)
        u0 = np.insert(u0, owner + 1, u_new)
        tips = np.insert(tips, owner + 1, pl_ if name == "left" else pr_, axis=0)
    # the template's symmetrical tool tips are the original cutter position points; their ratios
    # ride along as an extra column so every interpolated point knows where it sits on the contacts
    curve = fit_curve(tips, extra=u0[:, None])
    t_new, s_new = equidistant_params(curve, dd)
    u = np.clip(curve.extra(t_new)[:, 0], 0.0, 1.0)
    u[0], u[-1] = u0[0], u0[-1]
    u = np.maximum.accumulate(u)
    pl, wl, pr, wr, spacing, nl, nr = _symmetric_at(left, right, u, tool_radius)
    # where the ball centres turn fast (rounded edges), add points so that straight moves between
    # them keep the balls on the offset surface (core.paths.interpolation.chord_subdivisions)
    for _ in range(SUBDIVISION_ROUNDS):
        pieces = np.maximum(chord_subdivisions(ball_centres(pl, wl, tool_radius), wl),
                            chord_subdivisions(ball_centres(pr, wr, tool_radius), wr))
        if (pieces == 1).all():
            break
        u_new = subdivision_points(u, pieces)
        new = _symmetric_at(left, right, u_new, tool_radius)  # only the new points
        order = np.argsort(np.concatenate([u, u_new]), kind="stable")
        u = np.concatenate([u, u_new])[order]
        pl, wl, pr, wr, spacing, nl, nr = (np.concatenate([a, b])[order]
                                           for a, b in zip((pl, wl, pr, wr, spacing, nl, nr), new, strict=True))
    return AlignedPair(index=path.index, r=path.r, direction=path.direction, kind="symmetric",
                       template=name, mode=tmpl.curve.mode, u=u, left_tip=pl, left_axis=wl,
                       right_tip=pr, right_axis=wr, spacing=spacing,
                       n_original=(len(path.left_cc), len(path.right_cc)),
                       step=curve.length / max(len(u) - 1, 1), left_normal=nl, right_normal=nr)


#: rounds of chord subdivision (each re-estimates on the new points; at the closing tip, where the ball
#: rolls round an LE of a few hundredths of a millimetre, two rounds left chords 5 times the tolerance)
SUBDIVISION_ROUNDS = 6


def align_single(path: ContourPath, dd: float, tool_radius: float, tool_length: float,
                 fitted=None, symmetric: AlignedPair | None = None) -> AlignedPair:
    """Aligned pair for single-sided machining (tip region): axes on the normals, tips = contacts.

    The template side's tips and tails (CC and CC + d_T n at its original points) go through the
    double-curve interpolation; the projection side is taken at the same contact-curve ratios.
    """
    tmpl, proj, name = fitted or sides(path)
    _, cc_t, n_t = tmpl.at_knots()
    interp = double_curve_interpolation(cc_t, tail_points(cc_t, n_t, tool_length), dd)
    params, tips_t, axes_t = interp.params, interp.tips, interp.axes
    u = interp.s / interp.s[-1]
    p_p, n_p = proj.at_ratio(u)
    for _ in range(SUBDIVISION_ROUNDS):  # keep straight moves of both balls on the offset surface
        pieces = np.maximum(chord_subdivisions(ball_centres(tips_t, axes_t, tool_radius), axes_t),
                            chord_subdivisions(ball_centres(p_p, n_p, tool_radius), n_p))
        if (pieces == 1).all():
            break
        p_new = subdivision_points(params, pieces)  # evaluate only the new points, then merge
        curve = interp.curve
        t_new, tails = curve.point(p_new), curve.extra(p_new)
        a_new = (tails - t_new) / np.linalg.norm(tails - t_new, axis=1, keepdims=True)
        u_new = np.clip(curve.arc_length(p_new) / curve.length, 0.0, 1.0)
        pp_new, np_new = proj.at_ratio(u_new)
        order = np.argsort(np.concatenate([params, p_new]), kind="stable")
        params, tips_t, axes_t, u, p_p, n_p = (
            np.concatenate([a, b])[order]
            for a, b in zip((params, tips_t, axes_t, u, p_p, n_p), (p_new, t_new, a_new, u_new, pp_new, np_new),
                            strict=True))
    if name == "left":
        pl, wl, pr, wr = tips_t, axes_t, p_p, n_p
        left, right = tmpl, proj
    else:
        pl, wl, pr, wr = p_p, n_p, tips_t, axes_t
        left, right = proj, tmpl
    # the symmetrical spacing still decides the region: report it alongside (interpolated from the
    # symmetrical alignment when the caller has it, else computed at these ratios)
    if symmetric is not None:
        spacing = np.interp(u, symmetric.u, symmetric.spacing)
    else:
        spacing = _symmetric_at(left, right, u, tool_radius)[4]
    return AlignedPair(index=path.index, r=path.r, direction=path.direction, kind="single",
                       template=name, mode=interp.mode, u=u, left_tip=pl, left_axis=wl,
                       right_tip=pr, right_axis=wr, spacing=spacing,
                       n_original=(len(path.left_cc), len(path.right_cc)), step=interp.step)
