"""``--set`` overrides: one grammar for ``sph run``, ``sph check`` and ``sph sweep``.

``KEY=VALUE``: KEY is ``section.key`` or reaches into an array of tables by index
(``blocks[0].count``, ``domain.planes[1].normal``); VALUE is read as TOML, or as a bare
string when it is not valid TOML (``--set kernel.name=cubic_spline``). Nothing is executed.
"""

from __future__ import annotations

import copy
import re

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from sphcore.errors import CaseError

_SEGMENT = re.compile(r"^([A-Za-z0-9_-]+)((?:\[\d+\])*)$")


def parse_key(text: str, option: str = "--vary") -> tuple:
    """``"blocks[0].count"`` -> ``("blocks", 0, "count")``; at least section and key."""
    path = []
    for seg in text.strip().split("."):
        m = _SEGMENT.match(seg)
        if not m:
            raise CaseError(option, text, "expected section.key or table[index].key (e.g. time.cfl, blocks[0].count)")
        path.append(m.group(1))
        path += [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
    if len(path) < 2:
        raise CaseError(option, text, "expected section.key (e.g. time.cfl)")
    return tuple(path)


def key_text(path) -> str:
    """The inverse of :func:`parse_key`."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


#: deepest nesting of arrays and tables in a value (as in a case file, sphcore.case.model)
MAX_DEPTH = 32


def parse_value(raw: str, key: str = "", option: str = "--set"):
    """A value as ``--set`` reads it: TOML, or a bare string (one parser for all). A value
    nested deeper than MAX_DEPTH is a CaseError naming ``option`` and ``key``."""
    depth = deepest = 0
    for c in raw:
        depth += (c in "[{") - (c in "]}")
        deepest = max(deepest, depth)
    if deepest > MAX_DEPTH:
        raise CaseError(option, key or raw[:40], f"a value nested {deepest} deep: expected arrays and tables "
                        f"nested at most {MAX_DEPTH} deep")
    try:
        return tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        return raw  # a bare word, e.g. --set kernel.name=cubic_spline
    except RecursionError:
        raise CaseError(option, key or raw[:40], f"a value nested too deep to read: expected arrays and tables "
                        f"nested at most {MAX_DEPTH} deep") from None


def parse_set(text: str, option: str = "--set") -> tuple:
    """``KEY=VALUE`` -> (path, value); KEY may hold indices."""
    if "=" not in text:
        raise CaseError(option, text, "expected section.key=value")
    key, raw = text.split("=", 1)
    return parse_key(key, option), parse_value(raw, key.strip(), option)


def fold(raw: dict, overrides, file="--set") -> list:
    """``(path, value)`` pairs that :func:`sphcore.case.model.apply_overrides` takes: an override
    that reaches into an array of tables (``blocks[0].count``) becomes one that replaces
    the whole array (``blocks``) with a copy carrying the change. ``raw`` is the case's
    TOML as read; overrides apply in order, as ``apply_overrides`` would."""
    work, out = copy.deepcopy(raw), []
    for path, value in overrides:
        path = tuple(path)
        node = work
        for depth, part in enumerate(path[:-1]):
            node = _child(node, part, path, depth, file)
        last = path[-1]
        if isinstance(last, int):
            _check_index(node, last, path, len(path) - 1, file)
        elif not isinstance(node, dict):
            raise CaseError(file, key_text(path), f"{key_text(path[:-1])} is not a table")
        node[last] = copy.deepcopy(value)
        first = next((d for d, p in enumerate(path) if isinstance(p, int)), None)
        if first is None:
            out.append((list(path), value))
        else:
            head = path[:first]
            array = work
            for part in head:
                array = array[part]
            out.append((list(head), copy.deepcopy(array)))
    return out


def _check_index(node, i, path, depth, file):
    where = key_text(path[:depth])
    if not isinstance(node, list):
        raise CaseError(file, key_text(path), f"{where} is not an array of tables in the case")
    if i >= len(node):
        raise CaseError(file, key_text(path), f"index {i} out of range: the case has {len(node)} {where} entries")


def _child(node, part, path, depth, file):
    if isinstance(part, int):
        _check_index(node, part, path, depth, file)
        return node[part]
    if not isinstance(node, dict):
        raise CaseError(file, key_text(path), f"{key_text(path[:depth])} is not a table")
    if part not in node and depth + 1 < len(path) and isinstance(path[depth + 1], int):
        raise CaseError(file, key_text(path), f"the case has no {key_text(path[:depth + 1])} array to index")
    return node.setdefault(part, {})
