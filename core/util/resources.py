"""Where the shipped resources are (sample blade, default machine.toml, icon): the ``resources`` folder
beside the ``core`` package, in the source tree, an installed copy and the desktop bundle alike."""

from __future__ import annotations

from pathlib import Path


def resources_dir() -> Path:
    """The folder of shipped resources."""
    return Path(__file__).resolve().parents[2] / "resources"
