"""bladecam workbench: the Qt GUI on top of the planning package ``core``."""

from core.util.process import configure_process

configure_process()  # (first: one BLAS thread per process, set before numpy loads)
