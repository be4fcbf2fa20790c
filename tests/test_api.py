"""The plugin API as a contract: documented hooks and context, one public module, no cycles,
one override grammar."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest

from sphcore import api, cli
from sphcore.plugin import context, hookspecs
from sphcore.testing import TINY_CASE, write_case
from sphcore.testing import context as make_context

ROOT = Path(__file__).resolve().parents[1]


def hook_names():
    return [n for n, f in vars(hookspecs).items() if n.startswith("sph_") and callable(f)]


@pytest.mark.parametrize("name", hook_names())
def test_every_hook_is_documented(name):
    doc = inspect.getdoc(getattr(hookspecs, name)) or ""
    assert "Fires" in doc, f"{name}: say when it fires"


def test_every_context_attribute_is_documented():
    ctx = make_context(TINY_CASE)
    public = {a for a in dir(ctx) if not a.startswith("_") and a not in ("all_stats",)}
    doc = context.__doc__
    missing = [a for a in sorted(public) if f"``ctx.{a}" not in doc]
    assert not missing, f"undocumented RunContext attributes: {missing}"


def test_public_module_exports_resolve():
    for name in api.__all__:
        assert getattr(api, name) is not None, name


def test_builtin_plugins_import_only_the_public_module():
    for path in (ROOT / "plugins").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "sphcore":
                assert node.module == "sphcore.api", f"{path.relative_to(ROOT)} imports {node.module}"
            if isinstance(node, ast.Import):
                for alias in node.names:
                    assert alias.name.split(".")[0] != "sphcore" or alias.name == "sphcore", \
                        f"{path.relative_to(ROOT)} imports {alias.name}"


def _module_imports(path: Path, package: str) -> set[str]:
    """Modules of ``package`` imported at module level (imports inside functions are lazy)."""
    out = set()
    tree = ast.parse(path.read_text())
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                mod = f"{base}.{node.module}" if node.module else base
                if node.module is None:
                    out |= {f"{base}.{a.name}" for a in node.names}
                else:
                    out.add(mod)
            elif node.module and node.module.startswith("sphcore"):
                out.add(node.module)
    return out


def test_core_has_no_import_cycle_and_imports_no_plugin():
    graph = {}
    for path in (ROOT / "sphcore").rglob("*.py"):
        rel = path.relative_to(ROOT).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        name = ".".join(parts)
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        deps = _module_imports(path, package)
        assert not any(d.startswith("sphcore_plugins") for d in deps), name
        graph[name] = {d for d in deps if d != name}
    state = {}

    def visit(node, trail):
        if state.get(node) == "done" or node not in graph:
            return
        assert state.get(node) != "open", f"import cycle: {' -> '.join(trail + [node])}"
        state[node] = "open"
        for dep in graph[node]:
            if dep != "sphcore" and not node.startswith(dep + "."):  # a package's own __init__
                visit(dep, trail + [node])
        state[node] = "done"

    for node in graph:
        visit(node, [])


def test_no_module_is_past_four_hundred_lines():
    for path in list((ROOT / "sphcore").rglob("*.py")) + list((ROOT / "plugins").rglob("*.py")):
        assert len(path.read_text().splitlines()) <= 400, path


def test_indexed_override_in_run_and_check(tmp_path, capsys):
    """``--set blocks[0].max=...`` (an indexed key) works in sph check and sph run as in sph sweep."""
    case_dir = write_case(tmp_path / "c", TINY_CASE)
    assert cli.main(["check", str(case_dir), "--set", "blocks[0].max=[0.08,0.06]"]) == 0
    assert "12 particles" in capsys.readouterr().out
    assert cli.main(["run", str(case_dir), "--set", "blocks[0].max=[0.08,0.06]", "--set", 'plugins.use=["reflective"]',
                     "--progress", "off"]) == 0
    assert cli.main(["check", str(case_dir), "--set", "blocks[3].max=[0.08,0.06]"]) == 2
    err = capsys.readouterr().err
    assert "blocks[3].max" in err and "out of range" in err


def test_options_of_a_plugin_without_options_says_so(capsys, monkeypatch):
    """`sph options counter` (an installed plugin with no table: every built-in one now has
    options, so a stand-in is installed here) answers, exit 0; an unknown name is refused
    with exit 2 and the known names, plugins without options included."""
    from sphcore.plugin import pluginhost

    class Counter:
        @api.hookimpl
        def sph_after_step(self, ctx):
            pass

    plugins = dict(pluginhost.available())
    plugins["counter"] = pluginhost.PluginInfo("counter", "tests:Counter", "tests", "0", Counter, "", {})
    monkeypatch.setattr(pluginhost, "available", lambda: plugins)
    assert cli.main(["options", "counter"]) == 0
    assert "no options" in capsys.readouterr().out
    assert cli.main(["options", "nothere"]) == 2
    assert "counter" in capsys.readouterr().err
