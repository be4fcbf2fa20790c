"""Helpers for testing a plugin on a tiny case, for sphcore's tests and third-party plugins.

    from sphcore.testing import TINY_CASE, run_case, context

    summary = run_case(tmp_path, TINY_CASE, plugins=["myplugin"], tables={"myplugin": {"k": 1}})
    assert summary["myplugin"]["figure"] == ...

``context`` builds a real :class:`sphcore.plugin.context.RunContext` of a case for calling one
hook directly (no run), so plugin unit tests need no stand-in objects.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from sphcore.case.model import validate
from sphcore.jit import prepare
from sphcore.physics.params import derive
from sphcore.plugin import pluginhost
from sphcore.plugin.context import RunContext
from sphcore.run import runner
from sphcore.run.build import build_state
from sphcore.run.state import RunState

#: a valid 2D case: a 10 x 10 block of water (dx = 0.02 m) resting on the floor of a 1 m box
TINY_CASE = """
[case]
dim = 2

[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]

[[blocks]]
min = [0.0, 0.0]
max = [0.2, 0.2]

[particles]
dx = 0.02

[time]
t_end = 0.002

[plugins]
use = []
"""


def _toml_value(v) -> str:
    return json.dumps(v) if isinstance(v, (str, bool, int, float, list)) else str(v)


def _emit(name: str, table: dict, lines: list) -> None:
    """Append ``table`` as TOML under the header ``name`` (nested tables and arrays of tables too)."""
    def is_tables(v):
        return isinstance(v, list) and v and all(isinstance(e, dict) for e in v)

    if name:
        lines.append(f"[{name}]")
    lines += [f"{k} = {_toml_value(v)}" for k, v in table.items() if not isinstance(v, dict) and not is_tables(v)]
    for k, v in table.items():
        sub = f"{name}.{k}" if name else k
        if isinstance(v, dict):
            _emit(sub, v, lines)
        elif is_tables(v):
            for entry in v:
                lines.append(f"[[{sub}]]")
                lines += [f"{kk} = {_toml_value(vv)}" for kk, vv in entry.items()]


def write_case(directory, text: str = TINY_CASE, plugins=None, tables=None) -> Path:
    """Write ``directory``/case.toml and return the directory: ``text`` (dedented) as it is,
    or, when ``plugins`` or ``tables`` ({table: {key: value}}) are given, ``text`` with
    ``[plugins] use`` replaced by ``plugins`` and the tables appended (rewritten from its
    parsed form, so comments are lost)."""
    text = textwrap.dedent(text)
    if plugins is not None or tables:
        raw = tomllib.loads(text)
        if plugins is not None:
            raw.setdefault("plugins", {})["use"] = list(plugins)
        for table, body in (tables or {}).items():
            raw.setdefault(table, {}).update(body)
        lines: list = []
        _emit("", raw, lines)
        text = "\n".join(lines) + "\n"
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "case.toml").write_text(text)
    return directory


def run_case(directory, text: str = TINY_CASE, plugins=None, tables=None, **run_args) -> dict:
    """Write the case (see :func:`write_case`) and run it quietly; output in
    ``directory``/output. Returns the summary (plugin figures under the plugin's name)."""
    case_dir = write_case(directory, text, plugins, tables)
    run_args.setdefault("output", Path(directory) / "output")
    return runner.run(case_dir, quiet=True, **run_args).summary


def context(text: str = TINY_CASE, file="case.toml", output_dir=None, plugins=None):
    """A RunContext of the case in ``text`` with its initial particles (no run, no plugin
    set-up): for calling a plugin's hooks directly in a test."""
    prepare()
    raw = tomllib.loads(textwrap.dedent(text))
    if plugins is not None:
        raw.setdefault("plugins", {})["use"] = list(plugins)
    case = validate(raw, Path(file), pluginhost.option_schemas(file, raw))
    state = build_state(case)
    return RunContext(case, derive(case, state), RunState(state, case.config["time"]["t_end"]), output_dir=output_dir)
