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
report's picture show. The light copies are actors of their own, built on the first drag after their full actors were
(re)built and hidden at rest; a drag hides the full actors and shows the copies.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from PySide6.QtCore import QObject, QTimer, Signal

BLADE_STRIDE = 3
PATH_SEGMENTS = 2500
RENDER_SCALE = 0.5
REST_MS = 200


def coarse_grid(grid: pv.StructuredGrid, stride: int = BLADE_STRIDE) -> pv.StructuredGrid:
    """Every ``stride``-th point of a structured surface along both of its grid directions, the last
    row and column kept (the blade's edges and tip stay where they are)."""
    nx, ny, nz = grid.dimensions
    pts = np.asarray(grid.points).reshape(nz, ny, nx, 3)  # (VTK's order: x fastest)
    ix = np.unique(np.r_[np.arange(0, nx, stride), nx - 1])
    iy = np.unique(np.r_[np.arange(0, ny, stride), ny - 1])
    out = pv.StructuredGrid()
    out.dimensions = (len(ix), len(iy), nz)
    out.points = pts[:, iy][:, :, ix].reshape(-1, 3)
    return out


def path_stride(pairs: np.ndarray, budget: int | None = None) -> int:
    """Every how many contours a light view draws, for about ``budget`` (default PATH_SEGMENTS) of
    the segments whose pair indices are ``pairs``."""
    budget = PATH_SEGMENTS if budget is None else budget
    if len(pairs) <= budget:
        return 1
    return int(np.ceil(len(pairs) / budget))


class DragDetail(QObject):
    """Shows light copies of a Viewport's heavy static actors while a timeline drag is in progress
    (``begin``, then ``moved`` per cursor move), and the full actors again (``end``, or the cursor at
    rest for REST_MS).

    Each light copy is an actor of its own, hidden at rest, sharing its full actor's property (colour,
    opacity, line width, as the operator set them); it is built on the first drag after its full
    actor was (re)built. ``light`` is True while the copies are shown; ``changed(bool)`` is emitted
    after each switch, once the frame of the new detail has been asked for."""

    changed = Signal(bool)

    def __init__(self, viewport, rest_ms: int = REST_MS):
        super().__init__(viewport)
        self.viewport = viewport
        self.enabled = True  # False: every drag frame in full detail (the benchmark's comparison)
        self.dragging = False
        self.light = False
        self._copies: dict[str, tuple[object, object]] = {}  # name -> (its full actor, the light actor)
        self._hidden: list[object] = []  # the full actors hidden for the light copies
        self._rest = QTimer(self)
        self._rest.setSingleShot(True)
        self._rest.setInterval(rest_ms)
        self._rest.timeout.connect(self._at_rest)

    def set_rest_ms(self, ms: int) -> None:
        """How long the cursor rests during a drag before the full scene is drawn."""
        self._rest.setInterval(int(ms))

    # -- the drag --------------------------------------------------------------------------------
    def begin(self) -> None:
        """A drag starts (the button pressed on the timeline): the next moves are drawn light."""
        self.dragging = True

    def moved(self) -> None:
        """The cursor moved: light while dragging, full again once it rests for REST_MS."""
        if not self.dragging or not self.enabled:
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
        blade, paths = vp.blade, vp.paths
        wanted = {}
        if blade.scallop is None and blade.section_r is None:
            for key, actor in blade.actors.items():
                wanted[f"blade-{key}"] = (actor, lambda k=key: coarse_grid(blade.meshes[k]),
                                          {"smooth_shading": True})
        if paths.actor is not None and paths.lines is not None:
            wanted["paths"] = (paths.actor, lambda: self._coarse_paths(paths),
                               {"scalars": "rgb", "rgb": True, "lighting": False})
        self._hidden = []
        for name, (full, build, kwargs) in wanted.items():
            if not full.GetVisibility():
                continue
            light = self._copy(name, full, build, kwargs)
            if light is not None:
                full.SetVisibility(False)
                light.SetVisibility(True)
                self._hidden.append(full)
        if vp.raster is not None:
            vp.raster.set_scale(RENDER_SCALE)
        self.light = True
        vp.render()
        self.changed.emit(True)

    def _to_full(self) -> None:
        if not self.light:
            return
        vp = self.viewport
        for _full, light in self._copies.values():
            light.SetVisibility(False)
        for full in self._hidden:
            full.SetVisibility(True)
        self._hidden = []
        if vp.raster is not None:
            vp.raster.set_scale(1.0)
        self.light = False
        vp.render()
        self.changed.emit(False)

    def _copy(self, name: str, full, build, kwargs: dict):
        """The light actor ``name`` of the actor ``full`` (built now if ``full`` is new; None when
        the copy would be no lighter)."""
        kept = self._copies.get(name)
        if kept is not None and kept[0] is full:
            return kept[1]
        plotter = self.viewport.plotter
        if kept is not None:
            plotter.remove_actor(kept[1], render=False)
            del self._copies[name]
        mesh = build()
        if mesh is None:
            return None
        light = plotter.add_mesh(mesh, name=f"drag-{name}", render=False, reset_camera=False, pickable=False,
                                 **kwargs)
        light.SetProperty(full.GetProperty())  # (the operator's colour, opacity and widths)
        light.SetVisibility(False)
        self._copies[name] = (full, light)
        return light

    @staticmethod
    def _coarse_paths(paths) -> pv.PolyData | None:
        """The shown face's paths, every n-th contour (None: few enough to draw them all)."""
        mask = paths.face_mask()
        stride = path_stride(paths.pair[mask])
        return paths.subset(mask & (paths.pair % stride == 0)) if stride > 1 else None

    def shown(self) -> dict[str, int]:
        """Cells drawn now by the blade's surfaces and the paths (for the tests and the benchmark)."""
        vp = self.viewport
        actors = {f"blade-{k}": a for k, a in vp.blade.actors.items()}
        if vp.paths.actor is not None:
            actors["paths"] = vp.paths.actor
        out = {}
        for name, full in actors.items():
            kept = self._copies.get(name)
            actor = kept[1] if kept is not None and kept[0] is full and kept[1].GetVisibility() else full
            out[name] = int(actor.mapper.dataset.n_cells)
        return out
