"""Project files: round trip, relative blade paths, validation naming the key."""

import json
import tomllib

import pytest

from core.errors import BladecamError, OutputError
from core.output.project import Project, ProjectError, load_project, project_text, save_project
from core.planner import PlanParameters


def test_round_trip_every_field(tmp_path):
    params = PlanParameters(tool_radius=2.0, dr=0.4, dd=0.3, h_safe=2.6, k_max=0.12, tool_length=35.0,
                            feed=1200.0, a_max=450.0, mode="symmetric", min_feed=250.0)
    proj = Project(source="sample", axis="x", params=params, profile="smooth", period=12.5, axes=True)
    path = save_project(proj, tmp_path / "job.toml")
    assert load_project(path) == proj
    text = path.read_text()
    assert "[parameters]" in text and "h_safe = 2.6" in text and 'mode = "symmetric"' in text


def test_a_project_without_a_minimum_feed_takes_the_default(tmp_path):
    path = save_project(Project(), tmp_path / "p.toml")
    text = path.read_text()
    assert 'min_feed = "auto"' in text
    path.write_text(text.replace('min_feed = "auto"\n', ""))
    back = load_project(path)
    assert back.params.min_feed is None
    assert back.params.resolved().min_feed == pytest.approx(0.3 * back.params.feed)


def test_auto_values_round_trip(tmp_path):
    proj = Project()  # dr, h_safe and period default
    path = save_project(proj, tmp_path / "p.toml")
    data = tomllib.loads(path.read_text())
    assert data["parameters"]["dr"] == "auto" and data["schedule"]["period_ms"] == "auto"
    back = load_project(path)
    assert back == proj and back.params.dr is None and back.period is None


def test_blade_paths_relative_to_the_project(tmp_path):
    (tmp_path / "blades").mkdir()
    face, back = tmp_path / "blades" / "face.stl", tmp_path / "blades" / "back.stl"
    proj = Project(source=f"{face},{back}", axis="x")
    path = save_project(proj, tmp_path / "p.toml")
    data = tomllib.loads(path.read_text())
    assert data["blade"]["source"] == "blades/face.stl,blades/back.stl"
    assert load_project(path).source == f"{face.resolve()},{back.resolve()}"
    # a copied project folder finds its own blades
    other = tmp_path / "copy"
    other.mkdir()
    (other / "p.toml").write_text(path.read_text())
    assert load_project(other / "p.toml").source.startswith(str(other.resolve() / "blades"))


@pytest.mark.parametrize("edit, key", [
    (("parameters", "h_safe", "2.0"), "h_safe"),          # a string, not a number
    (("parameters", "k_max", 0.9), None),                  # accepted: inside (0, 1)
    (("parameters", "dr", -1.0), "dr"),
    (("parameters", "mode", "both"), "mode"),
    (("parameters", "hsafe", 1.0), "hsafe"),               # a typo is an unknown key
    (("blade", "axis", "w"), "axis"),
    (("schedule", "profile", "cubic"), "profile"),
    (("schedule", "period_ms", 0.0), "period_ms"),
    (("schedule", "axes", "yes"), "axes"),
    (("parameters", "h_safe", 100.0), "h_safe"),           # impossible: above 10 tool radii
    (("blade", "index", 0), "index"),
    (("blade", "index", 1.5), "index"),
    (("blade", "r_min", -2.0), "r_min"),
    (("blade", "units", "ft"), "units"),
])
def test_bad_values_name_the_key(tmp_path, edit, key):
    path = save_project(Project(), tmp_path / "p.toml")
    table, name, value = edit
    data = tomllib.loads(path.read_text())
    data[table][name] = value
    lines = []
    for t in ("blade", "parameters", "schedule"):
        lines.append(f"[{t}]")
        for k, v in data[t].items():
            lines.append(f"{k} = {json.dumps(v)}")  # JSON scalars are TOML scalars
    path.write_text("format = 1\n" + "\n".join(lines) + "\n")
    if key is None:
        assert load_project(path).params.k_max == 0.9
        return
    with pytest.raises(ProjectError) as exc:
        load_project(path)
    assert key in str(exc.value) and str(path) in str(exc.value)
    assert isinstance(exc.value, BladecamError)


def test_missing_key_and_bad_syntax(tmp_path):
    path = save_project(Project(), tmp_path / "p.toml")
    text = path.read_text()
    path.write_text(text.replace("feed = 1000.0\n", ""))
    with pytest.raises(ProjectError, match="feed"):
        load_project(path)
    path.write_text(text.replace("[schedule]", "[schedule"))
    with pytest.raises(ProjectError, match="TOML"):
        load_project(path)
    path.write_text(text.replace("format = 1", "format = 7"))
    with pytest.raises(ProjectError, match="format"):
        load_project(path)
    with pytest.raises(ProjectError, match="cannot read"):
        load_project(tmp_path / "nothing.toml")


def test_propeller_blade_index_hub_cut_and_units_round_trip(tmp_path):
    """[blade] index, r_min and units are the SOURCE string's reading options, written back as the keys."""
    mesh = tmp_path / "propeller.stl"
    proj = Project(source=f"{mesh}?blade=3&r_min=38.5&units=cm", axis="x")
    path = save_project(proj, tmp_path / "p.toml")
    data = tomllib.loads(path.read_text())
    assert data["blade"] == {"source": "propeller.stl", "axis": "x", "index": 3, "r_min": 38.5, "units": "cm"}
    assert load_project(path) == Project(source=f"{mesh.resolve()}?blade=3&r_min=38.5&units=cm", axis="x")
    path.write_text(path.read_text().replace("index = 3\n", "").replace("units = \"cm\"\n", ""))
    assert load_project(path).source == f"{mesh.resolve()}?r_min=38.5"


def test_axes_key_is_optional(tmp_path):
    path = save_project(Project(axes=True), tmp_path / "p.toml")
    assert "axes = true" in path.read_text()
    path.write_text(path.read_text().replace("axes = true\n", ""))
    assert load_project(path).axes is False


def test_unwritable_folder(tmp_path):
    with pytest.raises(OutputError):
        save_project(Project(), tmp_path / "no" / "such" / "p.toml")


def test_text_is_small_and_commented():
    text = project_text(Project())
    assert text.startswith("# bladecam project")
    assert len(text.splitlines()) < 25
