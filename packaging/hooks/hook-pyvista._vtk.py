"""pyvista >= 0.48 imports VTK lazily: ``pyvista._vtk`` maps each VTK class to its ``vtkmodules``
module and imports that module on first use (``importlib.import_module``), and
``pyvista.plotting._rendering_imports`` loads three rendering modules the same way. PyInstaller's
static analysis sees none of these imports, and pyinstaller-hooks-contrib's hook-pyvista only adds
pyvista's plotter-component entry points. This hook lists the VTK modules pyvista can load (the
contrib hooks of each ``vtkmodules.vtk*`` module then add the modules they depend on) and pyvista's
own lazily imported submodules.
"""

from PyInstaller import isolated
from PyInstaller.utils.hooks import collect_submodules


@isolated.decorate
def _pyvista_vtk_modules():
    import pyvista._vtk as v

    names = set(v._CORE_MODULES) | set(v._PLOTTING_MODULES) | set(v._OPENGL_MODULES)
    return sorted(names)


# loaded for their side effects (factory overrides) in pyvista/plotting/_rendering_imports.py, and
# by the irregular loaders at the end of pyvista/_vtk.py (vtkPythonItem for chart backgrounds)
_EXTRA = ["vtkRenderingContextOpenGL2", "vtkRenderingFreeType", "vtkRenderingMatplotlib",
          "vtkPythonContext2D"]

hiddenimports = [f"vtkmodules.{name}" for name in (*_pyvista_vtk_modules(), *_EXTRA)]

# pyvista's top-level __getattr__ and its component/theme registries import submodules by name.
# Leave out what a desktop bundle never runs: examples/datasets (downloads), Jupyter/trame, Sphinx.
_SKIP = ("pyvista.examples", "pyvista.demos", "pyvista.ext", "pyvista.jupyter", "pyvista.trame",
         "pyvista.plotting.tests", "pyvista.core.tests")
hiddenimports += collect_submodules(
    "pyvista", filter=lambda name: not name.startswith(_SKIP))
