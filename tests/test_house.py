"""The shape of the code: layers that import only downwards, no import circle, no private
attribute of another object read or written, a small top level. Read from the sources'
syntax (nothing is imported), so a violation names the file and line."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SPHCORE = ROOT / "sphcore"

#: sphcore's subpackages from the bottom up: a module may import its own package and those
#: listed before it, never one after it. The top-level modules (api, cli, testing) may
#: import anything; errors imports nothing of sphcore.
LAYERS = ["errors", "jit", "geometry", "neighbours", "physics", "case", "plugin", "io", "run", "sweep"]
TOP = {"api", "cli", "testing", "__init__"}


def _modules(root: Path):
    for path in sorted(root.rglob("*.py")):
        if "__pycache__" not in path.parts:
            yield path, ast.parse(path.read_text(), filename=str(path))


def _layer(path: Path) -> str:
    rel = path.relative_to(SPHCORE).parts
    return rel[0] if len(rel) > 1 else Path(rel[0]).stem


def _sphcore_imports(tree: ast.AST):
    """(line, imported module's dotted name under sphcore) of every import in ``tree``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            parts = node.module.split(".")
            if parts[0] == "sphcore":
                if len(parts) == 1:  # from sphcore import x
                    for alias in node.names:
                        yield node.lineno, alias.name
                else:
                    yield node.lineno, ".".join(parts[1:])
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("sphcore."):
                    yield node.lineno, alias.name[len("sphcore."):]


def test_sphcore_imports_only_its_own_layer_and_those_below():
    bad = []
    for path, tree in _modules(SPHCORE):
        mine = _layer(path)
        if mine in TOP:
            continue
        for line, target in _sphcore_imports(tree):
            theirs = target.split(".")[0]
            if theirs == "__version__" or theirs == mine:
                continue
            if theirs in TOP or LAYERS.index(theirs) > LAYERS.index(mine):
                bad.append(f"{path.relative_to(ROOT)}:{line}: {mine} imports sphcore.{target}")
    assert not bad, "imports of a higher layer:\n" + "\n".join(bad)


def test_no_import_circle_between_modules():
    """Module-level imports only (an import inside a function runs when it is called)."""
    graph: dict[str, set[str]] = {}
    for path, tree in _modules(SPHCORE):
        name = ".".join(path.relative_to(SPHCORE).with_suffix("").parts)
        name = name[: -len(".__init__")] if name.endswith(".__init__") else name
        deps = graph.setdefault(name, set())
        for node in tree.body:
            for line, target in _sphcore_imports(node) if isinstance(node, (ast.Import, ast.ImportFrom)) else ():
                deps.add(target)
    known = set(graph)

    def resolve(target):  # "run.budget" or "run" (a package) or "physics.eos.x" (a name in a module)
        while target and target not in known:
            target = target.rpartition(".")[0]
        return target or None

    edges = {m: {r for t in deps if (r := resolve(t)) and r != m} for m, deps in graph.items()}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for n in edges[m]:
            if state.get(n) == 1:
                raise AssertionError("import circle: " + " -> ".join(stack[stack.index(n):] + [n]))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m)


#: a named tuple's public methods and fields carry an underscore so as not to clash with its fields
NAMEDTUPLE_API = {"_fields", "_replace", "_asdict", "_make", "_field_defaults"}


#: standard-library functions whose documented names begin with an underscore
PUBLIC_UNDERSCORED = {("os", "_exit")}


def _private_uses(tree: ast.AST):
    """(line, text) of every ``x._name`` whose ``x`` is not ``self`` or ``cls`` (dunders are
    not private), and of every private name imported from another module."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
            base = node.value
            if isinstance(base, ast.Name) and base.id in ("self", "cls"):
                continue
            if node.attr in NAMEDTUPLE_API:
                continue
            if isinstance(base, ast.Name) and (base.id, node.attr) in PUBLIC_UNDERSCORED:
                continue
            yield node.lineno, ast.unparse(node)
        elif isinstance(node, ast.ImportFrom) and node.module != "__future__":
            for alias in node.names:
                if alias.name.startswith("_") and not alias.name.startswith("__"):
                    yield node.lineno, f"from {'.' * node.level}{node.module or ''} import {alias.name}"


@pytest.mark.parametrize("folder", ["sphcore", "plugins"])
def test_no_private_attribute_of_another_object_is_used(folder):
    bad = [f"{path.relative_to(ROOT)}:{line}: {text}"
           for path, tree in _modules(ROOT / folder) for line, text in _private_uses(tree)]
    assert not bad, "private attributes used from outside their object:\n" + "\n".join(bad)


def test_the_top_level_of_sphcore_is_small():
    entries = sorted(p.name for p in SPHCORE.iterdir() if p.name != "__pycache__")
    assert len(entries) <= 15, entries
    assert {p.stem for p in SPHCORE.glob("*.py")} == TOP | {"errors"}


#: what takes the particles out of a run: it reads them through RunState.host / RunContext.host
#: (sphcore.run.state), never the run's own arrays, so that those arrays may live elsewhere
LEAVES_THE_RUN = ["plugins/vtu.py", "plugins/netcdf.py", "sphcore/run/checkpoint.py"]


@pytest.mark.parametrize("file", LEAVES_THE_RUN)
def test_what_writes_particles_out_reads_host_arrays(file):
    tree = ast.parse((ROOT / file).read_text())
    bad = [f"{file}:{node.lineno}: {ast.unparse(node)}" for node in ast.walk(tree)
           if isinstance(node, ast.Attribute) and node.attr in ("state", "particles")]
    assert not bad, "particles read without host():\n" + "\n".join(bad)
