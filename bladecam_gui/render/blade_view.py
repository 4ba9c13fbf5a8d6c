"""Render adapter for the blade's face and back surfaces, in the workpiece frame W.

Two inspection layers sit on the surfaces:
- the scallop map: each surface cell coloured by the largest scallop height of the strips between
  contour paths that cross it (plan.json's per-path figures, core.paths.scallop), with a colour bar;
  cells beyond the outermost or innermost path have none (grey), cells over a strip left uncut (a
  stepover of 2 r or more) are drawn in the bar's 'above' colour;
- the section at a contour: the blade cut by the contour's cylinder (the contour paths are the
  blade's cylindrical sections at their radius, SPEC section 1), the tip side removed and the
  section's outline (the blade's own section at that radius, core.blade.model.Blade.section) drawn
  thick.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from ..plan_data import BladeData
from ..style import BLADE_BACK, BLADE_FACE

#: the scallop map's colours: the colour map, a strip left uncut, a cell outside the paths
SCALLOP_CMAP = "viridis"
SCALLOP_UNCUT = "#ff3030"
SCALLOP_NONE = "#6c7380"
SECTION_COLOUR = "#ffd84a"
SCALLOP_BAR = "scallop (mm)"  # the colour bar's title


def grid_surface(points: np.ndarray) -> pv.StructuredGrid:
    """(n_r, n_c, 3) float, mm -> a pyvista surface with the same points."""
    x, y, z = (points[..., i] for i in range(3))
    return pv.StructuredGrid(x, y, z)


def grid_radius(blade: BladeData, points: np.ndarray) -> np.ndarray:
    """Radius (mm, from the propeller axis Z_B) of points (..., 3) given in W (the frame's inverse)."""
    f = blade.frame
    b = (points - f.translation) @ f.rotation
    return np.hypot(b[..., 0], b[..., 1])


def scallop_bands(paths, per_path: dict) -> np.ndarray:
    """(k, 3): inner radius, outer radius, scallop height mm of every strip between a path and the next
    one by radius towards the hub (plan.json's per_path_max_mm: its key is the outer path's index;
    None, a strip left uncut, is inf), ascending by radius."""
    ordered = sorted(paths, key=lambda p: -p.r)
    rows = []
    for a, b in zip(ordered, ordered[1:], strict=False):
        key = str(a.index)
        if key in per_path:
            h = per_path[key]
            rows.append((b.r, a.r, np.inf if h is None else float(h)))
    return np.array(sorted(rows), float).reshape(-1, 3)


def cell_scallops(radius: np.ndarray, bands: np.ndarray) -> np.ndarray:
    """Per cell of a grid whose points have ``radius`` (n_r, n_c): the largest scallop height of the
    strips ``bands`` (scallop_bands) that the cell's radii overlap; inf over an uncut strip, NaN where
    none does. Ordered as pyvista's StructuredGrid numbers its cells (first index fastest)."""
    corners = np.stack([radius[:-1, :-1], radius[1:, :-1], radius[:-1, 1:], radius[1:, 1:]])
    lo, hi = corners.min(axis=0).ravel(order="F"), corners.max(axis=0).ravel(order="F")
    if not len(bands):
        return np.full(lo.shape, np.nan)
    overlap = (bands[None, :, 0] < hi[:, None]) & (bands[None, :, 1] > lo[:, None])
    h = np.where(overlap, bands[None, :, 2], -np.inf).max(axis=1)
    return np.where(np.isneginf(h), np.nan, h)


class BladeView:
    """Owns the two surface actors of the blade in one plotter (and the section's outline)."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actors: dict[str, object] = {}
        self.opacity = 1.0
        self.visible = True
        self.blade: BladeData | None = None
        self.meshes: dict[str, pv.StructuredGrid] = {}
        self.scallop: dict[str, np.ndarray] | None = None  # key -> per-cell heights (cell_scallops)
        self.scallop_range = (0.0, 1.0)
        self.section_r: float | None = None
        self.outline = None

    def show(self, blade: BladeData) -> None:
        self.blade = blade
        self.meshes = {}
        for key, grid in (("face", blade.face), ("back", blade.back)):
            mesh = grid_surface(grid)
            mesh.point_data["radius"] = grid_radius(blade, np.asarray(mesh.points))
            self.meshes[key] = mesh
        self.scallop = None
        self.section_r = None
        self._draw()

    def _draw(self) -> None:
        self.clear(keep=True)
        if self.blade is None:
            return
        for key, colour in (("face", BLADE_FACE), ("back", BLADE_BACK)):
            mesh = self.meshes[key]
            if self.scallop is not None:
                mesh.cell_data["scallop"] = self.scallop[key]
            if self.section_r is not None:
                mesh = mesh.clip_scalar(scalars="radius", value=self.section_r, invert=True)
            kw = dict(name=f"blade-{key}", render=False, reset_camera=False, smooth_shading=True)
            if self.scallop is not None and mesh.n_cells:
                lo, hi = self.scallop_range
                self.actors[key] = self.plotter.add_mesh(
                    mesh, scalars="scallop", preference="cell", cmap=SCALLOP_CMAP, clim=(lo, hi),
                    nan_color=SCALLOP_NONE, above_color=SCALLOP_UNCUT, show_scalar_bar=key == "face",
                    scalar_bar_args={"title": SCALLOP_BAR, "fmt": "%.3f", "n_labels": 4, "vertical": True,
                                     "position_x": 0.84, "position_y": 0.25, "height": 0.5, "width": 0.05,
                                     "title_font_size": 12, "label_font_size": 11, "above_label": "uncut",
                                     "nan_annotation": True}, **kw)
                if key == "face":
                    self.plotter.scalar_bars[SCALLOP_BAR].SetNanAnnotation("none")
            elif mesh.n_cells:
                self.actors[key] = self.plotter.add_mesh(mesh, color=colour, **kw)
        if self.section_r is not None:  # the outline: the blade's own section at r (core's), in W
            sec = self.blade.blade.section(self.section_r)
            frame = self.blade.frame
            outline = pv.merge([pv.lines_from_points(frame.points(np.asarray(c, float)))
                                for c in (sec.face, sec.back)])
            self.outline = self.plotter.add_mesh(outline, color=SECTION_COLOUR, line_width=4, lighting=False,
                                                 name="blade-section", render=False, reset_camera=False,
                                                 pickable=False)
        self.set_opacity(self.opacity)
        self.set_visible(self.visible)

    # -- inspection ------------------------------------------------------------------------------
    def set_scallop(self, paths, per_path: dict | None) -> None:
        """Colour by the scallop heights of ``paths`` (plan.json's per_path_max_mm), or plainly (None)."""
        if per_path is None or self.blade is None:
            self.scallop = None
        else:
            bands = scallop_bands(paths, per_path)
            self.scallop = {k: cell_scallops(m.point_data["radius"].reshape(g.shape[:2], order="F"), bands)
                            for (k, m), g in zip(self.meshes.items(), (self.blade.face, self.blade.back),
                                                 strict=True)}
            finite = bands[np.isfinite(bands[:, 2]), 2] if len(bands) else np.zeros(0)
            hi = float(finite.max()) if len(finite) else 1.0
            self.scallop_range = (0.0, hi if hi > 0 else 1.0)
        self._draw()

    def set_section(self, r: float | None) -> None:
        """Cut the blade at radius r mm (the tip side removed, the outline drawn), or whole (None)."""
        r = None if r is None else float(r)
        if r != self.section_r:
            self.section_r = r
            self._draw()

    # -- operator's choices ----------------------------------------------------------------------
    def set_opacity(self, opacity: float) -> None:
        """0 (invisible) .. 1 (opaque), both surfaces: see the cutter behind the blade."""
        self.opacity = float(opacity)
        for actor in self.actors.values():
            actor.prop.opacity = self.opacity

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible)
        for actor in (*self.actors.values(), self.outline):
            if actor is not None:
                actor.SetVisibility(self.visible)
        if self.scallop is not None and SCALLOP_BAR in self.plotter.scalar_bars:
            self.plotter.scalar_bars[SCALLOP_BAR].SetVisibility(self.visible)

    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(lo, hi) (3,) mm of the blade in W, or None."""
        if not self.meshes:
            return None
        b = np.array([m.bounds for m in self.meshes.values()])
        return b[:, 0::2].min(axis=0), b[:, 1::2].max(axis=0)

    def clear(self, keep: bool = False) -> None:
        """Remove the actors (and, unless ``keep``, forget the blade)."""
        for actor in (*self.actors.values(), self.outline):
            if actor is not None:
                self.plotter.remove_actor(actor, render=False)
        if SCALLOP_BAR in self.plotter.scalar_bars:
            self.plotter.remove_scalar_bar(SCALLOP_BAR, render=False)
        self.actors.clear()
        self.outline = None
        if not keep:
            self.blade = None
            self.meshes = {}
