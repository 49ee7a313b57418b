"""The layout of the Python package (tools/wetclutch): dependencies run one way, no import circle, no file
over 600 lines.

The import graph is read from the source (ast), not from a running interpreter: every import of a
wetclutch module, at the top of a file or inside a function, is an edge; importing a.b.c also runs the
__init__ of a and a.b (an edge to each, unless the importer lives in it: then it is already running).
Imports under `if TYPE_CHECKING:` never run; the only ones allowed are the reference's annotations naming
the Calibration type (the loader above it checks the film table with the reference's film equations).
"""
from __future__ import annotations

import ast
import graphlib
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "tools" / "wetclutch"
MAX_LINES = 600

# Each role imports only from the roles before it (the same layer: not from each other).
LAYERS = (
    ("util",),
    ("reference",),
    ("calibration",),
    ("gearbox",),
    ("generate", "simulate", "hil"),
    ("identify", "shift"),
    ("studies",),
    ("cycle",),
    ("cli",),
)
TYPE_ONLY_ALLOWED = {("reference", "wetclutch.calibration.parameters")}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


MODULES = _modules()


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _resolve(importer: str, node: ast.ImportFrom | ast.Import) -> list[str]:
    """The wetclutch modules an import statement runs (the imported module and the names that are modules)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "wetclutch"]
    if node.level:
        base = importer if _is_package(importer) else importer.rsplit(".", 1)[0]
        for _ in range(node.level - 1):
            base = base.rsplit(".", 1)[0]
        target = f"{base}.{node.module}" if node.module else base
    else:
        target = node.module or ""
    if target.split(".")[0] != "wetclutch":
        return []
    assert target in MODULES, f"{importer}: import of {target}, not a module of the package"
    out = [target]
    out += [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in MODULES]
    return out


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            ids |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    return ids


def _edges():
    """(importer, imported, type_only) for every import, with the packages an import runs on the way."""
    edges = set()
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        typing_only = _type_checking_nodes(tree)
        own = {name.rsplit(".", k)[0] for k in range(name.count(".") + 1)}   # the importer and its packages
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            for target in _resolve(name, node):
                if id(node) in typing_only:     # never runs: the name it annotates with
                    edges.add((name, target, True))
                    continue
                parts = target.split(".")
                for k in range(1, len(parts) + 1):
                    step = ".".join(parts[:k])
                    if step not in own:
                        edges.add((name, step, False))
    return edges


def _role(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_no_import_circle():
    sorter = graphlib.TopologicalSorter({m: set() for m in MODULES})
    for a, b, type_only in _edges():
        if not type_only:
            sorter.add(a, b)
    try:
        order = list(sorter.static_order())
    except graphlib.CycleError as e:
        pytest.fail(f"import circle: {' -> '.join(e.args[1])}")
    assert set(order) == set(MODULES)


def test_dependencies_run_one_way():
    layer = {role: k for k, roles in enumerate(LAYERS) for role in roles}
    roles = {_role(m) for m in MODULES} - {None}
    assert roles == set(layer), f"a role without a layer (or a layer without a folder): {roles ^ set(layer)}"
    wrong = []
    for a, b, type_only in sorted(_edges()):
        ra, rb = _role(a), _role(b)
        if rb is None or ra == rb:
            continue
        if type_only:
            if (ra, b) not in TYPE_ONLY_ALLOWED:
                wrong.append(f"{a} -> {b} (annotations)")
        elif not layer[rb] < layer[ra]:
            wrong.append(f"{a} ({ra}, layer {layer[ra]}) -> {b} ({rb}, layer {layer[rb]})")
    assert not wrong, "imports against the layers:\n" + "\n".join(wrong)


def test_every_module_imports_in_a_fresh_interpreter():
    """Each module imported first in its own role's order would expose a circle the source check missed."""
    code = ("import importlib, sys\n"
            "for name in sys.argv[1:]:\n"
            "    importlib.import_module(name)\n")
    names = sorted(m for m in MODULES if not m.endswith("__main__"))
    r = subprocess.run([sys.executable, "-c", code, *names], capture_output=True, text=True,
                       cwd=ROOT / "tools")
    assert r.returncode == 0, r.stderr


def test_no_python_file_over_600_lines():
    long = [f"{p.relative_to(ROOT)}: {n}" for p in sorted([*(ROOT / "tools").rglob("*.py"),
                                                           *(ROOT / "tests").rglob("*.py")])
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES]
    assert not long, f"over {MAX_LINES} lines: {long}"
