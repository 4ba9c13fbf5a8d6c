"""Process-wide settings of the programs built on core (the command line, the workbench, the tests and
benchmarks), applied by their entry points before numpy is imported: importing core changes nothing.

- One BLAS thread per process. The parallel work is explicit (one thread per cutter side, forked path
  workers and table helpers); OpenBLAS's own threads only compete with it on two cores, and do not
  survive a fork well.
- No transparent huge pages for numpy's arrays: a plan allocates and frees arrays of tens of MB
  thousands of times, and the kernel zeroes each huge page on its first touch and splits or copies it
  after a fork (docs/DECISIONS.md).
An explicit setting in the environment wins over both.
"""

from __future__ import annotations

import os

#: the variables set, and their values
SETTINGS = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
            "NUMPY_MADVISE_HUGEPAGE": "0"}


def configure_process() -> None:
    """Set SETTINGS where the environment does not (effective only before numpy is imported)."""
    for name, value in SETTINGS.items():
        os.environ.setdefault(name, value)
