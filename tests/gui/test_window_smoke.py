"""The first window shows the sample blade."""

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def test_window_shows_sample_blade(main_window, qtbot):
    assert main_window.load_blade_source("sample")
    assert set(main_window.blade_view.actors) == {"face", "back"}
    main_window.plotter.render()
    img = np.asarray(main_window.plotter.screenshot(return_img=True))
    assert img.ndim == 3 and img.shape[0] > 100
    flat = img.reshape(-1, img.shape[-1])[:, :3].astype(int)
    # not one flat colour, and the blade colours are present (light grey-blue pixels)
    assert len(np.unique(flat, axis=0)) > 50
    light = (flat.min(axis=1) > 120).mean()
    assert light > 0.02, f"only {light:.3%} light pixels: the blade is not visible"
    assert "tip radius 229.36" in main_window.statusBar().currentMessage()


def test_bad_blade_source_shows_dialog_and_keeps_blade(main_window, qtbot, monkeypatch, tmp_path):
    from PySide6.QtWidgets import QMessageBox

    shown = []
    monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: shown.append(a[2]))
    assert main_window.load_blade_source("sample")
    before = main_window.state.blade
    bad = tmp_path / "broken.stl"
    bad.write_text("this is not a mesh")
    assert not main_window.load_blade_source(str(bad))
    assert shown and "broken.stl" in shown[0]
    assert main_window.state.blade is before
