"""A sweep's results: one xarray Dataset, the grid view, a printed table, the Pareto plot.

The Dataset has one dimension, ``variant`` (the variant's directory name is its
coordinate); each varied key is a coordinate along it (numbers as numbers, anything else
as its TOML text); every numeric summary key is a data variable (NaN where a variant did
not report it; the ``counters`` table becomes ``counters.<name>``); ``status`` and
``message`` are strings. :func:`grid` reshapes it to one dimension per ``--vary``.
"""

from __future__ import annotations

import json
import math
from numbers import Number

import numpy as np

STATUS_KEYS = ("status", "message")


def _flatten(summary: dict) -> dict:
    out = {}
    for k, v in summary.items():
        if isinstance(v, dict):
            out.update({f"{k}.{kk}": vv for kk, vv in v.items()})
        else:
            out[k] = v
    return out


def _numeric(v) -> bool:
    return isinstance(v, Number) and not isinstance(v, complex)


def _coord(values: list, texts: list):
    """Numbers stay numbers (bools too); anything else becomes its text as written."""
    if all(_numeric(v) for v in values):
        kinds = {type(v) for v in values}
        return np.array(values, dtype=bool if kinds == {bool} else (np.int64 if kinds <= {int, bool} else float))
    if all(isinstance(v, str) for v in values):
        return np.array(values, dtype=object)
    return np.array(texts, dtype=object)


def to_dataset(variants, axes, summaries: list[dict], attrs: dict | None = None):
    """One Dataset for the sweep; ``summaries[i]`` belongs to ``variants[i]``."""
    import xarray as xr

    flat = [_flatten(s) for s in summaries]
    keys: list[str] = []
    for f in flat:
        keys += [k for k, v in f.items() if k not in keys and k not in STATUS_KEYS and _numeric(v)]
    data = {}
    for k in keys:
        col = [f.get(k) for f in flat]
        present = [v for v in col if _numeric(v)]
        if len(present) == len(col) and all(isinstance(v, int) for v in present):
            arr = np.array(col, dtype=np.int64)  # bools and ints, all present
        else:
            arr = np.array([float(v) if _numeric(v) else math.nan for v in col])
        data[k] = ("variant", arr)
    for k in STATUS_KEYS:
        data[k] = ("variant", np.array([str(f.get(k, "")) for f in flat], dtype=object))
    coords = {"variant": np.array([v.name for v in variants], dtype=object)}
    for d, a in enumerate(axes):
        for m, key in enumerate(a.keys):
            values = [p[m] for p in a.points]
            texts = [json.dumps(v) if len(a.keys) > 1 else t for v, t in zip(values, a.texts)]
            per_point = _coord(values, texts)
            coords[key] = ("variant", per_point[[v.combo[d] for v in variants]])
    meta = dict(attrs or {})
    meta["sweep_axes"] = json.dumps([[a.keys, len(a)] for a in axes])
    return xr.Dataset(data, coords=coords, attrs=meta)


def grid(ds):
    """The sweep reshaped to one dimension per ``--vary`` (named after its first key; a
    linked key's partners are coordinates along it). Variants are stored in the order of
    the Cartesian product, so this is a reshape."""
    import xarray as xr

    axes = json.loads(ds.attrs["sweep_axes"])
    dims = [keys[0] for keys, _ in axes]
    shape = [n for _, n in axes]
    if not axes:
        return ds
    out = {}
    for name, var in ds.data_vars.items():
        out[name] = (dims, var.values.reshape(shape))
    coords = {"variant": (dims, ds["variant"].values.reshape(shape))}
    for d, (keys, n) in enumerate(axes):
        first = ds[keys[0]].values.reshape(shape)
        index = (0,) * d + (slice(None),) + (0,) * (len(axes) - d - 1)
        coords[keys[0]] = first[index]
        for k in keys[1:]:
            coords[k] = (keys[0], ds[k].values.reshape(shape)[index])
    return xr.Dataset(out, coords=coords, attrs=ds.attrs)


# -- reading the results -----------------------------------------------------------------

def is_error_key(key: str) -> bool:
    """A plugin figure named ``err*``, ``rms*`` or ``*_err`` (``front_gauge.err_cruchaga_0.20s``,
    ``pressure_gauge.pressure_max_layer_err``) is an error against a reference: the naming
    convention the sweep relies on to pick a default error."""
    last = key.rsplit(".", 1)[-1]
    return last.startswith(("err", "rms")) or last.endswith("_err")


def default_error_key(ds) -> str | None:
    """The first error figure (:func:`is_error_key`), in the Dataset's order, that some
    variant reported as a finite number."""
    for k in ds.data_vars:
        if is_error_key(k) and ds[k].dtype.kind in "fiu" and np.isfinite(ds[k].values.astype(float)).any():
            return k
    return None


def pareto_mask(cost, err) -> np.ndarray:
    """True for the points no other point beats on both cost and error (NaN never counts)."""
    cost, err = np.asarray(cost, float), np.asarray(err, float)
    ok = np.isfinite(cost) & np.isfinite(err)
    mask = np.zeros(cost.shape, bool)
    for i in np.nonzero(ok)[0]:
        others = ok & (cost <= cost[i]) & (err <= err[i]) & ((cost < cost[i]) | (err < err[i]))
        mask[i] = not others.any()
    return mask


def _short(v) -> str:
    return f"{v:.4g}" if isinstance(v, (float, np.floating)) else str(v)


def _label(ds, i) -> str:
    keys = [k for keys, _ in json.loads(ds.attrs["sweep_axes"]) for k in keys]
    return ", ".join(f"{k.split('.')[-1]}={_short(ds[k].values[i])}" for k in keys) or str(ds["variant"].values[i])


def table(ds, error_key: str | None = None) -> str:
    """A plain-text table: one row per variant, then the reasons of the runs that did not complete."""
    keys = [k for keys, _ in json.loads(ds.attrs["sweep_axes"]) for k in keys]
    cols = ["#"] + keys + ["status", "t s", "steps", "particles", "wall s", "particle-steps/s"]
    cols += [f"|{error_key}|"] if error_key else []

    def num(k, i, fmt):
        v = float(ds[k].values[i]) if k in ds else math.nan
        return format(v, fmt) if math.isfinite(v) else "-"

    rows = []
    for i in range(ds.sizes["variant"]):
        row = [str(i)] + [_short(ds[k].values[i]) for k in keys] + [str(ds["status"].values[i]),
               num("t", i, ".4g"), num("steps", i, ".0f"), num("n_particles", i, ".0f"), num("wall_time_s", i, ".1f"),
               num("particle_steps_per_s", i, ".3g")]
        if error_key:
            v = abs(float(ds[error_key].values[i])) if error_key in ds else math.nan
            row.append(format(v, ".4g") if math.isfinite(v) else "-")
        rows.append(row)
    width = [max(len(c), *(len(r[j]) for r in rows)) for j, c in enumerate(cols)]
    lines = ["  ".join(c.rjust(w) for c, w in zip(cols, width))]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, width)) for r in rows]
    for i in range(ds.sizes["variant"]):
        if ds["status"].values[i] != "completed":
            lines.append(f"{i} ({ds['variant'].values[i]}): {ds['status'].values[i]}: {ds['message'].values[i]}")
    return "\n".join(lines)


def plot_pareto(ds, error_key: str, path, cost_key: str = "wall_time_s") -> np.ndarray:
    """|error| against wall time, the Pareto front highlighted, written to ``path`` (PNG).
    Runs that did not complete are drawn grey (their figures cover part of the run only).
    Returns the Pareto mask (over completed runs)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cost = ds[cost_key].values.astype(float)
    err = np.abs(ds[error_key].values.astype(float))
    done = ds["status"].values == "completed"
    front = pareto_mask(np.where(done, cost, np.nan), np.where(done, err, np.nan))
    fig, ax = plt.subplots(figsize=(7, 5))
    ok = done & np.isfinite(cost) & np.isfinite(err)
    ax.scatter(cost[ok & ~front], err[ok & ~front], color="tab:blue", label="completed")
    bad = ~done & np.isfinite(cost) & np.isfinite(err)
    if bad.any():
        ax.scatter(cost[bad], err[bad], color="grey", marker="x", label="not completed (partial run)")
    order = np.argsort(cost[front])
    ax.plot(cost[front][order], err[front][order], "o-", color="tab:red", label="Pareto front")
    for i in np.nonzero(ok | bad)[0]:
        ax.annotate(_label(ds, i), (cost[i], err[i]), fontsize=7, xytext=(4, 3), textcoords="offset points")
    for axis, v in (("x", cost[ok | bad]), ("y", err[ok | bad])):
        pos = v[v > 0]
        if pos.size > 1 and pos.max() / pos.min() > 20:
            getattr(ax, f"set_{axis}scale")("log")
    ax.set_xlabel(f"{cost_key} (s)")
    ax.set_ylabel(f"|{error_key}|")
    ax.set_title(f"{ds.attrs.get('case', '')}: accuracy against cost, {int(ok.sum())} of {ds.sizes['variant']} "
                 "runs completed", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return front
