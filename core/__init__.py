"""bladecam core: planning for double-sided collaborative machining of propeller blades.

Pure numpy/scipy/trimesh; never imports Qt or VTK.
"""
import os as _os

# One BLAS thread per process. The parallel work here is explicit (one thread per cutter side, forked
# path workers and table helpers); OpenBLAS's own threads only compete with it: on two cores the two
# sides' axis smoothing took 2.2 s with them and 1.0 s without; and OpenBLAS's threads do not
# survive a fork well (a forked helper's smoothing took 5.5 s instead of 0.95). Set before numpy is
# imported (core is imported first by the CLI, the workbench and the tests); an explicit setting wins.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_name, "1")

__version__ = "0.1.0"
