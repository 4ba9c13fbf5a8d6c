"""CAD blades made from a geometry table for the tests (OpenCASCADE through OCP): each side a cubic
B-spline surface interpolating the table's own surface points on a grid of radii and chordwise
stations, written as STEP or IGES, as a face/back pair or as one closed solid (the two sides and
ruled caps at the hub and the tip, sewn).

The interpolation is done here (scipy, not-a-knot cubics) in the parameters (i / (n_r - 1), j / (m - 1))
of the grid: with cosine-spaced stations a table's surface is a smooth function of those (a section's
nose, like sqrt(x/c), is sin(pi v / 2)), so the surface follows the table closely between the grid
points too (OpenCASCADE's own interpolation, by chord length, rings near the LE)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.interpolate import make_interp_spline


def grid(table, n_r: int, m: int, r_max: float = 0.995):
    """The table's face and back points (n_r, m, 3) at n_r radii from the hub to r_max of the tip and
    m cosine-spaced chordwise stations."""
    radii = np.linspace(table.hub_radius, r_max * table.tip_radius, n_r)
    xi = 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, m)))
    face, back = table.surface_points(np.repeat(radii, m), np.tile(xi, n_r))
    return face.reshape(n_r, m, 3), back.reshape(n_r, m, 3)


def bspline_surface(points: np.ndarray):
    """A Geom_BSplineSurface interpolating points (n_r, m, 3) at u = i / (n_r - 1), v = j / (m - 1)."""
    from OCP.collections import Array1_double, Array1_int, Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    n_r, m, _ = points.shape
    sv = make_interp_spline(np.linspace(0.0, 1.0, m), points, k=3, axis=1)
    su = make_interp_spline(np.linspace(0.0, 1.0, n_r), sv.c, k=3, axis=1)
    poles = su.c
    arr = Array2_gp_Pnt(1, poles.shape[0], 1, poles.shape[1])
    for i in range(poles.shape[0]):
        for j in range(poles.shape[1]):
            arr.SetValue(i + 1, j + 1, gp_Pnt(*map(float, poles[i, j])))

    def knots(t):
        k, mult = np.unique(t, return_counts=True)
        a, b = Array1_double(1, len(k)), Array1_int(1, len(k))
        for i, (x, c) in enumerate(zip(k, mult, strict=True)):
            a.SetValue(i + 1, float(x))
            b.SetValue(i + 1, int(c))
        return a, b

    (uk, um), (vk, vm) = knots(su.t), knots(sv.t)
    return Geom_BSplineSurface(arr, uk, vk, um, vm, 3, 3)


def side_faces(table, n_r: int = 40, m: int = 241):
    """The face and back of the table's blade as two TopoDS_Face."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    return [BRepBuilderAPI_MakeFace(bspline_surface(g), 1e-7).Face() for g in grid(table, n_r, m)]


def solid(table, n_r: int = 40, m: int = 241):
    """The table's blade as one closed solid: face, back and ruled caps at the hub and the tip."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepFill import BRepFill
    from OCP.TopoDS import TopoDS

    face_g, back_g = grid(table, n_r, m)
    surfaces = [bspline_surface(g) for g in (face_g, back_g)]
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    sew = BRepBuilderAPI_Sewing(1e-6)
    for s in surfaces:
        sew.Add(BRepBuilderAPI_MakeFace(s, 1e-7).Face())
    for u in (0.0, 1.0):
        e1, e2 = (BRepBuilderAPI_MakeEdge(s.UIso(u)).Edge() for s in surfaces)
        sew.Add(BRepFill.Face_s(e1, e2))
    sew.Perform()
    shell = TopoDS.Shell(sew.SewedShape())
    return BRepBuilderAPI_MakeSolid(shell).Solid()


def write(shape, path: Path) -> Path:
    """Write a shape as STEP (.step, .stp) or IGES (.igs, .iges), in millimetres."""
    from core.blade.cad import _quiet

    _quiet()
    if path.suffix.lower() in (".step", ".stp"):
        from OCP.STEPControl import STEPControl_StepModelType, STEPControl_Writer

        w = STEPControl_Writer()
        w.Transfer(shape, STEPControl_StepModelType.STEPControl_AsIs)
        w.Write(str(path))
    else:
        from OCP.IGESControl import IGESControl_Writer

        w = IGESControl_Writer("MM", 1)
        w.AddShape(shape)
        w.ComputeModel()
        w.Write(str(path))
    return path


def propeller(table, blades: int, hub_radius: float, n_r: int = 40, m: int = 241, solids: bool = False):
    """A whole propeller: the table's blade (its face and back, or with ``solids`` its closed solid)
    in ``blades`` copies 360/blades degrees apart about Z (the first where the table puts it), and a hub
    cylinder of ``hub_radius`` about Z (its end discs included) across the blades' roots, as one
    compound."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp, gp_Ax2, gp_Pnt, gp_Trsf
    from OCP.TopoDS import TopoDS_Compound

    parts = [solid(table, n_r, m)] if solids else side_faces(table, n_r, m)
    face_g, back_g = grid(table, 2, 3)
    z = np.concatenate([face_g[0, :, 2], back_g[0, :, 2]])
    low, high = float(z.min()) - 5.0, float(z.max()) + 5.0
    out, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(out)
    for k in range(blades):
        turn = gp_Trsf()
        turn.SetRotation(gp.OZ_s(), 2.0 * np.pi * k / blades)
        for p in parts:
            builder.Add(out, BRepBuilderAPI_Transform(p, turn, True).Shape())
    builder.Add(out, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0.0, 0.0, low), gp.DZ_s()), hub_radius, high - low).Shape())
    return out
