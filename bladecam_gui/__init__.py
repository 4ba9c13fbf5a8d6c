"""bladecam workbench: the Qt GUI on top of the planning package ``core``."""

import core  # noqa: E402,F401  (first: one BLAS thread per process, set before numpy loads)
