"""CAD blades in: one blade (a solid, or a face/back pair: core.blade.cad) or one blade of a whole
propeller given as one STEP or IGES file (``load_cad_blade``).

A whole propeller's blades are found on BRepMesh's tessellation of all its faces (at
core.blade.cad.SECTION_DEFLECTION) by the steps that find a propeller mesh's blades
(core.blade.propeller.find_blades: the hub's end, the cut at r_min, the pieces, face and back, the
numbering). The picked blade is then made of its own CAD faces, cut at r_min:
- each CAD face of the blade goes whole to the side (face, back or caps) holding most of its area among
  the blade's triangles; caps are dropped. A face with more than MIXED_SHARE of its side area on the
  other side (one surface wrapped round the LE or TE) is refused: the split runs along CAD faces;
- each side is a core.blade.cad.FaceGroup of those faces and the cut tessellation's triangles on them (the
  corners' parameters taken from the uncut triangles they were clipped out of), so its sections are
  ordered by the cut tessellation and made exact on those faces' surfaces as any CAD pair's are;
- the tessellation that verify and the gouge guard check against is cut at r_min too (CadBlade.facets).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from core.blade.cad import CadBlade, FaceGroup, corner_parameters, read_cad
from core.blade.mesh import AxisMisfit
from core.blade.placement import parse_axis
from core.blade.propeller import cut_propeller, label_picked, picked_index
from core.errors import BladeInputError

#: a CAD face with more than this share of its face-and-back area on the side it is not put on is
#: refused (it runs round the LE or TE)
MIXED_SHARE = 0.25


def load_cad_blade(paths: str | Path | Sequence[str | Path], axis: str = "z",
                   origin: Sequence[float] = (0.0, 0.0, 0.0),
                   pick: tuple[int | None, float | None] = (None, None)) -> CadBlade:
    """A CadBlade from one file holding a closed blade, or two files: (face, back) in that order, or one
    blade of a whole propeller in one file.

    axis : an AXIS string (core.blade.placement); origin : (3,) mm, added to the axis's point; pick :
    (the blade's number from 1, the hub cut r_min in mm) of a whole propeller, None each when not given.
    One file is a whole propeller when either is given, or when it does not lie beside the axis as one
    blade does and holds two blades or more outside its hub (then blade 1 is taken, with a warning).
    Raises BladeInputError naming the file for every unusable input."""
    files = [paths] if isinstance(paths, str | Path) else list(paths)
    if not 1 <= len(files) <= 2:
        raise BladeInputError(
            f"{', '.join(str(f) for f in files) or 'no CAD file'}: give one closed blade (a solid), or two "
            f"surfaces (face, back); got {len(files)} files")
    groups = [FaceGroup.of_shape(read_cad(f)) for f in files]
    if len(files) == 1 and (pick[0] is not None or pick[1] is not None):
        return propeller_cad_blade(groups[0], str(files[0]), axis, origin, pick)
    try:
        return CadBlade(groups, [str(f) for f in files], axis=axis, origin=origin)
    except AxisMisfit:
        if len(files) > 1:
            raise
        try:
            blade = propeller_cad_blade(groups[0], str(files[0]), axis, origin, pick)
        except BladeInputError:
            blade = None
        if blade is None or len(blade.propeller.blades) < 2:
            raise
        return blade


def propeller_cad_blade(whole: FaceGroup, file: str, axis: str, origin: Sequence[float],
                        pick: tuple[int | None, float | None]) -> CadBlade:
    """Blade ``pick[0]`` (default 1) of the whole propeller whose faces and tessellation are ``whole``
    (file frame, mm), its hub cut at ``pick[1]`` mm (default: core.blade.propeller.hub_end), as a
    face/back CadBlade (see the module)."""
    name = Path(file).name
    _, rot, point = parse_axis(axis)
    org = np.asarray(origin, float).reshape(3) + point
    try:
        prop, cut = cut_propeller(whole.mesh.vertices, whole.triangles, rot, org, 1.0, r_min=pick[1])
    except BladeInputError as exc:
        raise BladeInputError(f"{file}: {exc} (axis {axis!r})") from None
    k, warning = picked_index(prop, pick[0], file, axis)
    parts = cut.blades[k - 1]
    cad_face = whole.face_of[cut.source]  # (the CAD face of each cut triangle)
    tri = cut.vertices[cut.faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    nf = len(whole.faces)
    on = [np.bincount(cad_face[idx], weights=area[idx], minlength=nf) for idx in (parts.face, parts.back)]
    on.append(np.bincount(cad_face[parts.facets], weights=area[parts.facets], minlength=nf) - on[0] - on[1])
    side_of = np.argmax(np.column_stack(on), axis=1)  # 0 face, 1 back, 2 caps (or not on this blade)
    sides = (on[0] + on[1]) > 0
    minor = np.where(side_of == 0, on[1], on[0])
    mixed = np.flatnonzero(sides & (side_of < 2) & (minor > MIXED_SHARE * (on[0] + on[1])))
    if mixed.size:
        f = int(mixed[0])
        raise BladeInputError(
            f"{file}: CAD face {f + 1} of blade {k} lies on both its face and its back ({on[0][f]:.4g} and "
            f"{on[1][f]:.4g} mm^2): one surface round the leading or trailing edge; bladecam splits a CAD "
            "propeller's face from its back along its faces: export the blade's face and back as separate "
            "surfaces, or give the propeller as a mesh (STL)")
    file_vertices = cut.vertices @ rot + org
    groups = []
    for s in (0, 1):
        idx = parts.facets[side_of[cad_face[parts.facets]] == s]
        if idx.size == 0:
            raise BladeInputError(f"{file}: blade {k} has no CAD face on its {('face', 'back')[s]}")
        groups.append(_side_group(whole, file_vertices, cut, idx, cad_face[idx]))
    names = [f"{name} blade {k} face", f"{name} blade {k} back"]
    blade = CadBlade(groups, names, axis=axis, origin=origin, r_min=cut.r_min)
    return label_picked(blade, name, k, prop, file, warning)


def _side_group(whole: FaceGroup, file_vertices: np.ndarray, cut, idx: np.ndarray, faces: np.ndarray) -> FaceGroup:
    """The FaceGroup of one side: the cut triangles ``idx`` (into cut.faces) lying on the CAD faces
    ``faces`` (idx's, indices into whole.faces), their corners' parameters from the uncut triangles."""
    used, local = np.unique(cut.faces[idx], return_inverse=True)
    corners = file_vertices[cut.faces[idx]]  # (n, 3, 3)
    src = np.repeat(cut.source[idx], 3)
    uv = corner_parameters(whole.mesh.vertices[whole.triangles[src]], whole.corner_uv[src], corners.reshape(-1, 3))
    own, face_of = np.unique(faces, return_inverse=True)
    return FaceGroup([whole.faces[f] for f in own], file_vertices[used], local.reshape(-1, 3), face_of.ravel(),
                  uv.reshape(-1, 3, 2))

