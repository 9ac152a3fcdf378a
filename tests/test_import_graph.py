"""The import graph (docs/architecture.md §1 Layers): one direction only, no cycles, no bare top-level packages.

Layering rules count every import, at module level or inside a function (a lazy import is still
a dependency). Cycle detection uses module-level imports only (not those inside functions or under
``if TYPE_CHECKING:``): those are the ones that run at import time, and a function-level import
is the usual, deliberate way to break a cycle.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import venv
from dataclasses import dataclass
from importlib.metadata import distributions
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("schemas", "recorder", "replay", "trackers")
BARE = FOLDERS  # names other projects own on PyPI; we must not install them
PACKAGE = "trackreplay"


@dataclass(frozen=True)
class Import:
    target: str  # the imported module (a submodule when ``from pkg import sub`` names one)
    line: int
    module_level: bool


def module_files() -> dict[str, Path]:
    """Our modules by installed name: ``replay/core/engine.py`` -> ``trackreplay.replay.core.engine``."""
    out = {}
    for top in (PACKAGE, *FOLDERS):
        base = ROOT / top
        for path in sorted(base.rglob("*.py")):
            parts = list(path.relative_to(base).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            prefix = [PACKAGE] if top == PACKAGE else [PACKAGE, top]
            out[".".join(prefix + parts)] = path
    return out


MODULES = module_files()


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports_of(name: str, path: Path) -> list[Import]:
    tree = ast.parse(path.read_text(), filename=str(path))
    is_package = path.name == "__init__.py"
    found: list[Import] = []

    def visit(node: ast.AST, module_level: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                visit(child, False)
            elif isinstance(child, ast.If) and _is_type_checking(child):
                visit(child, False)
            elif isinstance(child, ast.Import):
                found.extend(Import(a.name, child.lineno, module_level) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    anchor = name.split(".") if is_package else name.split(".")[:-1]
                    anchor = anchor[: len(anchor) - (child.level - 1)]
                    base = ".".join(anchor + ([child.module] if child.module else []))
                for alias in child.names:
                    sub = f"{base}.{alias.name}"
                    found.append(Import(sub if sub in MODULES else base, child.lineno, module_level))
            else:
                visit(child, module_level)

    visit(tree, True)
    return found


GRAPH = {name: imports_of(name, path) for name, path in MODULES.items()}


def _ours(target: str) -> bool:
    return target == PACKAGE or target.startswith(PACKAGE + ".")


def _violations(layer: str, allowed: tuple[str, ...]) -> list[str]:
    out = []
    for name, imports in GRAPH.items():
        if not name.startswith(f"{PACKAGE}.{layer}"):
            continue
        for imp in imports:
            if _ours(imp.target) and not any(imp.target == a or imp.target.startswith(a + ".") for a in allowed):
                out.append(f"{MODULES[name].relative_to(ROOT)}:{imp.line} imports {imp.target}")
    return out


def test_the_source_folders_were_found() -> None:
    assert {"trackreplay.replay.core.engine", "trackreplay.trackers.base", "trackreplay.recorder.annotate",
            "trackreplay.schemas.records", "trackreplay"} <= set(MODULES)


def test_trackers_import_only_schemas_and_trackers() -> None:
    assert _violations("trackers", (f"{PACKAGE}.schemas", f"{PACKAGE}.trackers")) == []


def test_schemas_import_nothing_else_of_ours() -> None:
    assert _violations("schemas", (f"{PACKAGE}.schemas",)) == []


def test_recorder_never_imports_replay() -> None:
    assert _violations("recorder", (f"{PACKAGE}.schemas", f"{PACKAGE}.recorder", f"{PACKAGE}.trackers")) == []


# replay/'s floors, lowest first: a sub-package imports only what lies on its own floor or below
# (each sub-package's ``__init__`` says the same in words).
BELOW_REPLAY = (f"{PACKAGE}.schemas", f"{PACKAGE}.trackers", f"{PACKAGE}.recorder")
REPLAY_FLOORS = {
    "log": ("log",),
    "views": ("views",),
    "core": ("log", "views", "core"),
    "analysis": ("log", "views", "core", "analysis"),
    "runs": ("log", "views", "core", "analysis", "runs"),
    "cli": ("log", "views", "core", "analysis", "runs", "cli"),
}


def test_replay_is_split_into_the_declared_sub_packages() -> None:
    top = {name.split(".")[2] for name in MODULES if name.startswith(f"{PACKAGE}.replay.")}
    assert top == set(REPLAY_FLOORS)


@pytest.mark.parametrize("floor", list(REPLAY_FLOORS))
def test_replay_sub_packages_import_only_their_floor_and_below(floor: str) -> None:
    allowed = BELOW_REPLAY + tuple(f"{PACKAGE}.replay.{f}" for f in REPLAY_FLOORS[floor])
    found = [v for v in _violations(f"replay.{floor}", allowed) if not v.endswith(f"imports {PACKAGE}")]  # __version__
    assert found == []


def test_the_rules_catch_a_back_edge(tmp_path: Path) -> None:
    """The checker itself: a function-level import of replay in recorder is found."""
    path = tmp_path / "annotate.py"
    path.write_text("import os\n\ndef f():\n    from trackreplay.replay.log.reader import LogReader\n    from . import log_summary\n")
    found = imports_of("trackreplay.recorder.annotate", path)
    assert [(i.target, i.module_level) for i in found] == [
        ("os", True), ("trackreplay.replay.log.reader", False), ("trackreplay.recorder.log_summary", False)]


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (or a self-import), Tarjan's algorithm."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10 * len(edges) + 100))

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in edges.get(v, ()):
                found.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            connect(v)
    return found


def test_cycles_are_detected() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles_at_module_level() -> None:
    edges = {name: {i.target for i in imports if i.module_level and i.target in MODULES and i.target != name}
             for name, imports in GRAPH.items()}
    assert cycles(edges) == []


# --- what the installed distribution provides -------------------------------------------------


def _our_distributions():
    return [d for d in distributions() if (d.metadata["Name"] or "").lower() == PACKAGE
            and Path(str(d.locate_file(""))).resolve() != ROOT]  # not the source tree's own egg-info


def test_the_installed_distribution_has_no_bare_top_level_packages() -> None:
    dists = _our_distributions()
    assert dists, "trackreplay is not installed in this environment (pip install -e .)"
    for dist in dists:
        assert (dist.read_text("top_level.txt") or PACKAGE).split() == [PACKAGE]
        tops = {Path(str(f)).parts[0] for f in dist.files or [] if not str(f).startswith("..")}
        assert not tops & set(BARE), f"{dist.locate_file('')} installs {sorted(tops & set(BARE))}"
    # Importing from outside the source tree (which would put the folders on sys.path) finds none
    # of the bare names in our files.
    code = ("import importlib.util, json, sys; "
            f"print(json.dumps({{n: getattr(importlib.util.find_spec(n), 'origin', None) for n in {list(BARE)!r}}}))")
    proc = subprocess.run([sys.executable, "-I", "-c", code], cwd=Path(os.sep), capture_output=True, text=True,
                          timeout=60, check=True)
    origins = json.loads(proc.stdout)
    ours = {n: o for n, o in origins.items() if o and Path(o).resolve().is_relative_to(ROOT)}
    assert ours == {}


SOURCES = ("setup.py", "pyproject.toml", "README.md", PACKAGE, *FOLDERS)


@pytest.mark.slow
def test_pypi_trackers_and_trackreplay_install_and_import_side_by_side(tmp_path: Path) -> None:
    """A fresh venv with the PyPI ``trackers`` and this repository (a copy, non-editable): both import.

    About 25-60 s (two pip installs from the package index); skipped when the index is unreachable.
    """
    import shutil

    src = tmp_path / "src"
    for name in SOURCES:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            src.mkdir(exist_ok=True)
            shutil.copy2(ROOT / name, src / name)
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    py = env_dir / "bin" / "python"
    pip = [str(py), "-m", "pip", "install", "-q", "--disable-pip-version-check"]
    got = subprocess.run([*pip, "trackers"], capture_output=True, text=True, timeout=600)
    if got.returncode != 0:
        pytest.skip(f"could not install trackers from the package index: {got.stderr.strip()[-300:]}")
    got = subprocess.run([*pip, str(src)], capture_output=True, text=True, timeout=900)
    assert got.returncode == 0, got.stderr[-2000:]
    code = ("import trackers, trackreplay, trackreplay.trackers.base, trackreplay.replay.core.engine; "
            "from pathlib import Path; "
            "assert Path(trackers.__file__).parent.name == 'trackers' and 'trackreplay' not in trackers.__file__; "
            "print(trackreplay.__version__)")
    done = subprocess.run([str(py), "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
