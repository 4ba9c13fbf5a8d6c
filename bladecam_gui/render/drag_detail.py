"""The 3D view's level of detail while the operator drags the timeline's cursor.

A drag frame redraws the whole scene for the cursor's new instant, though only the cutters and the
machines move. On a software OpenGL (Mesa's llvmpipe: Xvfb, remote desktops, machines without a GPU
driver) that frame costs its pixels (the blade and the machines fill much of the view) and its
vertices; on a loaded machine a drag then lagged 130-190 ms a frame. While a drag is in progress the
view is drawn light:

- the blade's two surfaces by a decimated copy of their grids (every ``BLADE_STRIDE``-th row and
  column, both ends kept); a blade coloured by the scallop map or cut at a section stays as it is;
- the paths by a coarse subset: whole contours, every n-th so that at most ``PATH_SEGMENTS``
  segments are drawn (the emphasised contour, a separate actor, is drawn whole);
- the off-screen view (bladecam_gui.render.raster_view) rendered at ``RENDER_SCALE`` of its pixels
  per side and shown scaled up;
- the cutters and the machines, the actors that move, in full.

Full detail comes back when the drag ends (the mouse button released) and whenever the cursor has
rested for ``REST_MS`` during a drag: the frame at rest is the full scene, what a screenshot and the
report's picture show. The light copies are built once per blade and per set of paths (on the first
drag), swapped into the actors' mappers and swapped back; an actor that an adapter rebuilt meanwhile
(a new plan, a face or a section change) is full detail already and is left alone.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import QObject, QTimer, Signal

BLADE_STRIDE = 3
PATH_SEGMENTS = 2500
RENDER_SCALE = 0.5
REST_MS = 200


def coarse_surface(grid: pv.StructuredGrid, stride: int = BLADE_STRIDE) -> pv.PolyData:
    """Every ``stride``-th point of a structured surface along both of its grid directions, the last
    row and column kept (the blade's edges and tip stay where they are), as the smooth-shaded surface
    the blade's actors draw (a PolyData with point normals, as pyvista's smooth shading makes it)."""
    nx, ny, nz = grid.dimensions
    pts = np.asarray(grid.points).reshape(nz, ny, nx, 3)  # (VTK's order: x fastest)
    ix = np.unique(np.r_[np.arange(0, nx, stride), nx - 1])
    iy = np.unique(np.r_[np.arange(0, ny, stride), ny - 1])
    sub = pts[:, iy][:, :, ix]
    out = pv.StructuredGrid()
    out.dimensions = (len(ix), len(iy), nz)
    out.points = sub.reshape(-1, 3)
    return out.extract_surface(pass_pointid=False, pass_cellid=False, algorithm="dataset_surface").compute_normals(
        cell_normals=False, split_vertices=False)


def path_stride(pairs: np.ndarray, budget: int = PATH_SEGMENTS) -> int:
    """Every how many contours a light view draws, for at most ``budget`` of the segments whose
    pair indices are ``pairs`` (every contour's segments counted)."""
    if len(pairs) <= budget:
        return 1
    return int(np.ceil(len(pairs) / budget))


class DragDetail(QObject):
    """Switches a Viewport's heavy static actors to their light copies while a timeline drag is in
    progress (``begin``), and back (``end``, or the cursor at rest for REST_MS).

    ``light`` is True while the light copies are shown; ``changed(bool)`` is emitted after each
    switch, once the frame of the new detail has been asked for."""

    changed = Signal(bool)

    def __init__(self, viewport, rest_ms: int = REST_MS):
        super().__init__(viewport)
        self.viewport = viewport
        self.dragging = False
        self.light = False
        self._swapped: list[tuple[object, object, object]] = []  # (actor, full dataset, light dataset)
        self._blade_copies: tuple[object, dict] | None = None  # (blade meshes, key -> coarse grid)
        self._path_copy: tuple[object, str, pv.PolyData] | None = None  # (lines, face, coarse mesh)
        self._rest = QTimer(self)
        self._rest.setSingleShot(True)
        self._rest.setInterval(rest_ms)
        self._rest.timeout.connect(self._at_rest)

    # -- the drag --------------------------------------------------------------------------------
    def begin(self) -> None:
        """A drag starts (the button pressed on the timeline): the next frames are light."""
        self.dragging = True

    def moved(self) -> None:
        """The cursor moved: light while dragging, full again once it rests for REST_MS."""
        if not self.dragging:
            return
        if not self.light:
            self._to_light()
        self._rest.start()

    def end(self) -> None:
        """The drag ends (the button released): full detail at once."""
        self.dragging = False
        self._rest.stop()
        self._to_full()

    def _at_rest(self) -> None:
        self._to_full()

    # -- switching -------------------------------------------------------------------------------
    def _to_light(self) -> None:
        vp = self.viewport
        self._swapped = []
        blade = vp.blade
        if blade.scallop is None and blade.section_r is None and blade.meshes:
            if self._blade_copies is None or self._blade_copies[0] is not blade.meshes:
                self._blade_copies = (blade.meshes, {k: coarse_surface(m) for k, m in blade.meshes.items()})
            for key, actor in blade.actors.items():
                self._swap(actor, self._blade_copies[1][key])
        paths = vp.paths
        if paths.actor is not None and paths.mesh is not None:
            coarse = self._coarse_paths(paths)
            if coarse is not None:
                self._swap(paths.actor, coarse)
        if vp.raster is not None:
            vp.raster.set_scale(RENDER_SCALE)
        self.light = True
        vp.render()
        self.changed.emit(True)

    def _to_full(self) -> None:
        if not self.light:
            return
        vp = self.viewport
        for actor, full, light in self._swapped:
            if actor.mapper.dataset is light:  # (an actor rebuilt meanwhile is full already)
                actor.mapper.dataset = full
        self._swapped = []
        if vp.raster is not None:
            vp.raster.set_scale(1.0)
        self.light = False
        vp.render()
        self.changed.emit(False)

    def _swap(self, actor, light) -> None:
        full = actor.mapper.dataset
        actor.mapper.dataset = light
        self._swapped.append((actor, full, light))

    def _coarse_paths(self, paths) -> pv.PolyData | None:
        """The shown face's paths, every n-th contour (None: few enough to draw them all)."""
        key = (paths.lines, paths.face)
        if self._path_copy is not None and self._path_copy[:2] == key:
            return self._path_copy[2]
        mask = paths.face_mask()
        stride = path_stride(paths.pair[mask])
        coarse = None
        if stride > 1:
            coarse = paths.subset(mask & (paths.pair % stride == 0))
        self._path_copy = (*key, coarse)
        return coarse

    def shown(self) -> dict[str, int]:
        """Cells drawn now by the blade's surfaces and the paths (for the tests and the benchmark)."""
        vp = self.viewport
        out = {f"blade-{k}": int(a.mapper.dataset.n_cells) for k, a in vp.blade.actors.items()}
        if vp.paths.actor is not None:
            out["paths"] = int(vp.paths.actor.mapper.dataset.n_cells)
        return out
