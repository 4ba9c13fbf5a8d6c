"""`bladecam blade info` for the three sources, and clean errors (exit 2, no traceback)."""

import json
import subprocess
import sys

import pytest

from ..conftest import bladecam


def run(*args):
    return bladecam(*args, timeout=120)


def test_info_sample_json():
    out = run("blade", "info", "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["tip_radius_mm"] == pytest.approx(229.36)
    assert info["chord_mm"]["0.2"] == pytest.approx(106.89, rel=0.005)
    assert info["chord_mm"]["0.5"] == pytest.approx(142.18, rel=0.005)
    assert info["chord_mm"]["0.95"] == pytest.approx(17.17, rel=0.005)
    assert set(info["max_thickness_mm"]) == {"0.2", "0.5", "0.95"}


def test_info_text():
    out = run("blade", "info")
    assert out.returncode == 0 and "tip radius" in out.stdout and "229.360" in out.stdout


def test_info_two_meshes(bladex_dir):
    out = run("blade", "info", "--blade", f"{bladex_dir/'upper.stl'},{bladex_dir/'lower.stl'}", "--axis", "x", "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["tip_radius_mm"] == pytest.approx(125.0, rel=1e-3)
    assert info["hub_radius_mm"] == pytest.approx(34.375, rel=1e-3)
    assert info["chord_mm"]["0.5"] > 0


def test_info_table_file(tmp_path):
    from core.blade.source import sample_table_path

    p = tmp_path / "copy.csv"
    p.write_text(sample_table_path().read_text())
    out = run("blade", "info", "--blade", str(p), "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["chord_mm"]["0.5"] == pytest.approx(142.18, rel=0.005)


@pytest.mark.parametrize("name, content, expect", [
    ("missing.csv", None, "not found"),
    ("bad.csv", "# blades: 3\nr/R,c/D\n0.2,0.1\n", "missing metadata"),
    ("empty.stl", "", "empty.stl"),
    ("garbage.stl", "hello, I am not a mesh\n", "garbage.stl"),
])
def test_info_bad_input_exits_2_without_traceback(tmp_path, name, content, expect):
    p = tmp_path / name
    if content is not None:
        p.write_text(content)
    out = run("blade", "info", "--blade", str(p))
    assert out.returncode == 2
    assert expect in out.stderr and "Traceback" not in out.stderr


def test_output_into_a_closed_pipe_stops_quietly():
    """`bladecam ... | head`: when the reader goes away the command stops without a traceback."""
    import time

    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(1.0); "
                             "import sys; from core.cli import main; sys.exit(main(['blade', 'info', '--json']))"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # the reader is gone before anything is written
    time.sleep(0.1)
    with proc.stderr:  # (closed: no ResourceWarning for an unclosed file)
        err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 141, err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
