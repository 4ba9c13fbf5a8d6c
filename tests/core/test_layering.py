"""The shape of core (CONVENTIONS.md, "The layout"): imports run downward only (no cycle among core's
modules, counting imports inside functions, and no arrow from a layer to one above it: ``LAYERS``),
core never imports the workbench, Qt or VTK, no module is over 500 lines, no function outside the
command line takes more than 8 parameters, and only the command line defers imports into functions
(to start quickly)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[2] / "core"
FORBIDDEN = ("bladecam_gui", "PySide6", "PyQt5", "PyQt6", "shiboken6", "vtk", "vtkmodules", "pyvista",
             "pyvistaqt", "pyqtgraph", "qtpy")
#: the modules that may import inside functions: the command line loads only what its command needs
DEFERRED_OK = {"core.cli"}
MAX_LINES = 500
MAX_PARAMETERS = 8
#: core's layers, bottom first: a module imports its own layer and the ones below it, never one above
#: (the records and exceptions; the shared helpers; the stages in the paper's order; a whole plan's
#: record; the files; the planner that chains the stages; the independent verification; the command line)
LAYERS = ("core.errors", "core.records", "core.util", "core.blade", "core.paths", "core.schedule", "core.machine",
          "core.result", "core.output", "core.budget", "core.planner", "core.verify", "core.cli", "core.__main__")


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(CORE.rglob("*.py")):
        parts = path.relative_to(CORE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


def _imports(name: str, path: Path) -> list[tuple[str, bool, int]]:
    """(imported module, inside a function, line) for every import of ``path``."""
    tree = ast.parse(path.read_text(), str(path))
    found = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.Import):
                found.extend((a.name, in_function, child.lineno) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
                    base = base[:len(base) - (child.level - 1)]
                    mod = ".".join(base + ([child.module] if child.module else []))
                else:
                    mod = child.module or ""
                found.append((mod, in_function, child.lineno))
                found.extend((f"{mod}.{a.name}", in_function, child.lineno) for a in child.names)
            elif isinstance(child, ast.If) and _is_type_checking(child.test):
                continue  # (annotations only: never executed)
            visit(child, inner)

    visit(tree, False)
    return found


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def import_graph() -> dict[str, set[str]]:
    """core module -> the core modules it imports (a package's __init__ counts as its package)."""
    mods = _modules()
    graph = {}
    for name, path in mods.items():
        targets = set()
        for mod, _, _ in _imports(name, path):
            while mod and mod not in mods:
                mod = mod.rpartition(".")[0]
            if mod and mod != name and mod != "core":  # (core's own __init__ holds only its version)
                targets.add(mod)
        graph[name] = targets
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle of ``graph`` as a list of modules (first == last), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def dfs(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                found = dfs(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            found = dfs(node)
            if found:
                return found
    return None


def floors(graph: dict[str, set[str]]) -> dict[str, int]:
    """Each module's import floor: 0 for a module that imports none of core, else one above the
    highest floor it imports (the graph must have no cycle)."""
    memo: dict[str, int] = {}

    def floor(node: str) -> int:
        if node not in memo:
            memo[node] = 1 + max((floor(n) for n in graph[node]), default=-1)
        return memo[node]

    return {n: floor(n) for n in graph}


def test_no_import_cycle_in_core():
    assert find_cycle(import_graph()) is None, f"import cycle: {' -> '.join(find_cycle(import_graph()))}"


def test_find_cycle_finds_one():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


def test_core_never_imports_the_workbench_qt_or_vtk():
    bad = [f"{path.relative_to(CORE.parent)}:{line} imports {mod}"
           for name, path in _modules().items() for mod, _, line in _imports(name, path)
           if mod.split(".")[0] in FORBIDDEN]
    assert not bad, "\n".join(bad)


def test_only_the_command_line_imports_inside_functions():
    bad = [f"{path.relative_to(CORE.parent)}:{line} imports {mod} inside a function"
           for name, path in _modules().items() if name not in DEFERRED_OK
           for mod, inside, line in _imports(name, path) if inside and mod.split(".")[0] == "core"]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("name", sorted(_modules()))
def test_module_is_short(name):
    n = len(_modules()[name].read_text().splitlines())
    assert n <= MAX_LINES, f"{name} has {n} lines (at most {MAX_LINES})"


def test_the_records_are_the_bottom_floor():
    graph = import_graph()
    assert graph["core.records"] <= {"core.errors"}
    level = floors(graph)
    for stage in ("core.blade", "core.paths", "core.schedule", "core.machine", "core.output"):
        for name in graph:
            if name.startswith(stage + "."):
                # a stage's modules import only stages below it in the paper's order
                later = [m for m in graph[name] if m.startswith(("core.planner", "core.cli", "core.verify"))]
                assert not later, f"{name} imports {later}"
    assert level["core.planner"] > level["core.output.writer"] or "core.output.writer" not in graph["core.planner"]


def test_the_stages_import_downward_in_the_papers_order():
    order = ["core.util", "core.blade", "core.paths", "core.schedule", "core.machine", "core.output"]
    graph = import_graph()
    for name, targets in graph.items():
        here = next((k for k, p in enumerate(order) if name.startswith(p + ".")), None)
        if here is None:
            continue
        for t in targets:
            there = next((k for k, p in enumerate(order) if t.startswith(p + ".")), None)
            assert there is None or there <= here, f"{name} imports {t}, a later stage"


def test_core_plans_without_the_gui_packages(tmp_path):
    """A whole plan (paths, schedule, machines, files) and its verification in a process where the
    workbench, Qt and VTK cannot be imported at all."""
    import subprocess
    import sys

    code = f"""
import sys
class Blocked:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {FORBIDDEN!r}:
            raise ImportError("blocked: " + name)
sys.meta_path.insert(0, Blocked())
from core.cli import main
assert main(["plan", "--dr", "4", "--dd", "0.5", "--out", {str(tmp_path / "plan")!r}]) == 0
assert main(["verify", {str(tmp_path / "plan")!r}]) == 0
print("ok", sorted(m for m in sys.modules if m.split(".")[0] in {FORBIDDEN!r}))
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip().splitlines()[-1] == "ok []"


def layer(name: str) -> int:
    """The index in LAYERS of a core module's layer."""
    found = [k for k, top in enumerate(LAYERS) if name == top or name.startswith(top + ".")]
    assert found, f"{name} is in none of core's layers (test_layering.LAYERS)"
    return found[0]


def upward_arrows(graph: dict[str, set[str]]) -> list[str]:
    """The imports of ``graph`` that run from a layer up to a higher one."""
    return [f"{name} imports {t}" for name, targets in sorted(graph.items()) for t in sorted(targets)
            if layer(t) > layer(name)]


def test_no_import_runs_up_a_layer():
    bad = upward_arrows(import_graph())
    assert not bad, "\n".join(bad)


def test_upward_arrows_finds_one():
    assert upward_arrows({"core.paths.x": {"core.schedule.y", "core.util.z"}, "core.util.z": set()}) == [
        "core.paths.x imports core.schedule.y"]


def long_parameter_lists(name: str, path: Path) -> list[str]:
    """The functions of a module with more than MAX_PARAMETERS parameters (self and cls not counted)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            names = [x.arg for x in (*a.posonlyargs, *a.args, *a.kwonlyargs)] + \
                [x.arg for x in (a.vararg, a.kwarg) if x is not None]
            n = len([x for x in names if x not in ("self", "cls")])
            if n > MAX_PARAMETERS:
                found.append(f"{name}.{node.name} (line {node.lineno}) takes {n} parameters")
    return found


def test_no_function_outside_the_command_line_takes_more_than_8_parameters():
    bad = [line for name, path in _modules().items() if name not in DEFERRED_OK
           for line in long_parameter_lists(name, path)]
    assert not bad, "\n".join(bad)
