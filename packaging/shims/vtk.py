"""The bundle's stand-in for VTK's top-level ``vtk`` module.

The real ``vtk`` (= ``vtkmodules.all``) imports every one of VTK's ~150 modules, about 0.5 GB the
workbench never uses; the bundle ships only the VTK modules pyvista loads (packaging/hooks/
hook-pyvista._vtk.py). PyInstaller finds this file first (the spec puts packaging/shims on its path),
so ``import vtk`` in the bundle gives vtkCommonCore (vtkVersion, vtkObject, ...) and looks any other
class up in the VTK modules that are bundled.
"""

import importlib as _importlib
import sys as _sys

from vtkmodules.vtkCommonCore import *  # noqa: F403


def __getattr__(name):
    if name.startswith("__"):
        raise AttributeError(name)
    try:  # pyvista's own class -> module table
        import pyvista._vtk as _pv_vtk

        return getattr(_pv_vtk, name)
    except (ImportError, AttributeError):
        pass
    for mod_name, mod in list(_sys.modules.items()):
        if mod_name.startswith("vtkmodules.vtk") and hasattr(mod, name):
            return getattr(mod, name)
    for mod_name in ("vtkmodules.vtkRenderingOpenGL2", "vtkmodules.vtkFiltersCore"):
        mod = _importlib.import_module(mod_name)
        if hasattr(mod, name):
            return getattr(mod, name)
    raise AttributeError(f"module 'vtk' (bladecam bundle) has no attribute {name!r}: that VTK module is "
                         "not in the bundle")
