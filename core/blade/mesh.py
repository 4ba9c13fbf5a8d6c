"""A blade read from a triangle mesh (STL, OBJ, PLY via trimesh).

Three kinds of source (``load_mesh_blade``):
- one file: a closed blade (face, back and the caps in one mesh);
- one file of a whole propeller: one blade picked out of it (core.blade.propeller), then read as a
  face/back pair;
- two files: two open surfaces, the first is used as the face and the second as the back, in the
  files' order, whatever side they lie on (a pair given the other way round is kept and noted in
  ``MeshBlade.warnings``); cap files (tip, root) are not wanted.

Frame: the vertices are moved into the blade frame of core.blade.model: minus ``origin`` (file coordinates),
then the propeller axis ('x', 'y' or 'z') is turned onto +Z by a cyclic permutation of the axes
(right-handed), then the whole mesh is turned about Z so that the area-weighted centroid of the blade
lies at theta = 0 (the generator line along +X). ``MeshBlade.transform`` is that 4x4 map.

Sections (``MeshBlade.section(r)``): each surface is cut by the cylinder along its facets and
resampled there, with facet normals (core.blade.mesh_sections). Then:
- Two surfaces: one open polyline each; LE and TE are where they meet: the matched end points are
  averaged (the two sides need not share vertices) and put back on the cylinder. On that LE/TE step
  the averaged end moves the last piece off its facet by up to half the gap between the sides' ends.
- One closed mesh: one closed loop; LE and TE are its two crossings farthest apart in the unrolled
  (r theta, z) plane; the face is the part to the right of the other walking LE -> TE (the smaller v
  of core.blade.model.chord_frame, the one definition of the sides used here and in the pair check).
The LE is the end with the larger r theta; both parts run LE -> TE and share their end points, and
each is resampled along its facets (``MeshBlade.step``, RESAMPLE_STEP by default). Radii within 1e-3
of the span from the hub or the tip are cut 1e-3 span inside the blade (the boundary rows of a real
mesh are noisy), then put on the requested cylinder.
Outward: a closed mesh gets a consistent winding and a positive volume; each open surface gets a
consistent winding and is turned so that its normals point away from the other surface; the facet
normals follow that winding.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from core.blade.mesh_sections import RESAMPLE_STEP, Polyline, Surface, resample
from core.blade.mesh_tools import farthest_pair, fix_winding
from core.blade.model import Blade, Section, chord_frame, section_chord, section_max_thickness, unroll
from core.blade.placement import AXIS_ROTATIONS, parse_axis
from core.blade.propeller import Propeller, label_picked, picked_index, split_propeller
from core.errors import BladeInputError
from core.util.files import require_file

if TYPE_CHECKING:
    import trimesh

MESH_SUFFIXES = (".stl", ".obj", ".ply")
#: cuts closer than this fraction of the span to the hub or tip are moved inside the blade
EDGE_MARGIN = 1e-3
#: a blade subtending a larger angle about the axis is refused (axis through the mesh, or a propeller)
MAX_ANGLE_DEG = 180.0
#: face and back ends farther apart than this share of the chord are refused (not one blade)
MAX_EDGE_GAP = 0.25
#: an open section of a closed mesh is accepted (and closed) if its gap is below this share of its length
MAX_LOOP_GAP = 0.05
#: a vertex farther than this from the file's origin (mm) is no part of a propeller blade (the largest
#: propellers are ~11 m across; core.blade.bounds accepts diameters up to 100 m)
MAX_COORD_MM = 1e5
#: two surfaces closer than this share of the chord at mid-span are one surface given twice
MIN_THICKNESS_RATIO = 1e-3


def read_mesh(path: str | Path) -> trimesh.Trimesh:
    """One triangle mesh from an STL, OBJ or PLY file (file coordinates, mm).

    Raises BladeInputError naming the file: missing, empty, unsupported format, unreadable, no faces.
    """
    import trimesh  # (0.7 s to import: only where a mesh is read)

    p = Path(path)
    require_file(p, "mesh file not found; check the path", "give an STL, OBJ or PLY mesh file")
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise BladeInputError(f"{p}: unsupported mesh format {p.suffix!r}; give an STL, OBJ or PLY file")
    if p.stat().st_size == 0:
        raise BladeInputError(f"{p}: the file is empty; export the mesh again")
    fmt = p.suffix[1:].upper()
    damaged = _stl_count_problem(p) if fmt == "STL" else None
    try:
        # (read as written: processing would drop a facet with a non-finite vertex without a word)
        with np.errstate(invalid="ignore", over="ignore"):  # (a stray vertex at 1e30: refused below, by name)
            loaded = trimesh.load(str(p), file_type=p.suffix.lower()[1:], process=False)
    except Exception as exc:  # trimesh raises many types on bad bytes
        raise BladeInputError(f"{p}: not a readable {fmt} mesh ({damaged or f'{type(exc).__name__}: {exc}'})"
                              "; export the blade as a triangle mesh") from exc
    parts = list(loaded.dump()) if isinstance(loaded, trimesh.Scene) else [loaded]  # transforms applied
    if not parts or damaged:  # (a count that does not match: triangles lost or read from other bytes)
        raise BladeInputError(f"{p}: not a readable {fmt} mesh ({damaged or 'no geometry found'}); "
                              f"export the blade as a triangle mesh")
    for m in parts:
        v = np.asarray(getattr(m, "vertices", np.zeros((0, 3))))
        bad = np.flatnonzero(~np.isfinite(v).all(axis=1))
        if bad.size:
            k = int(bad[0])
            facet = f" (facet {k // 3 + 1})" if fmt == "STL" else ""
            raise BladeInputError(f"{p}: vertex {k + 1}{facet} is not a finite number "
                                  f"({', '.join(f'{c:.4g}' for c in v[k])}; {bad.size} such vertices): a "
                                  "damaged file; export the mesh again")
        if isinstance(m, trimesh.Trimesh):
            with np.errstate(invalid="ignore", over="ignore"):
                m.process()
    meshes = [m for m in parts if isinstance(m, trimesh.Trimesh) and len(m.faces) > 0]
    if not meshes:
        raise BladeInputError(f"{p}: the mesh has no triangles (points or lines only?); "
                              f"export the blade surface as a triangle mesh")
    mesh = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
    if isinstance(loaded, trimesh.Scene) and len(meshes) > 1:
        mesh.merge_vertices()
    mesh.remove_unreferenced_vertices()
    v = np.asarray(mesh.vertices)
    far = np.flatnonzero(~np.isfinite(v).all(axis=1) | (np.abs(v).max(axis=1) > MAX_COORD_MM))
    if far.size:
        k = int(far[0])
        raise BladeInputError(f"{p}: vertex {k + 1} lies at ({', '.join(f'{c:.4g}' for c in v[k])}) mm: beyond "
                              f"{MAX_COORD_MM:g} mm of the origin, no part of a blade ({far.size} such vertices); "
                              "remove the stray vertices or check the file's units")
    return mesh


def _orient_away(mesh: trimesh.Trimesh, other: trimesh.Trimesh) -> None:
    """Turn an open surface (consistent winding) so that its normals point away from `other`."""
    _, idx = cKDTree(other.vertices).query(mesh.vertices)
    vote = np.einsum("ij,ij->", mesh.vertex_normals, mesh.vertices - other.vertices[idx])
    if vote < 0:
        mesh.invert()


def _face_on_back_side(section: Section) -> bool:
    """True if the face part lies on the back's side of the other part: left of it walking LE -> TE
    in the unrolled section (core.blade.model.chord_frame: v grows towards the back)."""
    fuv, buv, _ = chord_frame(section)
    return bool(fuv[:, 1].mean() > buv[:, 1].mean())


class AxisMisfit(BladeInputError):
    """The mesh does not lie beside the axis as one blade does (MeshBlade._check_axis): a wrong axis, or
    a whole propeller (load_mesh_blade then looks for its blades)."""


class MeshBlade(Blade):
    """A blade from one closed mesh or from two open surfaces (face, back), in the blade frame.

    meshes : one or two trimesh.Trimesh in file coordinates (mm); files : their file names (messages);
    axis : an AXIS string (core.blade.placement: 'x', 'y', 'z' or 'DX,DY,DZ', optionally '@PX,PY,PZ'), the
    propeller axis in the file; origin : (3,), file units, added to the axis's point; scale : mm per
    unit of the file's numbers (core.blade.placement.UNITS).
    step : mm, the largest distance between section points along a facet (RESAMPLE_STEP).
    Attributes: transform (4, 4) file -> blade frame, closed (one closed mesh), warnings (list of str),
    propeller (core.blade.propeller.Propeller when the blade was picked out of a whole propeller, with
    blade_index its number from 1; else None).
    """

    propeller: Propeller | None = None
    blade_index: int | None = None
    #: the sections run along facets (a CAD blade's lie on its exact surface)
    faceted = True

    def __init__(self, meshes: Sequence[trimesh.Trimesh], files: Sequence[str], axis: str = "z",
                 origin: Sequence[float] = (0.0, 0.0, 0.0), step: float = RESAMPLE_STEP, scale: float = 1.0):
        if not step > 0:
            raise ValueError(f"step must be positive, got {step}")
        self.step = float(step)
        names = [Path(f).name for f in files]
        self.name = " + ".join(names)
        self.source = ",".join(str(f) for f in files)
        self.files = [str(f) for f in files]
        self.closed = len(meshes) == 1
        self.warnings: list[str] = []
        try:
            named, rot, point = parse_axis(axis)
        except BladeInputError as exc:
            raise BladeInputError(f"{self.name}: {exc}") from None
        org = (np.asarray(origin, float).reshape(3) + point) * scale
        meshes = [m.copy() for m in meshes]
        if scale != 1.0:
            for m in meshes:
                m.apply_scale(scale)
        for m in meshes:
            fix_winding(m)
        if self.closed:
            if meshes[0].volume < 0:
                meshes[0].invert()
        else:
            _orient_away(meshes[0], meshes[1])
            _orient_away(meshes[1], meshes[0])
        both = meshes[0] + meshes[1] if len(meshes) > 1 else meshes[0]
        c = (np.asarray(both.triangles_center) - org) @ rot.T
        cxy = (np.asarray(both.area_faces)[:, None] * c[:, :2]).sum(axis=0)
        phi = -float(np.arctan2(cxy[1], cxy[0])) if np.hypot(*cxy) > 0 else 0.0
        rz = np.array([[np.cos(phi), -np.sin(phi), 0.0], [np.sin(phi), np.cos(phi), 0.0], [0.0, 0.0, 1.0]])
        rot = rz @ rot
        self.transform = np.eye(4)
        self.transform[:3, :3] = rot
        self.transform[:3, 3] = -rot @ org
        self._surfaces = [Surface(m, rot, org, n) for m, n in zip(meshes, names, strict=True)]
        radii = np.concatenate([s.radii for s in self._surfaces])
        self._hub, self._tip = float(radii.min()), float(radii.max())
        try:
            self._check_axis(f"axis {axis!r} through {tuple(round(float(v), 6) for v in org)} mm")
        except AxisMisfit as exc:
            raise AxisMisfit(f"{exc}{_other_axes(meshes, org, named)}") from None
        mid = self.section(0.5 * (self._hub + self._tip))  # fail early on an unusable mesh
        if not self.closed:
            chord, thick = section_chord(mid), section_max_thickness(mid)
            if thick <= MIN_THICKNESS_RATIO * chord:
                raise BladeInputError(
                    f"{self.name}: the two surfaces coincide (thickness {thick:.3g} mm on a chord of {chord:.4g} mm "
                    f"at r = {mid.r:.3f} mm): the same surface given twice? give the face and the back of one blade")
            if _face_on_back_side(mid):
                self.warnings.append(
                    f"{names[0]} lies left of {names[1]} walking LE -> TE in the unrolled section, so by "
                    f"the project's convention it is the back; used as given: {names[0]} = face, "
                    f"{names[1]} = back")

    def facets(self) -> tuple[np.ndarray, np.ndarray]:
        """The mesh itself: vertices (V, 3) float, mm, blade frame, and triangles (T, 3) int."""
        verts, faces, base = [], [], 0
        for srf in self._surfaces:
            verts.append(srf.vertices)
            faces.append(srf.faces + base)
            base += len(srf.vertices)
        return np.concatenate(verts), np.concatenate(faces)

    def _check_axis(self, where: str) -> None:
        """Refuse a mesh that does not lie beside the axis as one blade does."""
        v = np.concatenate([s.vertices for s in self._surfaces])
        problem = axis_problem(v, np.eye(3), np.zeros(3))
        if problem is not None:
            raise AxisMisfit(f"{self.name}: the {where}: {problem}; check the axis and origin, and give one "
                             "blade")

    @property
    def hub_radius(self) -> float:
        return self._hub

    def section_error(self, r: float) -> float:
        """An estimate (mm) of how far the section at r can lie from the smooth blade the mesh's vertices
        sample: the largest over its surfaces (core.blade.mesh_sections.Surface.sag_estimate)."""
        return max(s.sag_estimate(float(r)) for s in self._surfaces)

    def info(self) -> dict:
        """Blade.info, with the sections' error from the facets (an estimate, at info's radii) and the
        blades found when this blade was picked out of a whole propeller."""
        out = super().info()
        if self.faceted:
            out["section_error_estimate_mm"] = {
                key: None if chord is None else round(self.section_error(float(key) * self.tip_radius), 4)
                for key, chord in out["chord_mm"].items()}
        if self.propeller is not None:
            out["propeller"] = {**self.propeller.summary(), "picked": self.blade_index}
        return out

    @property
    def tip_radius(self) -> float:
        return self._tip

    def section(self, r: float) -> Section:
        """The cylindrical section at radius r (mm), face and back LE -> TE with outward unit normals."""
        self._check_radius(r)
        r = float(r)
        margin = EDGE_MARGIN * (self._tip - self._hub)
        r_cut = min(max(r, self._hub + margin), self._tip - margin)
        cuts = [s.cut(r_cut) for s in self._surfaces]
        for s, c in zip(self._surfaces, cuts, strict=True):
            if c is None:
                raise BladeInputError(f"{s.file}: no blade surface at r = {r:.3f} mm (the mesh spans "
                                      f"{self._hub:.3f} to {self._tip:.3f} mm); check the axis and origin, "
                                      f"or choose a radius on the blade")
        if self.closed:
            face, back = self._split_loop(r, cuts[0])
        else:
            face, back = self._join_sides(r, r_cut, cuts[0], cuts[1])
        (f, fn), (b, bn) = self._sample(face, back, r_cut, r)
        b[0], b[-1] = f[0], f[-1]  # the same points (vector and scalar float paths may differ by an ulp)
        return Section(r=r, face=f, back=b, face_normals=fn, back_normals=bn)

    def _sample(self, face: Polyline, back: Polyline, r_cut: float,
                r: float) -> list[tuple[np.ndarray, np.ndarray]]:
        """Points and normals along the face and back polylines of the cut at r_cut, put on the
        cylinder r: along the facets (mesh_sections.resample)."""
        return resample([face, back], r_cut, r, self.step)

    def _split_loop(self, r: float, loop: Polyline) -> tuple[Polyline, Polyline]:
        """Split the closed loop of a one-mesh blade at its LE and TE: (face, back), LE -> TE."""
        pts = loop.points
        length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
        gap = float(np.linalg.norm(pts[-1] - pts[0]))
        if len(pts) < 3 or (not loop.closed and gap > MAX_LOOP_GAP * length):
            raise BladeInputError(
                f"{self.files[0]}: the section at r = {r:.3f} mm is not a closed loop (gap {gap:.3f} mm): "
                f"the mesh is not a closed blade; repair it, or give face and back as two files")
        if not loop.closed:  # a small gap: closed by a straight step on no known facet
            loop = replace(loop, facet_normals=np.vstack([loop.facet_normals, np.zeros((1, 3))]), closed=True,
                           facets=None if loop.facets is None else np.append(loop.facets, -1))
        uv = unroll(pts, r)
        i, j = farthest_pair(uv)
        le, te = (i, j) if uv[i, 0] >= uv[j, 0] else (j, i)
        n = len(pts)
        k = (te - le) % n
        fwd = loop.part((le + np.arange(k + 1)) % n)
        bwd = loop.part((le - np.arange(n - k + 1)) % n)
        sec = Section(r=r, face=fwd.points, back=bwd.points, face_normals=fwd.normals,
                      back_normals=bwd.normals)
        return (bwd, fwd) if _face_on_back_side(sec) else (fwd, bwd)

    def _join_sides(self, r: float, r_cut: float, face: Polyline,
                    back: Polyline) -> tuple[Polyline, Polyline]:
        """Join the open face and back polylines of a two-surface blade at their common ends:
        (face, back), LE -> TE, sharing their end points."""
        for s, c in zip(self._surfaces, (face.closed, back.closed), strict=True):
            if c:
                raise BladeInputError(f"{s.file}: the section at r = {r:.3f} mm is a closed loop; a face or "
                                      f"back surface must be open (give a closed blade as one file)")
        f, b = face.points, back.points
        d_same = np.linalg.norm(f[0] - b[0]) + np.linalg.norm(f[-1] - b[-1])
        d_swap = np.linalg.norm(f[0] - b[-1]) + np.linalg.norm(f[-1] - b[0])
        if d_swap < d_same:
            back = back.reversed()
            b = back.points
        gap = max(np.linalg.norm(f[0] - b[0]), np.linalg.norm(f[-1] - b[-1]))
        ends = 0.5 * (np.array([f[0], f[-1]]) + np.array([b[0], b[-1]]))
        if gap > MAX_EDGE_GAP * np.linalg.norm(ends[1] - ends[0]):
            raise BladeInputError(
                f"{self.name}: at r = {r:.3f} mm the two surfaces do not meet at LE and TE "
                f"(gap {gap:.3f} mm); give the face and back of one blade")
        ends[:, :2] *= (r_cut / np.hypot(ends[:, 0], ends[:, 1]))[:, None]
        if unroll(ends, r)[0, 0] < unroll(ends, r)[1, 0]:
            face, back, ends = face.reversed(), back.reversed(), ends[::-1]
        out = []
        for side in (face, back):
            p = side.points.copy()
            p[0], p[-1] = ends[0], ends[1]
            out.append(replace(side, points=p))
        return out[0], out[1]


def _stl_count_problem(path: Path) -> str | None:
    """What is wrong with a binary STL whose header's triangle count does not match its size (None: an
    ASCII STL, or a count that matches): 84 bytes of header and count, then 50 bytes a triangle."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(84)
    except OSError:
        return None
    if len(head) < 84 or head.lstrip()[:5].lower() == b"solid" and b"facet" in _start(path):
        return None
    count = int.from_bytes(head[80:84], "little")
    if size == 84 + 50 * count:
        return None
    return (f"a binary STL whose header counts {count:,} triangles, {84 + 50 * count:,} bytes, in a file of "
            f"{size:,} bytes (room for {(size - 84) / 50:,.1f}): truncated or damaged")


def _start(path: Path, n: int = 4096) -> bytes:
    with open(path, "rb") as f:
        return f.read(n).lower()


def axis_problem(vertices: np.ndarray, rot: np.ndarray, org: np.ndarray) -> str | None:
    """Why the axis of ``rot`` (a file axis turned onto Z) through ``org`` cannot be a blade's (None: the
    vertices (V, 3), mm, file frame, lie beside it as one blade does): the checks of MeshBlade._check_axis."""
    v = (vertices - org) @ rot.T
    radius = np.hypot(v[:, 0], v[:, 1])
    hub, tip = float(radius.min()), float(radius.max())
    if not tip > 0 or tip - hub <= 1e-6 * tip:
        return f"the mesh spans no radius about it (radius {hub:.4g} to {tip:.4g} mm)"
    if hub < 1e-3 * tip:
        return f"it passes through the mesh (hub radius {hub:.4g} mm)"
    span = _angle_spanned(vertices, rot, org)
    if span > MAX_ANGLE_DEG:
        return (f"the mesh surrounds it ({span:.0f} degrees): the axis passes through it, or it holds several "
                "blades")
    return None


def _other_axes(meshes: Sequence[trimesh.Trimesh], org: np.ndarray, given: str | None) -> str:
    """A hint naming the other file axes the mesh lies beside as one blade does ('' if none)."""
    v = np.concatenate([np.asarray(m.vertices) for m in meshes])
    fits = [a for a in AXIS_ROTATIONS if a != given and axis_problem(v, AXIS_ROTATIONS[a], org) is None]
    if not fits:
        return ""
    if len(fits) == 1:
        return f"; the mesh lies beside axis {fits[0]} as a blade does: try --axis {fits[0]}"
    # several fit: a blade spans the narrowest angle about its own axis (about another one, its
    # chord and its span both sweep round it)
    angle = {a: _angle_spanned(v, AXIS_ROTATIONS[a], org) for a in fits}
    fits.sort(key=angle.get)
    spans = ", ".join(f"{angle[a]:.0f} about {a}" for a in fits)
    return (f"; the mesh lies beside axes {' and '.join(fits)} as a blade does, and spans the narrowest "
            f"angle about {fits[0]} (degrees: {spans}): try --axis {fits[0]}")


def _propeller_axes(mesh: trimesh.Trimesh, given: str, origin: Sequence[float], scale: float) -> str:
    """A hint naming the first other file axis (x, y, z through the given axis's point) about which the
    mesh is a whole propeller ('' if none)."""
    _, _, point = parse_axis(given)
    org = (np.asarray(origin, float).reshape(3) + point) * scale
    for name, rot in AXIS_ROTATIONS.items():
        if name == given:
            continue
        try:
            n = len(split_propeller(mesh.vertices, mesh.faces, rot, org, scale).blades)
        except BladeInputError:
            continue
        if n > 1:
            at = given.partition("@")[2]
            spec = f"{name}@{at}" if at else name
            return f"; it is a whole propeller of {n} blades about axis {name}: try --axis {spec}"
    return ""


def _angle_spanned(vertices: np.ndarray, rot: np.ndarray, org: np.ndarray) -> float:
    """Degrees the vertices (V, 3), mm, file frame, span about the axis of ``rot`` through ``org``."""
    v = (vertices - org) @ rot.T
    theta = np.sort(np.arctan2(v[:, 1], v[:, 0]))
    return float(360.0 - np.degrees(np.max(np.diff(np.concatenate([theta, [theta[0] + 2 * np.pi]])))))


def load_mesh_blade(paths: str | Path | Sequence[str | Path], axis: str = "z",
                    origin: Sequence[float] = (0.0, 0.0, 0.0), scale: float = 1.0,
                    pick: tuple[int | None, float | None] = (None, None)) -> MeshBlade:
    """A MeshBlade from one closed blade mesh, or from two open surfaces: (face, back) in that order,
    or one blade of a whole propeller in one mesh (core.blade.propeller).

    paths : one path, or a sequence of one or two paths (STL, OBJ, PLY); axis : an AXIS string, the
    propeller axis in the file's coordinates; origin : (3,), a point added to the axis's; scale : mm
    per unit of the file's numbers; pick : (the blade's number from 1, the hub cut r_min in mm) of a
    whole propeller, None each when not given. One mesh file is a whole propeller when either is
    given, or when it does not lie beside the axis as one blade does and holds two blades or more
    outside its hub (then blade 1 is taken, with a warning naming the others).
    Raises BladeInputError naming the file for every unusable input.
    """
    files = [paths] if isinstance(paths, str | Path) else list(paths)
    if not 1 <= len(files) <= 2:
        raise BladeInputError(
            f"{', '.join(str(f) for f in files) or 'no mesh file'}: give one closed blade mesh, or two "
            f"open surfaces (face, back); got {len(files)} files (leave out tip and root caps)")
    meshes = [read_mesh(f) for f in files]
    index, r_min = pick
    if len(files) == 1 and (index is not None or r_min is not None):
        return propeller_blade(meshes[0], str(files[0]), axis, origin, scale, pick)
    try:
        return MeshBlade(meshes, [str(f) for f in files], axis=axis, origin=origin, scale=scale)
    except AxisMisfit as misfit:
        if len(files) > 1:
            raise
        try:
            blade = propeller_blade(meshes[0], str(files[0]), axis, origin, scale, pick)
        except BladeInputError:
            raise AxisMisfit(f"{misfit}{_propeller_axes(meshes[0], axis, origin, scale)}") from None
        if len(blade.propeller.blades) < 2:
            raise
        return blade


def propeller_blade(mesh: trimesh.Trimesh, file: str, axis: str, origin: Sequence[float], scale: float,
                    pick: tuple[int | None, float | None]) -> MeshBlade:
    """Blade ``pick[0]`` (default 1) of the whole propeller ``mesh`` (file coordinates), its hub cut at
    ``pick[1]`` mm (default: core.blade.propeller.hub_end), as a face/back MeshBlade."""
    name = Path(file).name
    _, rot, point = parse_axis(axis)
    org = (np.asarray(origin, float).reshape(3) + point) * scale
    try:
        prop = split_propeller(mesh.vertices, mesh.faces, rot, org, scale, r_min=pick[1])
    except BladeInputError as exc:
        raise BladeInputError(f"{file}: {exc} (axis {axis!r})") from None
    k, warning = picked_index(prop, pick[0], file, axis)
    b = prop.blades[k - 1]
    blade = MeshBlade([b.face, b.back], [f"{name} blade {k} face", f"{name} blade {k} back"], axis=axis,
                      origin=origin, scale=scale)
    return label_picked(blade, name, k, prop, file, warning)
