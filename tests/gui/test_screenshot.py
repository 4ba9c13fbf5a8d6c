"""``bladecam gui --screenshot PNG`` (``make run`` without a display): the workbench plans, saves its
picture once the plan is shown, says where, and quits with status 0."""

import subprocess
import sys

import numpy as np
import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.gui

PROJECT = """format = 1
[blade]
source = "sample"
axis = "z"
[parameters]
tool_radius = 1.5
dr = 4.0
dd = 0.5
h_safe = "auto"
k_max = 0.15
tool_length = 40.0
feed = 1000.0
a_max = 500.0
mode = "collaborative"
[schedule]
profile = "sigmoid"
period_ms = "auto"
axes = false
"""


def test_the_workbench_pictures_its_plan_and_quits(tmp_path):
    from PySide6.QtGui import QImage

    project = tmp_path / "coarse.toml"
    project.write_text(PROJECT)
    png = tmp_path / "pictures" / "workbench.png"
    done = subprocess.run([sys.executable, "-m", "bladecam_gui", str(project), "--screenshot", str(png)],
                          cwd=REPO, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert f"picture of the workbench: {png}" in done.stdout
    image = QImage(str(png))
    assert image.width() >= 1000 and image.height() >= 600
    pixels = np.array([image.pixel(x, y) for x in range(0, image.width(), 37)
                       for y in range(0, image.height(), 37)])
    assert len(np.unique(pixels)) > 20  # (a drawn window, not a blank one)
