"""A blade read from exact CAD surfaces: STEP (.step, .stp) or IGES (.igs, .iges) through OpenCASCADE
(the package cadquery-ocp-novtk, imported here only, when a CAD file is read: never at start-up).

Two kinds of source, as for meshes (core.blade.mesh): one file holding one closed blade (a solid or a
closed shell: face, back and the caps), or two files holding the face and the back (each one or more
faces). Every face is converted to a NURBS surface (BRepBuilderAPI_NurbsConvert: planes, cylinders
and B-splines alike), whose poles, weights and knots are evaluated here with numpy (core.blade.bspline,
on homogeneous coordinates), vectorised over points.

Sections are exact:
- which pieces the cylinder r cuts, in which order, and where LE and TE lie, come from BRepMesh's
  tessellation of the faces at SECTION_DEFLECTION (its cut is the mesh blade's: core.blade.mesh, so a
  closed blade is split at LE and TE and a pair joined there exactly as a mesh is);
- every point is then moved onto the exact intersection of the surface with the cylinder (Newton
  steps in the face's (u, v), each the smallest move in space that reaches the cylinder, so a point
  slides along the section by no more than the tessellation's error squared), and points are inserted
  on that exact curve, evenly in the face's parameters, about STEP apart;
- normals are the surfaces' own: S_u x S_v, turned outward (a closed blade's faces by the blade's
  volume, each surface of a pair away from the other).
Where the tessellation's straight boundary chord and a trimmed face's boundary curve differ, the LE and
TE of a pair are off by that chord error (< SECTION_DEFLECTION) along the edge; a face bounded by its
parameter lines (untrimmed) ends exactly.

Units: OpenCASCADE converts the file's length unit to millimetres when it reads the file.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from core.blade.bspline import TensorSpline
from core.blade.mesh import MeshBlade
from core.blade.mesh_sections import Polyline
from core.blade.propeller import clip_outside
from core.errors import BladeInputError
from core.util.files import file_problem

CAD_SUFFIXES = (".step", ".stp", ".igs", ".iges")
#: chordal tolerance (mm) of the tessellation whose cut orders the sections' points
SECTION_DEFLECTION = 0.2
#: angular tolerance (rad) of that tessellation
SECTION_ANGLE = 0.3
#: chordal (mm) and angular (rad) tolerance of the tessellation the gouge guard and bladecam verify check
#: the balls against (CadBlade.facets): where the blade is concave its facets lie up to this far off it
#: towards the balls, which the guard then pushes out by as much
CHECK_DEFLECTION = 0.01
CHECK_ANGLE = 0.2
#: exact section points lie about this far apart (mm; evenly in the parameters between two points of the
#: tessellation's cut, so up to the parametrisation's change of speed over a triangle more)
STEP = 0.25
#: a tangent shorter than this share of the other is taken as vanishing (a degenerate parametrisation at
#: an edge of the face's parameter box, see Patch.normals)
DEGENERATE = 1e-4
#: Newton steps onto the surface's section: at most NEWTON_ROUNDS, until every point is within
#: NEWTON_TOLERANCE (mm) of the cylinder; a section with a point still farther than SECTION_TOLERANCE
#: (mm) after them is refused
NEWTON_ROUNDS = 12
NEWTON_TOLERANCE = 1e-9
SECTION_TOLERANCE = 1e-6
#: the package that reads CAD files, and what to install when it is missing
OCP_PACKAGE = "cadquery-ocp-novtk"


def _ocp_missing(path: str) -> BladeInputError:
    return BladeInputError(f"{path}: reading STEP and IGES files needs OpenCASCADE (the Python package "
                           f"{OCP_PACKAGE}), which is not installed: pip install {OCP_PACKAGE}, or export the "
                           "blade as a mesh (STL)")


def _quiet() -> None:
    """OpenCASCADE's readers print their statistics to stdout: only failures are let through."""
    from OCP.Message import Message, Message_Gravity

    for printer in Message.DefaultMessenger_s().Printers():
        printer.SetTraceLevel(Message_Gravity.Message_Fail)


def read_cad(path: str | Path):
    """The shape in a STEP or IGES file (TopoDS_Shape, mm), with its faces converted to NURBS.

    Raises BladeInputError naming the file: missing, empty, unsupported, unreadable, no faces."""
    p = Path(path)
    problem = file_problem(p)
    if problem == "not found":
        raise BladeInputError(f"{p}: CAD file not found; check the path")
    if problem is not None:
        raise BladeInputError(f"{p}: {problem}; give a STEP or IGES file")
    suffix = p.suffix.lower()
    if suffix not in CAD_SUFFIXES:
        raise BladeInputError(f"{p}: unsupported CAD format {p.suffix!r}; give a STEP (.step, .stp) or IGES "
                              "(.igs, .iges) file")
    if p.stat().st_size == 0:
        raise BladeInputError(f"{p}: the file is empty; export the blade again")
    try:
        from OCP.BRep import BRep_Tool
        from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
        from OCP.Geom import Geom_BSplineSurface
        from OCP.IFSelect import IFSelect_ReturnStatus
        from OCP.IGESControl import IGESControl_Reader
        from OCP.STEPControl import STEPControl_Reader
    except ImportError:
        raise _ocp_missing(str(p)) from None
    _quiet()
    fmt = "STEP" if suffix in (".step", ".stp") else "IGES"
    reader = STEPControl_Reader() if fmt == "STEP" else IGESControl_Reader()
    if reader.ReadFile(str(p)) != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise BladeInputError(f"{p}: not a readable {fmt} file; export the blade again as {fmt} (or as STL)")
    reader.TransferRoots()
    shape = reader.OneShape()
    if shape.IsNull() or not _faces(shape):
        raise BladeInputError(f"{p}: the {fmt} file holds no surfaces (curves or points only?); export the "
                              "blade's surfaces or solid")
    if all(isinstance(BRep_Tool.Surface_s(f), Geom_BSplineSurface) for f in _faces(shape)):
        return shape  # (B-splines already, the usual case: converting copies them for nothing)
    return BRepBuilderAPI_NurbsConvert(shape, True).Shape()


def _faces(shape) -> list:
    from OCP.TopAbs import TopAbs_ShapeEnum
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    out, ex = [], TopExp_Explorer(shape, TopAbs_ShapeEnum.TopAbs_FACE)
    while ex.More():
        out.append(TopoDS.Face(ex.Current()))
        ex.Next()
    return out


class Patch:
    """One face as a NURBS surface S(u, v), file frame, mm, evaluated with numpy (vectorised).

    bounds : (u0, u1, v0, v1), the face's parameter box; sign : +1 or -1, S_u x S_v times it points
    out of the material as the face is oriented in its shape."""

    def __init__(self, face):
        from OCP.BRep import BRep_Tool
        from OCP.BRepTools import BRepTools
        from OCP.TopAbs import TopAbs_Orientation

        srf = BRep_Tool.Surface_s(face)
        if srf.IsUPeriodic() or srf.IsVPeriodic():
            srf = srf.Copy()
            if srf.IsUPeriodic():
                srf.SetUNotPeriodic()
            if srf.IsVPeriodic():
                srf.SetVNotPeriodic()
        nu, nv = srf.NbUPoles(), srf.NbVPoles()
        pole, weight = srf.Pole, srf.Weight
        q = np.array([pole(i, j).Coord() for i in range(1, nu + 1) for j in range(1, nv + 1)]).reshape(nu, nv, 3)
        w = np.ones((nu, nv, 1))
        if srf.IsURational() or srf.IsVRational():
            w = np.array([weight(i, j) for i in range(1, nu + 1) for j in range(1, nv + 1)]).reshape(nu, nv, 1)
        h = np.concatenate([q * w, w], axis=2)
        knots = [np.array([seq.Value(k) for k in range(1, seq.Length() + 1)])
                 for seq in (srf.UKnotSequence(), srf.VKnotSequence())]
        self._spline = TensorSpline((knots[0], knots[1]), h, (srf.UDegree(), srf.VDegree()))
        self.bounds = tuple(BRepTools.UVBounds_s(face))
        self.sign = -1.0 if face.Orientation() == TopAbs_Orientation.TopAbs_REVERSED else 1.0

    def evaluate(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """S, S_u, S_v at the parameters uv (n, 2): three (n, 3) float arrays, file frame."""
        h = self._spline(uv)
        hu, hv = self._spline(uv, nu=(1, 0)), self._spline(uv, nu=(0, 1))
        w = h[:, 3:]
        s = h[:, :3] / w
        return s, (hu[:, :3] - s * hu[:, 3:]) / w, (hv[:, :3] - s * hv[:, 3:]) / w

    def onto_cylinder(self, uv: np.ndarray, r: float, rot: np.ndarray,
                      origin: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Newton steps from uv (n, 2) onto the section of the surface with the cylinder r about the
        blade frame's Z axis (p_blade = rot @ (p - origin)); each the smallest move in space reaching
        the cylinder to first order, along the parameter line of the box's edge where it would leave
        the parameter box. Returns (uv (n, 2), points (n, 3) and unit normals (n, 3), blade frame,
        normals times ``sign``)."""
        uv = np.array(uv, float)
        u0, u1, v0, v1 = self.bounds
        lo, hi = np.array([u0, v0]), np.array([u1, v1])
        # a point that starts on an edge of the parameter box (a pair's LE or TE on a face bounded by its
        # parameter lines) moves along that edge only
        eps = 1e-12 * (hi - lo)
        edge = (uv <= lo + eps) | (uv >= hi - eps)
        for _ in range(NEWTON_ROUNDS):
            s, su, sv = (x @ rot.T for x in self.evaluate(uv))
            s = s - origin @ rot.T
            f = s[:, 0] ** 2 + s[:, 1] ** 2 - r * r
            if np.all(np.abs(f) <= 2.0 * r * NEWTON_TOLERANCE):
                break
            g = 2.0 * np.column_stack([s[:, 0] * su[:, 0] + s[:, 1] * su[:, 1],
                                       s[:, 0] * sv[:, 0] + s[:, 1] * sv[:, 1]])
            e, ff, gg = (su * su).sum(1), (su * sv).sum(1), (sv * sv).sum(1)
            det = e * gg - ff * ff
            with np.errstate(divide="ignore", invalid="ignore"):
                a = np.column_stack([gg * g[:, 0] - ff * g[:, 1], e * g[:, 1] - ff * g[:, 0]]) / det[:, None]
                step = -f[:, None] * a / (g * a).sum(1, keepdims=True)
                out = ((uv + step < lo) | (uv + step > hi)) & ~edge[:, ::-1]
                # along the box's edge: only the other parameter moves
                one = np.where((out | edge)[:, :1], np.column_stack([np.zeros_like(f), -f / g[:, 1]]),
                               np.column_stack([-f / g[:, 0], np.zeros_like(f)]))
            step = np.where((out | edge).any(axis=1, keepdims=True), one, step)
            uv = np.clip(uv + np.nan_to_num(step), lo, hi)
        s, su, sv = (x @ rot.T for x in self.evaluate(uv))
        s = s - origin @ rot.T
        return uv, s, self.normals(uv, su, sv, rot)

    def normals(self, uv: np.ndarray, su: np.ndarray, sv: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """Unit normals sign * S_u x S_v (n, 3) at uv (n, 2) from the tangents su, sv (n, 3) (frame of
        ``rot``). Where a tangent (nearly) vanishes, at or next to an edge of the parameter box (a
        degenerate parametrisation, such as a section's TE stations crowding as (1 - v)^2), its
        direction is ill-conditioned and the limit direction is used: the second derivative, pointing
        into the box from the nearer edge."""
        u0, u1, v0, v1 = self.bounds
        for k, (t, lo, hi) in enumerate(((su, u0, u1), (sv, v0, v1))):
            other = sv if k == 0 else su
            weak = np.linalg.norm(t, axis=1) <= DEGENERATE * np.linalg.norm(other, axis=1)
            if weak.any():
                nu = (2, 0) if k == 0 else (0, 2)
                h, hd = self._spline(uv[weak]), self._spline(uv[weak], nu=nu)
                second = (hd[:, :3] - h[:, :3] / h[:, 3:] * hd[:, 3:]) / h[:, 3:]  # (a tangent's own part is ~0)
                into = np.where(np.abs(uv[weak, k] - lo) <= np.abs(uv[weak, k] - hi), 1.0, -1.0)
                t = t.copy()
                t[weak] = (second @ rot.T) * into[:, None]
                if k == 0:
                    su = t
                else:
                    sv = t
        n = np.cross(su, sv) * self.sign
        return n / np.linalg.norm(n, axis=1, keepdims=True)


def tessellate(shape, deflection: float, angle: float = SECTION_ANGLE):
    """BRepMesh's tessellation of a shape at the chordal tolerance ``deflection`` (mm): vertices (V, 3)
    (merged where faces share them), triangles (T, 3) int oriented as their faces, the face of each
    triangle (T,) int (an index into ``_faces(shape)``) and the parameters of each triangle's corners
    (T, 3, 2) on its face."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopAbs import TopAbs_Orientation
    from OCP.TopLoc import TopLoc_Location

    BRepMesh_IncrementalMesh(shape, deflection, False, angle, True)
    verts, tris, face_of, corner_uv, base = [], [], [], [], 0
    for k, face in enumerate(_faces(shape)):
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face, loc)
        if tri is None or tri.NbTriangles() == 0:
            continue
        n, node, uv_node, triangle = tri.NbNodes(), tri.Node, tri.UVNode, tri.Triangle
        pts = np.array([node(i).Coord() for i in range(1, n + 1)])
        if not loc.IsIdentity():
            trsf = loc.Transformation()
            m = np.array([[trsf.Value(r, c) for c in range(1, 5)] for r in range(1, 4)])  # (scale included)
            pts = pts @ m[:, :3].T + m[:, 3]
        uv = np.array([uv_node(i).Coord() for i in range(1, n + 1)])
        t = np.array([triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)]) - 1
        if face.Orientation() == TopAbs_Orientation.TopAbs_REVERSED:
            t = t[:, ::-1]
        verts.append(pts)
        tris.append(t + base)
        face_of.append(np.full(len(t), k))
        corner_uv.append(uv[t])
        base += n
    if not tris:
        raise BladeInputError("the CAD surfaces could not be tessellated (degenerate faces?); export the blade "
                              "again, or as a mesh (STL)")
    # the faces' copies of the nodes on their shared edges (the same polygon) are one vertex; nothing
    # else is merged (a blade's sides come within micrometres of each other at a closed TE)
    v = np.concatenate(verts)
    _, first, inverse = np.unique(v, axis=0, return_index=True, return_inverse=True)
    return v[first], inverse.ravel()[np.concatenate(tris)], np.concatenate(face_of), np.concatenate(corner_uv)


class FaceGroup:
    """The faces of one CAD file or of one side of a blade (file frame, mm): their patches (made on
    first use) and the tessellation the sections are ordered by (``tessellate``'s arrays, face_of
    indexing ``faces``)."""

    def __init__(self, faces: Sequence, vertices: np.ndarray, triangles: np.ndarray, face_of: np.ndarray,
                 corner_uv: np.ndarray):
        import trimesh

        self.faces = list(faces)
        self._patches: dict[int, Patch] = {}
        self.triangles, self.face_of, self.corner_uv = triangles, face_of, corner_uv
        self.mesh = trimesh.Trimesh(vertices, triangles, process=False)
        self.nv = len(vertices)

    @classmethod
    def of_shape(cls, shape, deflection: float = SECTION_DEFLECTION) -> FaceGroup:
        """All the faces of a shape, tessellated at ``deflection`` (mm)."""
        return cls(_faces(shape), *tessellate(shape, deflection))

    def patch(self, k: int) -> Patch:
        """The NURBS surface of face k."""
        if k not in self._patches:
            self._patches[k] = Patch(self.faces[k])
        return self._patches[k]

    def parameters(self, tri: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Parameters (n, 2) on the faces of triangles ``tri`` (n,) of points p (n, 3) in (or next to)
        them (``corner_parameters``)."""
        return corner_parameters(self.mesh.vertices[self.triangles[tri]], self.corner_uv[tri], p)


def corner_parameters(corners: np.ndarray, corner_uv: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Parameters (n, 2) of points p (n, 3) in (or next to) triangles with corners (n, 3, 3) whose
    parameters are corner_uv (n, 3, 2): the corners' parameters weighted by p's barycentric coordinates
    in the triangle's plane (clamped to the triangle)."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    v0, v1, v2 = b - a, c - a, p - a
    d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
    d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
    den = d00 * d11 - d01 * d01
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.column_stack([(d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den])
    lam = np.clip(np.nan_to_num(lam), 0.0, 1.0)
    lam = np.column_stack([1.0 - lam.sum(1), lam])
    lam = np.maximum(lam, 0.0)
    lam /= lam.sum(1, keepdims=True)
    return np.einsum("nk,nkj->nj", lam, corner_uv)


def compound(faces: Sequence):
    """One TopoDS_Compound of the faces."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    out, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(out)
    for f in faces:
        builder.Add(out, f)
    return out


class CadBlade(MeshBlade):
    """A blade from exact CAD surfaces: one closed blade, or two surfaces (face, back), in the blade
    frame of core.blade.model (axis and origin as for a mesh, core.blade.mesh).

    groups : one or two FaceGroup (one closed blade; or face, back); files : their names; step : mm, the
    largest distance between section points; deflection : mm, the chordal tolerance of the
    tessellation that orders them; r_min : mm, the hub cut of a blade picked out of a whole propeller
    (its check tessellation is cut there too; None: the whole faces). Attributes: transform (4, 4)
    file -> blade frame, closed, warnings."""

    faceted = False  # (sections on the exact surface: no facets' error to report)

    def __init__(self, groups: Sequence[FaceGroup], files: Sequence[str], axis: str = "z",
                 origin: Sequence[float] = (0.0, 0.0, 0.0), step: float = STEP,
                 deflection: float = SECTION_DEFLECTION, r_min: float | None = None):
        self.deflection = float(deflection)
        self._r_min = r_min
        self._facets: tuple[np.ndarray, np.ndarray] | None = None
        self._groups = list(groups)
        self._rot = np.eye(3)
        self._org = np.zeros(3)
        self._signs: list[np.ndarray] | None = None
        super().__init__([g.mesh for g in self._groups], files, axis=axis, origin=origin, step=step)

    def _face_signs(self) -> list[np.ndarray]:
        """Per group, per face: +1 or -1 so that sign * patch.sign * S_u x S_v points the way the
        blade's oriented tessellation does (outward: core.blade.mesh), voted by its triangles."""
        if self._signs is None:
            self._rot, self._org = self.transform[:3, :3], np.asarray(self._origin_file)
            out = []
            for g, srf in zip(self._groups, self._surfaces, strict=True):
                centre_uv = g.corner_uv.mean(axis=1)
                votes = np.zeros(len(g.faces))
                for k in np.unique(g.face_of):
                    idx = np.flatnonzero(g.face_of == k)
                    patch = g.patch(k)
                    if idx.size:
                        s, su, sv = patch.evaluate(centre_uv[idx])
                        n = np.cross(su, sv) @ self._rot.T * patch.sign
                        votes[k] = np.einsum("ij,ij->", n, srf.face_normals[idx])
                out.append(np.where(votes < 0, -1.0, 1.0))
            self._signs = out
        return self._signs

    @property
    def _origin_file(self) -> np.ndarray:
        """The file-frame point that maps to the blade frame's origin."""
        return -self.transform[:3, :3].T @ self.transform[:3, 3]

    def _split_loop(self, r: float, loop: Polyline) -> tuple[Polyline, Polyline]:
        """A closed blade's loop made exact first (its points on the surfaces' section, STEP apart),
        then split at LE and TE as a mesh's is (so LE and TE are found on the exact section)."""
        r_cut = float(np.hypot(*loop.points[0, :2]))
        ring = Polyline(np.vstack([loop.points, loop.points[:1]]), loop.normals, loop.turn, loop.facet_normals,
                        False, loop.facets)
        pts, nrm = self._exact(self._groups[0], self._face_signs()[0], ring, r_cut)
        pts, nrm = pts[:-1], nrm[:-1]
        exact = Polyline(pts, nrm, np.zeros(len(pts)), np.zeros((len(pts), 3)), True, None)
        return super()._split_loop(r, exact)

    def _sample(self, face: Polyline, back: Polyline, r_cut: float,
                r: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """Exact points and normals along face and back (see the module), put on the cylinder r (the
        parts of a closed blade's loop are exact already: _split_loop)."""
        signs = self._face_signs()
        out = []
        groups = [0, 0] if len(self._groups) == 1 else [0, 1]
        for part, gi in zip((face, back), groups, strict=True):
            if part.facets is None:
                pts, nrm = part.points.copy(), part.normals.copy()
            else:
                pts, nrm = self._exact(self._groups[gi], signs[gi], part, r_cut)
            pts[:, :2] *= (r / np.hypot(pts[:, 0], pts[:, 1]))[:, None]
            out.append((pts, nrm))
        return out

    def _exact(self, g: FaceGroup, signs: np.ndarray, part: Polyline, r_cut: float) -> tuple[np.ndarray, np.ndarray]:
        """The points of one side on the exact section at r_cut, about STEP apart, with normals."""
        n = len(part.points)
        fac = part.facets.copy()
        for k in range(1, len(fac)):  # (a step on no known facet: its predecessor's, as a guess)
            if fac[k] < 0:
                fac[k] = fac[k - 1]
        if fac[0] < 0:
            fac[0] = fac[fac >= 0][0]
        pts_b = part.points @ self._rot + self._org  # the tessellation's frame: the file's
        start = g.parameters(fac, pts_b[:-1])
        end = g.parameters(fac, pts_b[1:])
        uv = np.concatenate([start, end[-1:]])
        for i, f in ((0, fac[0]), (-1, fac[-1])):
            # an end in a triangle with a side on an edge of its face's parameter box (a pair's LE or TE on
            # a face bounded by its parameter lines) lies on that edge
            box = np.array(g.patch(g.face_of[f]).bounds).reshape(2, 2)
            on = np.abs(g.corner_uv[f][:, :, None] - box[None]) <= 1e-9 * (box[:, 1:] - box[:, :1])[None]
            side = on.sum(axis=0) >= 2  # (param, bound): two corners on it
            for k, b in zip(*np.nonzero(side), strict=True):
                uv[i, k] = box[k, b]
        face = g.face_of[np.append(fac, fac[-1])]
        # inner points of each step on its own face, evenly in the parameters between its ends
        length = np.linalg.norm(np.diff(part.points, axis=0), axis=1)
        inner = np.ceil(length / self.step).astype(int) - 1
        step_of = np.repeat(np.arange(n - 1), inner)
        j = np.arange(step_of.size) - np.repeat(np.cumsum(inner) - inner, inner) + 1
        w = (j / (inner[step_of] + 1.0))[:, None]
        in_uv = (1.0 - w) * start[step_of] + w * end[step_of]
        in_face = g.face_of[fac[step_of]]
        all_uv, all_face = np.concatenate([uv, in_uv]), np.concatenate([face, in_face])
        pts, nrm = np.empty((len(all_uv), 3)), np.empty((len(all_uv), 3))
        for f in np.unique(all_face):
            m = all_face == f
            _, p, q = g.patch(f).onto_cylinder(all_uv[m], r_cut, self._rot, self._org)
            pts[m], nrm[m] = p, q * signs[f]
        # the order: point i, then the inner points of step i
        at = np.arange(n) + np.concatenate([[0], np.cumsum(inner)])
        order = np.empty(len(all_uv), int)
        order[at] = np.arange(n)
        rest = np.ones(len(all_uv), bool)
        rest[at] = False
        order[rest] = n + np.arange(step_of.size)
        pts, nrm = pts[order], nrm[order]
        # a point that Newton carried far from where the tessellation put it (onto another stretch of the
        # section, past a fold of the parametrisation) is dropped: each lies within the tessellation's
        # error of the chord between its step's ends
        guess = np.concatenate([part.points, (1.0 - w) * part.points[step_of] + w * part.points[step_of + 1]])[order]
        seg = np.concatenate([np.zeros(n), length[step_of]])[order]
        keep = np.linalg.norm(pts - guess, axis=1) <= 4.0 * self.deflection + 0.25 * seg
        keep[[0, -1]] = True
        pts, nrm = pts[keep], nrm[keep]
        off = np.abs(np.hypot(pts[:, 0], pts[:, 1]) - r_cut)
        if off.max() > SECTION_TOLERANCE:
            raise BladeInputError(f"{self.name}: the exact section at r = {r_cut:.3f} mm could not be found "
                                  f"({off.max():.3g} mm off the cylinder); check the surfaces (degenerate "
                                  "parametrisation?) or export the blade as a mesh")
        return pts, nrm

    def facets(self) -> tuple[np.ndarray, np.ndarray]:
        """The blade's tessellation by BRepMesh at CHECK_DEFLECTION, what the paths' gouge guard pushes
        balls out of and ``bladecam verify`` measures against (cut at r_min when there is one): vertices
        (V, 3), mm, blade frame, and triangles (T, 3) int (made once, on the first call)."""
        if self._facets is None:
            verts, tris, base = [], [], 0
            for g in self._groups:
                v, t, _, _ = tessellate(compound(g.faces), CHECK_DEFLECTION, CHECK_ANGLE)
                v = (v - self._origin_file) @ self.transform[:3, :3].T
                if self._r_min is not None:
                    v, t, _ = clip_outside(v, t, self._r_min)
                    used, inverse = np.unique(t, return_inverse=True)
                    v, t = v[used], inverse.reshape(-1, 3)
                verts.append(v)
                tris.append(t + base)
                base += len(v)
            self._facets = (np.concatenate(verts), np.concatenate(tris))
        return self._facets
