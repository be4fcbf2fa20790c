"""Sweep specifications: ``--vary`` value lists, indexed keys and the grid of variants.

Syntax (see docs/howto/sweeps.md):

- ``--vary KEY=V1,V2,...``: the values are split on the commas that lie outside brackets,
  braces and quoted strings, so an item may be a TOML array or inline table
  (``plugins.use=["ghost"],["reflective","ghost"]``). Each item is read exactly like a
  ``--set`` value: as TOML, or as a bare string when it is not valid TOML
  (``kernel.name=cubic_spline,wendland_c2``).
- ``--vary K1,K2=[a1,a2],[b1,b2]``: linked keys. The keys change together; each item is a
  TOML array holding one value per key (the resolution and the time to reach, say).
- ``KEY`` is ``section.key``, or reaches into an array of tables by index:
  ``blocks[0].count``, ``domain.planes[1].normal``.

Several ``--vary`` options make the Cartesian product, the first one slowest.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass, field

from sphcore.case.overrides import fold, key_text, parse_key, parse_set, parse_value  # noqa: F401 (re-exported for the sweep)
from sphcore.errors import CaseError

_OPEN, _CLOSE = "[{", "]}"


# -- values --------------------------------------------------------------------------

def split_values(text: str, key: str = "") -> list[str]:
    """Split on commas at bracket/brace depth 0 and outside quoted strings."""
    items, depth, quote, cur, i = [], 0, None, [], 0
    while i < len(text):
        c = text[i]
        cur.append(c)
        if quote:
            if c == "\\" and quote == '"' and i + 1 < len(text):  # escape in a TOML basic string
                cur.append(text[i + 1])
                i += 1
            elif c == quote:
                quote = None
        elif c in "\"'":
            quote = c
        elif c in _OPEN:
            depth += 1
        elif c in _CLOSE:
            depth -= 1
            if depth < 0:
                raise CaseError("--vary", key, f"unbalanced '{c}' in {text!r}")
        elif c == "," and depth == 0:
            cur.pop()
            items.append("".join(cur).strip())
            cur = []
        i += 1
    if quote or depth:
        raise CaseError("--vary", key, f"unclosed {'quote' if quote else 'bracket'} in {text!r}")
    items.append("".join(cur).strip())
    if not all(items):
        raise CaseError("--vary", key, f"an empty value in {text!r} (values are separated by single commas)")
    return items


# -- axes and variants -----------------------------------------------------------------

@dataclass(frozen=True)
class Axis:
    """One ``--vary``: its keys (several when linked) and, per point, one value per key."""

    paths: tuple  # of key paths
    points: tuple  # of tuples, one value per key
    texts: tuple  # the items as written, for names and labels

    @property
    def keys(self) -> list[str]:
        return [key_text(p) for p in self.paths]

    def __len__(self):
        return len(self.points)


@dataclass
class Variant:
    index: int
    name: str  # directory name: index, then label=value per varied key
    values: dict  # key text -> value
    overrides: list = field(default_factory=list)  # (path, value) pairs, --set ones first
    combo: tuple = ()  # the index of its point along each axis


def parse_vary(text: str) -> Axis:
    """One ``--vary`` option (see the module docstring)."""
    if "=" not in text:
        raise CaseError("--vary", text, "expected KEY=V1,V2,... (or K1,K2=[a1,a2],[b1,b2])")
    lhs, rhs = text.split("=", 1)
    keys = [k.strip() for k in lhs.split(",")]
    paths = tuple(parse_key(k) for k in keys)
    items = split_values(rhs, lhs.strip())
    values = [parse_value(item, lhs.strip(), "--vary") for item in items]
    if len(paths) == 1:
        points = tuple((v,) for v in values)
    else:
        for item, v in zip(items, values):
            if not isinstance(v, list) or len(v) != len(paths):
                raise CaseError("--vary", lhs.strip(), f"linked keys take one TOML array of {len(paths)} values "
                                f"per variant, got {item!r}")
        points = tuple(tuple(v) for v in values)
    return Axis(paths, points, tuple(items))


def _labels(axes) -> list[str]:
    """Short labels for names: the last key segment, the whole key where those collide."""
    paths = [p for a in axes for p in a.paths]
    short = [str(next(s for s in reversed(p) if isinstance(s, str))) for p in paths]
    return [s if short.count(s) == 1 else key_text(p) for s, p in zip(short, paths)]


def _clean(text: str) -> str:
    text = re.sub(r"[\s\"'\[\]{}]", "", text).replace(",", "-")
    return re.sub(r"[^A-Za-z0-9._=+-]", "_", text)[:40]


#: most variants one sweep runs (and validates before it starts: about 10 ms each)
MAX_VARIANTS = 1000


def expand(axes, sets=()) -> list[Variant]:
    """The Cartesian product of the axes, in order (the first axis slowest); refused above
    MAX_VARIANTS (CaseError naming the --vary keys)."""
    size = 1
    for a in axes:
        size *= len(a)
    if size > MAX_VARIANTS:
        raise CaseError("--vary", ", ".join(k for a in axes for k in a.keys), f"{' x '.join(str(len(a)) for a in axes)}"
                        f" = {size} variants, more than {MAX_VARIANTS} in one sweep: expected fewer values (split the "
                        "grid into several sweeps)")
    keys = [k for a in axes for k in a.keys]
    dup = {k for k in keys if keys.count(k) > 1}
    if dup:
        raise CaseError("--vary", sorted(dup)[0], "varied twice: give its values in one --vary")
    labels = _labels(axes)
    base = [parse_set(s) if isinstance(s, str) else s for s in sets]
    out = []
    for index, combo in enumerate(itertools.product(*(range(len(a)) for a in axes))):
        values, bits, overrides, li = {}, [], list(base), 0
        for a, j in zip(axes, combo):
            linked = len(a.paths) > 1
            for m, (path, v) in enumerate(zip(a.paths, a.points[j])):
                values[key_text(path)] = v
                overrides.append((path, v))
                text = _clean(repr(v) if linked else a.texts[j])
                bits.append(f"{labels[li]}={text}")
                li += 1
        name = "_".join([f"{index:03d}"] + bits) if bits else f"{index:03d}"
        out.append(Variant(index, name, values, overrides, combo))
    return out
