"""Helpers for testing a plugin on a tiny case, for sphcore's tests and third-party plugins.

    from sphcore.testing import case_with, context, run_case, tiny_case

    case = case_with(tiny_case(), {"time.t_end": 0.01, "myplugin.k": 1})
    summary = run_case(tmp_path, case, plugins=["myplugin"])
    assert summary["myplugin"]["figure"] == ...

A case is given as data, a nested dict laid out as ``case.toml`` is (:func:`tiny_case`, a
variant made with :func:`case_with`), or as the TOML text of ``case.toml`` (:data:`TINY_CASE`).
``context`` builds a real :class:`sphcore.plugin.context.RunContext` of a case for calling one
hook directly (no run), so plugin unit tests need no stand-in objects.
"""

from __future__ import annotations

import copy
import datetime
import math
import re
import textwrap
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from sphcore.case.model import validate
from sphcore.case.overrides import fold, parse_key
from sphcore.jit import prepare
from sphcore.physics.params import derive
from sphcore.plugin import pluginhost
from sphcore.plugin.context import RunContext
from sphcore.run import runner
from sphcore.run.build import build_state
from sphcore.run.state import RunState

#: a valid 2D case: a 10 x 10 block of water (dx = 0.02 m) resting on the floor of a 1 m box
#: (the same case as :func:`tiny_case`, as the text of a case.toml)
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


def tiny_case() -> dict:
    """The case of :data:`TINY_CASE` as data: a new dict on every call, free to change."""
    return {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [1.0, 1.0]},
        "blocks": [{"min": [0.0, 0.0], "max": [0.2, 0.2]}],
        "particles": {"dx": 0.02},
        "time": {"t_end": 0.002},
        "plugins": {"use": []},
    }


_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def case_with(base: dict | str, changes: dict) -> dict:
    """A copy of the case ``base`` (a dict, or TOML text) with ``changes`` made; ``base``
    itself is left as it is.

    Each key of ``changes`` names what to set, as ``sph run --set`` does: ``"time.t_end"``,
    ``"blocks[0].count"``, ``"domain.planes[1].normal"``, or a top-level name (``"blocks"``,
    ``"probes"``) to set a whole table or array of tables. A value replaces what was there
    (a dict replaces the whole table: set ``"fluid.nu"`` to change one key of it); a
    missing table on the way is created; the value ``None`` removes the key (or the array
    entry). Changes are made in order::

        case_with(tiny_case(), {"time.t_end": 0.01, "plugins.use": ["reflective"],
                                "blocks[0].max": [0.2, 0.4], "fluid": {"nu": 1e-6}})
    """
    raw = _raw(base)
    pairs = [(_key_path(key), value) for key, value in changes.items()]
    for path, value in fold(raw, pairs, "case_with"):  # an indexed key: the whole array, changed
        node = raw
        for part in path[:-1]:
            node = node.setdefault(part, {})
        node[path[-1]] = copy.deepcopy(value)
    return _without_none(raw)


def _key_path(key: str) -> tuple:
    return (key,) if _BARE.match(key) else parse_key(key, "case_with")


def _without_none(value):
    if isinstance(value, dict):
        return {k: _without_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_without_none(v) for v in value if v is not None]
    return value


def case_toml(case: dict) -> str:
    """The TOML text of the case ``case`` (a nested dict): what :func:`write_case` writes.
    ``tomllib.loads(case_toml(case)) == case`` for any case of TOML's value types (tables,
    arrays of tables, strings, integers, floats, booleans, dates and times)."""
    lines: list = []
    _emit((), case, lines)
    return "\n".join(lines) + "\n"


def _toml_key(key) -> str:
    if not isinstance(key, str):
        raise TypeError(f"a TOML key is a string, not {key!r}")
    return key if _BARE.match(key) else _toml_string(key)


_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def _toml_string(s: str) -> str:
    out = (_ESCAPES.get(c) or (f"\\u{ord(c):04X}" if ord(c) < 0x20 or ord(c) == 0x7F else c) for c in s)
    return '"' + "".join(out) + '"'


def _toml_value(v, where: str = "") -> str:
    """``v`` as a TOML value (an inline table for a dict)."""
    if hasattr(v, "tolist") and not isinstance(v, (str, bytes)):  # numpy scalars and arrays
        v = v.tolist()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, str):
        return _toml_string(v)
    if isinstance(v, (datetime.datetime, datetime.date, datetime.time)):
        return v.isoformat()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x, f"{where}[{i}]") for i, x in enumerate(v)) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(x, f'{where}.{k}')}" for k, x in v.items()) + "}"
    raise TypeError(f"{where or 'the case'}: {v!r} has no TOML form")


def _is_tables(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(e, dict) for e in v)


def _emit(path: tuple, table: dict, lines: list, entry: bool = False) -> None:
    """Append ``table`` as TOML under the header of ``path`` (``[[path]]`` for an entry of an
    array of tables): its values first, then its tables and arrays of tables, nested ones
    inside entries of arrays of tables too."""
    if path:
        header = ".".join(_toml_key(p) for p in path)
        lines += ([""] if lines else []) + [f"[[{header}]]" if entry else f"[{header}]"]
    where = ".".join(path)
    for k, v in table.items():
        if not isinstance(v, dict) and not _is_tables(v):
            lines.append(f"{_toml_key(k)} = {_toml_value(v, f'{where}.{k}' if where else k)}")
    for k, v in table.items():
        if isinstance(v, dict):
            _emit(path + (k,), v, lines)
        elif _is_tables(v):
            for item in v:
                _emit(path + (k,), item, lines, entry=True)


def _raw(case, plugins=None, tables=None) -> dict:
    """The case (a dict, or TOML text, dedented) as a new dict, with ``plugins`` and ``tables``."""
    raw = tomllib.loads(textwrap.dedent(case)) if isinstance(case, str) else copy.deepcopy(case)
    if plugins is not None:
        raw.setdefault("plugins", {})["use"] = list(plugins)
    for table, body in (tables or {}).items():
        raw.setdefault(table, {}).update(copy.deepcopy(body))
    return raw


def write_case(directory, case: dict | str = TINY_CASE, plugins=None, tables=None, *, text=None) -> Path:
    """Write ``directory``/case.toml (the directory made if need be) and return the directory.

    ``case`` is a dict (written as :func:`case_toml` writes it) or the TOML text of the file
    (written as it is, dedented). ``plugins`` replaces ``[plugins] use``; ``tables``
    ({table: {key: value}}) adds to or replaces keys of those tables (a text given with
    either is rewritten from its parsed form: its comments are lost). ``text=`` is the
    older name of ``case``."""
    case = case if text is None else text
    if isinstance(case, str) and plugins is None and not tables:
        text = textwrap.dedent(case)
    else:
        text = case_toml(_raw(case, plugins, tables))
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "case.toml").write_text(text)
    return directory


def run_case(directory, case: dict | str = TINY_CASE, plugins=None, tables=None, *, text=None, **run_args) -> dict:
    """Write the case (a dict or TOML text, see :func:`write_case`) and run it quietly;
    output in ``directory``/output unless ``output=`` says otherwise (other keywords go
    to :func:`sphcore.run.runner.run`). Returns the summary (plugin figures under the
    plugin's name; ``text=`` is the older name of ``case``)."""
    case_dir = write_case(directory, case if text is None else text, plugins, tables)
    run_args.setdefault("output", Path(directory) / "output")
    return runner.run(case_dir, quiet=True, **run_args).summary


def context(case: dict | str = TINY_CASE, file="case.toml", output_dir=None, plugins=None, *, text=None):
    """A RunContext of the case (a dict or TOML text) with its initial particles (no run,
    no plugin set-up): for calling a plugin's hooks directly in a test. ``plugins``
    replaces ``[plugins] use``; ``file`` is the name errors give the case (``text=`` is the
    older name of ``case``)."""
    prepare()
    raw = _raw(case if text is None else text, plugins)
    config = validate(raw, Path(file), pluginhost.option_schemas(file, raw))
    state = build_state(config)
    return RunContext(config, derive(config, state), RunState(state, config.config["time"]["t_end"]),
                      output_dir=output_dir)
