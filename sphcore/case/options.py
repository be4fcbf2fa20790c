"""Typed, documented case options and their validation.

Every case key is an :class:`Option`: a default, a kind, a unit and a one-line doc.
Core options live in :mod:`sphcore.case.defaults`; a plugin declares its own table through
the ``sph_options`` hook. Validation never executes anything from the case.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import Any

from sphcore.errors import CaseError

#: kinds of value an option accepts
KINDS = ("bool", "int", "float", "str", "vector", "list", "table_list", "str_list")


@dataclass(frozen=True)
class Option:
    default: Any
    kind: str  # one of KINDS
    unit: str = ""
    doc: str = ""
    min: float | None = None  # inclusive lower bound for int/float
    positive: bool = False  # strictly > 0 (int/float)
    choices: tuple = ()  # allowed strings
    nullable: bool = False  # the default None means "derived" (e.g. radius = dx/2)
    extra: dict = field(default_factory=dict)
    restart: bool = False  # may change on --restart: how the run reports, not what it computes

    def describe(self) -> str:
        bits = [self.doc]
        if self.unit:
            bits.append(f"[{self.unit}]")
        if self.choices:
            bits.append("one of " + ", ".join(map(str, self.choices)))
        return " ".join(bits)


def _expected(opt: Option) -> str:
    what = {
        "bool": "true or false",
        "int": "an integer",
        "float": "a number",
        "str": "a string",
        "vector": "a list of numbers",
        "list": "a list",
        "table_list": "a list of tables",
        "str_list": "a list of strings",
    }[opt.kind]
    if opt.positive:
        what = f"a positive {what.split(' ', 1)[1]}" if opt.kind in ("int", "float") else what
    if opt.choices:
        what = "one of " + ", ".join(repr(c) for c in opt.choices)
    return what


def check_value(opt: Option, value: Any, file: str, key: str) -> Any:
    """Return ``value`` converted to the option's kind, or raise :class:`CaseError`."""
    if value is None and opt.nullable:
        return None
    k = opt.kind
    bad = CaseError(file, key, f"expected {_expected(opt)}, got {value!r}")
    if k == "bool":
        if not isinstance(value, bool):
            raise bad
        return value
    if k in ("int", "float"):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad
        if k == "int" and not isinstance(value, int):
            raise bad
        # integers beyond int64 would overflow numpy arrays; a float overflows on float()
        if isinstance(value, int) and not -(2**63) < value < 2**63:
            raise CaseError(file, key, f"expected {_expected(opt)} within the 64-bit range, got {value:.3g}")
        value = int(value) if k == "int" else float(value)
        if not math.isfinite(value):
            raise bad
        # subnormal numbers (below 2.2e-308) lose precision and overflow when divided by
        if value != 0 and abs(value) < sys.float_info.min:
            raise CaseError(file, key, f"expected {_expected(opt)} of normal magnitude (0 or above "
                            f"{sys.float_info.min:.3g} in size), got {value!r}")
        if opt.positive and not value > 0:
            raise CaseError(file, key, f"expected a positive number, got {value!r}")
        if opt.min is not None and value < opt.min:
            raise CaseError(file, key, f"expected a number >= {opt.min}, got {value!r}")
        if "max" in opt.extra and value > opt.extra["max"]:
            raise CaseError(file, key, f"expected a number <= {opt.extra['max']}, got {value!r}")
        return value
    if k == "str":
        if not isinstance(value, str):
            raise bad
        if opt.choices and value not in opt.choices:
            raise bad
        return value
    if k == "vector":
        if not isinstance(value, list) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value
        ):
            raise bad
        return [float(v) for v in value]
    if k == "str_list":
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise bad
        return list(value)
    if k == "table_list":
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise bad
        return list(value)
    if k == "list":
        if not isinstance(value, list):
            raise bad
        return list(value)
    raise ValueError(f"unknown option kind {k!r}")  # a bug in a declaration, not user input


def validate_table(
    schema: dict[str, Option], table: dict, file: str, section: str
) -> dict[str, Any]:
    """Merge ``table`` over the schema's defaults; unknown keys and wrong types are errors."""
    if not isinstance(table, dict):
        raise CaseError(file, section, f"expected a table [{section}], got {table!r}")
    for key in table:
        if key not in schema:
            known = ", ".join(sorted(schema))
            raise CaseError(file, f"{section}.{key}", f"unknown key (known keys: {known})")
    out = {}
    for key, opt in schema.items():
        if key in table:
            out[key] = check_value(opt, table[key], file, f"{section}.{key}")
        else:
            out[key] = opt.default
    return out
