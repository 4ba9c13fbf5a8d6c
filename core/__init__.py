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
# No transparent huge pages for numpy's large arrays: a plan allocates and frees arrays of tens of MB
# thousands of times, and the kernel zeroes each huge page on its first touch (2 MB at a time, also
# for a page barely used) and splits or copies it after a fork. The feed override took 2.9 s with
# them and 2.3 s without (system time 0.82 -> 0.19 s); `bladecam plan` 9.7-10.2 s -> 9.4-9.6 s
# (docs/DECISIONS.md). numpy reads this when it is imported; an explicit setting wins.
_os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

__version__ = "0.1.0"
