"""The About box: what this is and the versions of everything it runs on."""

from __future__ import annotations

import platform

from PySide6.QtWidgets import QMessageBox, QWidget


def versions() -> dict[str, str]:
    import numpy
    import pyqtgraph
    import PySide6
    import pyvista
    import scipy
    import trimesh
    from PySide6.QtCore import qVersion

    import core

    try:
        import vtk
        vtk_version = vtk.vtkVersion.GetVTKVersion()
    except Exception:  # noqa: BLE001 (shown as unknown)
        vtk_version = "unknown"
    return {"bladecam": core.__version__, "Python": platform.python_version(), "Qt": qVersion(),
            "PySide6": PySide6.__version__, "pyvista": pyvista.__version__, "VTK": vtk_version,
            "pyqtgraph": pyqtgraph.__version__, "numpy": numpy.__version__, "scipy": scipy.__version__,
            "trimesh": trimesh.__version__}


def about_text(view: str | None = None) -> str:
    """The About box's text; ``view``: which 3D view the window uses (Viewport.kind)."""
    items = versions()
    if view:
        items["3D view"] = view
    rows = "".join(f"<tr><td>{k}</td><td>{v}</td></tr>" for k, v in items.items())
    return ("<h3>bladecam</h3><p>Double-sided collaborative machining of propeller blades, after Wang, Ge "
            "and Guo, <i>Appl. Sci.</i> 2023, 13, 6529: two ball nose cutters, symmetric where safe, "
            "staggered near the thin edges, one side at a time at the tip.</p>"
            f"<table>{rows}</table><p>MIT licence.</p>")


def show_about(parent: QWidget, view: str | None = None) -> None:
    QMessageBox.about(parent, "About bladecam", about_text(view))
