"""The package's layers, read from its imports (docs/developer.md, section Layers).

Every ``import`` statement of ``uvms_qp`` is parsed (module level, inside functions and under
``if TYPE_CHECKING:``), relative imports are resolved, and each internal import is mapped to the
layer of the package it reaches. A module may import only from the layers above its own; within
layer 0 only from the modules listed before it; ``hqp`` only from layer 0 (the solver never sees a
robot) and ``safety`` only from ``hqp`` and layer 0; ``tasks`` and ``constraints`` never import
each other; nothing in the library imports ``testing``. Import-time cycles between modules are
reported (``TYPE_CHECKING`` imports do not run, so they may close a loop, but must still respect
the layers).

An internal import inside a function is refused: it is how a cycle gets hidden. The one exception
is the command line: ``uvms_qp/cli`` modules import the heavy layers (``model`` brings Pinocchio,
``hqp`` brings qpsolvers and scipy.optimize, ``sim`` and ``bench`` bring both) inside their
``run`` functions, so that ``uvms-qp --help`` and the parsing of a wrong option do not load them.
Measured on the 2-core machine (7 interleaved runs, medians): ``python -m uvms_qp.cli --help``
takes 0.37 s lazily and 2.4 s when the sub-commands' imports are made at module level (``import
uvms_qp.hqp.registry`` alone 1.5 s, ``uvms_qp.model`` alone 0.62 s; bare ``python`` 0.10 s).
Lazy imports of optional third-party packages (plotly, pink, qpsolvers back-ends) are not internal
imports and are not checked here.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "uvms_qp"

#: The layer of each top-level module or sub-package (docs/developer.md, section Layers).
#: ``None``: outside the layers (``testing`` may import anything and nothing imports it;
#: ``scenarios`` holds data files only and imports nothing).
LAYERS: dict[str, int | None] = {
    "errors": 0, "_validation": 0, "rows": 0, "analytic": 0,
    "model": 1,
    "tasks": 2, "constraints": 2, "dynamics": 2,
    "stack": 3, "hqp": 3,
    "safety": 4,
    "controller": 5,
    "schemes": 6,
    "sim": 7,
    "bench": 8,
    "cli": 9,
    "__main__": 10,
    "testing": None, "scenarios": None,
}

#: Layer 0 in order: each of these imports only the ones before it.
LAYER0_ORDER = ("errors", "_validation", "rows", "analytic")

#: Packages that know less than every layer above them.
KNOWS_ONLY: dict[str, frozenset[str]] = {
    "dynamics": frozenset({*LAYER0_ORDER, "model"}),
    "hqp": frozenset(LAYER0_ORDER),
    "safety": frozenset({*LAYER0_ORDER, "hqp"}),
}

#: Function-local internal imports allowed: importing package -> packages it may import lazily.
LAZY_ALLOWED: dict[str, frozenset[str]] = {
    "cli": frozenset({"model", "hqp", "sim", "bench"}),
}

ROOT_UNIT = "<package>"  # uvms_qp/__init__.py: errors and ``__version__``, the rest lazily


@dataclass(frozen=True)
class Import:
    """One internal import: where it is written and which module it reaches."""

    path: str  # file, relative to the repository
    line: int
    source: str  # dotted name of the importing module
    target: str  # dotted name of the imported module
    local: bool  # inside a function
    type_only: bool  # under ``if TYPE_CHECKING:``


def unit(module: str) -> str:
    """The top-level module or sub-package of ``uvms_qp`` that ``module`` belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ROOT_UNIT


def _module_name(path: str) -> tuple[str, bool]:
    parts = list(Path(path).with_suffix("").parts)
    is_package = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_package else parts), is_package


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _walk(node: ast.AST, local: bool = False, type_only: bool = False
          ) -> Iterator[tuple[ast.Import | ast.ImportFrom, bool, bool]]:
    """Every import statement under ``node`` with its (inside a function, TYPE_CHECKING) flags."""
    if isinstance(node, ast.If) and _is_type_checking(node.test):
        for child in node.body:
            yield from _walk(child, local, True)
        for child in node.orelse:
            yield from _walk(child, local, type_only)
        return
    if isinstance(node, ast.Import | ast.ImportFrom):
        yield node, local, type_only
        return
    inner = local or isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
    for child in ast.iter_child_nodes(node):
        yield from _walk(child, inner, type_only)


def _lazy_names(tree: ast.Module) -> dict[str, str]:
    """The ``_LAZY`` table of a package facade: public name -> relative module (``".hqp"``)."""
    for node in tree.body:
        if isinstance(node, ast.AnnAssign | ast.Assign):
            targets = [node.target] if isinstance(node, ast.AnnAssign) else node.targets
            if any(isinstance(t, ast.Name) and t.id == "_LAZY" for t in targets):
                return ast.literal_eval(node.value) if node.value is not None else {}
    return {}


def collect(sources: Mapping[str, str]) -> list[Import]:
    """Every internal import of the modules in ``sources`` (relative path -> source text)."""
    modules = {_module_name(p)[0] for p in sources}
    facade = {name: PACKAGE + rel for name, rel in
              _lazy_names(ast.parse(sources.get(f"{PACKAGE}/__init__.py", ""))).items()}
    found: list[Import] = []
    for path, text in sorted(sources.items()):
        source, is_package = _module_name(path)
        here = source.split(".") if is_package else source.split(".")[:-1]
        for node, local, type_only in _walk(ast.parse(text, path)):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                if node.level:
                    base = ".".join(here[: len(here) - node.level + 1])
                    module = f"{base}.{node.module}" if node.module else base
                else:
                    module = node.module or ""
                # ``from pkg import sub`` reaches the sub-module; ``from uvms_qp import Name``
                # reaches the module the facade loads Name from.
                targets = []
                for alias in node.names:
                    if f"{module}.{alias.name}" in modules:
                        targets.append(f"{module}.{alias.name}")
                    elif module == PACKAGE and alias.name in facade:
                        targets.append(facade[alias.name])
                    else:
                        targets.append(module)
            for target in dict.fromkeys(targets):
                if target == PACKAGE or target.startswith(PACKAGE + "."):
                    found.append(Import(path, node.lineno, source, target, local, type_only))
    return found


def _layer_problem(a: str, b: str) -> str | None:
    """Why unit ``a`` may not import unit ``b`` (None when it may)."""
    if a == b or b == ROOT_UNIT:
        return None
    if b not in LAYERS:
        return f"{b} is not in the layer table"
    if a not in LAYERS and a != ROOT_UNIT:
        return f"{a} is not in the layer table"
    if b == "testing":
        return "the library never imports testing"
    if a == "testing":
        return None
    if a == "scenarios":
        return "scenarios holds data only"
    if b == "scenarios":
        return None
    if a == ROOT_UNIT:
        return None if LAYERS[b] == 0 else "the package facade imports layer 0 only"
    la, lb = LAYERS[a], LAYERS[b]
    assert la is not None and lb is not None
    if a in KNOWS_ONLY and b not in KNOWS_ONLY[a]:
        return f"{a} knows only {', '.join(sorted(KNOWS_ONLY[a]))}"
    if la == lb == 0:
        ok = LAYER0_ORDER.index(b) < LAYER0_ORDER.index(a)
        return None if ok else "layer 0 imports only the modules before it"
    if lb == la:
        return "same-layer siblings never import each other"
    if lb > la:
        return "a layer imports only the layers above it"
    return None


def _cycles(imports: list[Import]) -> list[list[str]]:
    """Strongly connected groups of modules that import each other when imported."""
    graph: dict[str, set[str]] = {}
    for imp in imports:
        if imp.type_only or imp.local:
            continue
        # Importing a.b.c runs a, a.b, a.b.c; the importer's own packages have already started.
        parts = imp.target.split(".")
        for k in range(1, len(parts) + 1):
            target = ".".join(parts[:k])
            if target != imp.source and not imp.source.startswith(target + "."):
                graph.setdefault(imp.source, set()).add(target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan's algorithm
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1 or v in graph.get(v, ()):
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return groups


def violations(sources: Mapping[str, str]) -> list[str]:
    """Every breach of the layers in ``sources`` (relative path -> source text), one per line."""
    imports = collect(sources)
    found = []
    for imp in imports:
        a, b = unit(imp.source), unit(imp.target)
        where = f"{imp.path}:{imp.line}: {imp.source} imports {imp.target}"
        problem = _layer_problem(a, b)
        if problem is not None:
            la, lb = LAYERS.get(a, "?"), LAYERS.get(b, "?")
            found.append(f"{where} ({a}, layer {la} -> {b}, layer {lb}): {problem}")
        if imp.local and b not in LAZY_ALLOWED.get(a, ()):
            found.append(f"{where} inside a function: import it at module level (a cycle is "
                         "fixed by moving code to its layer)")
    for group in _cycles(imports):
        found.append(f"import cycle: {' -> '.join(group)}")
    return found


def package_sources() -> dict[str, str]:
    """Relative path -> source text of every module of the package."""
    return {p.relative_to(ROOT).as_posix(): p.read_text(encoding="utf-8")
            for p in sorted((ROOT / PACKAGE).rglob("*.py"))}


def test_package_respects_its_layers():
    found = violations(package_sources())
    assert not found, "\n".join(found)


def test_every_package_is_in_the_layer_table():
    units = {unit(_module_name(p)[0]) for p in package_sources()} - {ROOT_UNIT}
    assert units == set(LAYERS)


def test_layer_table_matches_the_developer_guide():
    text = (ROOT / "docs" / "developer.md").read_text(encoding="utf-8")
    section = text.split("## Layers", 1)[1].split("\n## ", 1)[0]
    documented: dict[str, int | None] = {}
    for layer, names in re.findall(r"^\| (\d+|-) \| ([^|]+) \|", section, re.MULTILINE):
        for name in re.findall(r"`([\w.]+)/?`", names):
            documented[name] = None if layer == "-" else int(layer)
    assert documented == LAYERS
    row0 = re.search(r"^\| 0 \| ([^|]+) \|", section, re.MULTILINE)
    assert row0 is not None
    assert tuple(re.findall(r"`([\w.]+)/?`", row0.group(1))) == LAYER0_ORDER


# --- the checker itself catches real breaches ------------------------------------------------

CLEAN = {
    "uvms_qp/__init__.py": '_LAZY = {"Controller": ".controller"}\nfrom .errors import E\n',
    "uvms_qp/errors.py": "",
    "uvms_qp/rows.py": "from .errors import E\n",
    "uvms_qp/model/__init__.py": "from ..errors import E\n",
    "uvms_qp/tasks/__init__.py": "from ..model import Model\n",
    "uvms_qp/constraints/__init__.py": "",
    "uvms_qp/controller/__init__.py": "from .controller import Controller\n",
    "uvms_qp/controller/controller.py": (
        "from typing import TYPE_CHECKING\nfrom ..tasks import Task\n"
        "if TYPE_CHECKING:\n    from ..model import State\n"),
    "uvms_qp/sim/__init__.py": "",
    "uvms_qp/sim/runner.py": (
        "from .. import __version__\nimport uvms_qp.controller.controller\n"
        "def f():\n    import plotly\n"),
    "uvms_qp/cli/run.py": "def run(args):\n    from ..sim.runner import simulate\n",
    "uvms_qp/testing/faults.py": "from ..controller import Controller\n",
}


def test_checker_passes_a_clean_package():
    assert violations(CLEAN) == []


@pytest.mark.parametrize(("path", "source", "expected"), [
    ("uvms_qp/model/state.py", "from ..controller import Controller\n",
     "model, layer 1 -> controller, layer 5"),
    ("uvms_qp/model/state.py", "import uvms_qp.controller as c\n",
     "model, layer 1 -> controller, layer 5"),
    ("uvms_qp/model/state.py",
     "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..tasks import Task\n",
     "uvms_qp/model/state.py:3"),
    ("uvms_qp/tasks/posture.py", "from ..constraints import Bounds\n",
     "same-layer siblings never import each other"),
    ("uvms_qp/hqp/solver.py", "from ..model import Model\n", "hqp knows only"),
    ("uvms_qp/errors.py", "from .rows import Rows\n", "layer 0 imports only the modules before"),
    ("uvms_qp/sim/runner.py", "from ..testing.faults import inject\n",
     "the library never imports testing"),
    ("uvms_qp/tasks/posture.py", "from uvms_qp import Controller\n",
     "tasks, layer 2 -> controller, layer 5"),
    ("uvms_qp/sim/deep/inner.py", "from ...tasks import Task\ndef f():\n    from ... import rows\n",
     "uvms_qp/sim/deep/inner.py:3: uvms_qp.sim.deep.inner imports uvms_qp.rows inside a function"),
    ("uvms_qp/controller/more.py", "def f():\n    from .controller import Controller\n",
     "inside a function"),
    ("uvms_qp/cli/run.py", "def run(args):\n    from ..errors import E\n", "inside a function"),
    ("uvms_qp/newthing.py", "from .errors import E\n", "newthing is not in the layer table"),
])
def test_checker_reports_a_breach(path, source, expected):
    found = violations({**CLEAN, path: source})
    assert any(expected in line for line in found), found


def test_checker_reports_a_cycle_but_not_through_type_checking():
    cyclic = {**CLEAN,
              "uvms_qp/sim/metrics.py": "from .runner import simulate\n",
              "uvms_qp/sim/runner.py": "from .metrics import compute\n"}
    assert violations(cyclic) == [
        "import cycle: uvms_qp.sim.metrics -> uvms_qp.sim.runner"]
    type_only = {**cyclic, "uvms_qp/sim/metrics.py":
                 "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .runner import R\n"}
    assert violations(type_only) == []
