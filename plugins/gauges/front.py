"""The dam-break surge front: definition, comparison with experiment, and the
``front_gauge`` plugin that records it during a run.

Definition (robust to splashes): take the particles whose centre lies within ``band``
spacings of the floor (the two lowest layers by default); sort them by their distance from
the back wall; walk from the wall while consecutive centres are at most ``gap`` spacings
apart (2 by default). The last particle of that connected chain is the tip, and
x_front = its centre + its radius (the water's edge). A drop separated from the chain by
more than ``gap`` does not count.

Reference (``front_gauge.reference``): the experiments only apply to their own geometry.
"auto" looks at the first fluid block (column width a along x, height along -g): a column
of height 2a (aspect ratio 2 within ``ASPECT_TOL``) is Martin & Moyce's n^2 = 2 column, and
if moreover a = 0.114 m (within ``CRUCHAGA_TOL``) it is Cruchaga's; any other column is
compared with nothing (the summary says why). A reference named explicitly that does not
fit the column is a CaseError.

Wall height (``front_gauge.wall_height = true``): the residual column height eta(t) at the
back wall, defined as the water depth of the depth probe (:mod:`sphcore_plugins.probes.sampling`:
the first height above the floor where the kernel fluid fraction drops below 0.5) on the
vertical line one particle spacing dx from the back wall (x = the block's min x + dx, away
from the wall's kernel truncation); compared with Martin & Moyce's H = eta/(2a) against
tau = t sqrt(g/a).
"""

from __future__ import annotations

import math

import numpy as np

from sphcore.api import SUPPORT, CaseError, Option, hookimpl, write_atomically
from sphcore_plugins.probes.sampling import depth_above, select_near

from . import reference

G = 9.81
ASPECT_TOL = 0.02  # relative tolerance on height / width = 2 for Martin & Moyce n^2 = 2
CRUCHAGA_WIDTH = 0.114  # m, Cruchaga et al.'s column width
CRUCHAGA_TOL = 0.01  # relative tolerance on that width
REFERENCES = ("auto", "martin_moyce_n2", "cruchaga", "none")


def front_position(pos, radius, floor=0.0, band=2.0, gap=2.0, axis=0, up=1) -> float:
    """x (m) of the connected surge tip; see the module docstring."""
    dx = 2.0 * float(np.median(radius))
    near = pos[:, up] - floor < band * dx
    if not near.any():
        return float("nan")
    order = np.argsort(pos[near, axis])
    xs = pos[near, axis][order]
    rs = radius[near][order]
    breaks = np.nonzero(np.diff(xs) > gap * dx)[0]
    tip = breaks[0] if breaks.size else xs.size - 1
    return float(xs[tip] + rs[tip])


def column_of(case):
    """(width a along x, height along -g) in m of the case's first fluid block, or None."""
    cfg = case.config
    g = np.asarray(cfg["physics"]["gravity"][: case.dim], float)
    up = int(np.argmax(np.abs(g))) if np.any(g) else 1
    for b in cfg["blocks"]:
        if b.get("kind", "fluid") != "fluid":
            continue
        if b.get("count") is not None:
            ext = np.asarray(b["count"], float) * case.dx
        else:
            ext = np.asarray(b["max"][: case.dim], float) - np.asarray(b["min"][: case.dim], float)
        return float(ext[0]), float(ext[up])
    return None


def select_references(case, name):
    """(references to compare with, a note for the summary) for ``front_gauge.reference = name``."""
    col = column_of(case)
    width, height = col if col else (float("nan"), float("nan"))
    ratio = height / width if col else float("nan")
    is_mm = bool(col) and abs(ratio - 2.0) <= 2.0 * ASPECT_TOL
    is_cru = is_mm and abs(width - CRUCHAGA_WIDTH) <= CRUCHAGA_TOL * CRUCHAGA_WIDTH
    shape = f"the first fluid block is {width:.6g} m wide and {height:.6g} m high (ratio {ratio:.3g})"
    if name == "none":
        return (), "none (front_gauge.reference = none)"
    if name == "martin_moyce_n2" and not is_mm:
        raise CaseError(case.file, "front_gauge.reference", f"martin_moyce_n2 needs a column twice as high as "
                        f"wide (ratio 2 within {ASPECT_TOL:.0%}); {shape}: use auto or none")
    if name == "cruchaga" and not is_cru:
        raise CaseError(case.file, "front_gauge.reference", f"cruchaga needs the {CRUCHAGA_WIDTH} m x "
                        f"{2 * CRUCHAGA_WIDTH} m column; {shape}: use auto or none")
    if name != "auto":
        return (name,), name
    refs = (("martin_moyce_n2",) if is_mm else ()) + (("cruchaga",) if is_cru else ())
    if not refs:
        return (), (f"none: no reference applies ({shape}; Martin & Moyce n^2 = 2 needs ratio 2 "
                    f"within {ASPECT_TOL:.0%})")
    return refs, ", ".join(refs)


def compare_height(t, eta, a) -> dict:
    """RMS relative error of H = eta/(2a) against Martin & Moyce's residual height at their
    points tau = t sqrt(g/a) that the run covers."""
    t, eta = np.asarray(t, float), np.asarray(eta, float)
    mm = reference.martin_moyce_height()
    tau = t * math.sqrt(G / a)
    sel = mm[:, 0] <= (tau[-1] if t.size else -1)
    out = {"martin_moyce_height_points": int(sel.sum())}
    if sel.any():
        h_sim = np.interp(mm[sel, 0], tau, eta / (2 * a))
        out["rms_rel_err_martin_moyce_height"] = float(np.sqrt(np.mean(((h_sim - mm[sel, 1]) / mm[sel, 1]) ** 2)))
    else:
        out["rms_rel_err_martin_moyce_height"] = float("nan")
    return out


def compare(t, x, a=0.114, x_wall=math.inf, references=("cruchaga", "martin_moyce_n2")) -> dict:
    """Front errors against the experiments named in ``references``.

    Cruchaga: relative error at its times (interpolated in the series). Martin & Moyce:
    RMS relative error of Z = x/a over their points with T <= 3 that the run covers and
    that lie before the front meets the opposite wall at ``x_wall``.
    """
    t, x = np.asarray(t, float), np.asarray(x, float)
    out = {}
    for tc, xe, xs in (reference.cruchaga() if "cruchaga" in references else ()):
        xi = float(np.interp(tc, t, x)) if t.size and t[0] <= tc <= t[-1] else float("nan")
        out[f"x_front_{tc:.2f}s_m"] = xi
        out[f"err_cruchaga_{tc:.2f}s"] = (xi - xe) / xe
    if "martin_moyce_n2" not in references:
        return out
    mm = reference.martin_moyce()
    big_t = t * math.sqrt(2 * G / a)
    sel = (mm[:, 0] <= 3.0) & (mm[:, 0] <= (big_t[-1] if t.size else -1)) & (mm[:, 1] * a < x_wall)
    if sel.any():
        z_sim = np.interp(mm[sel, 0], big_t, x / a)
        out["rms_rel_err_martin_moyce_T3"] = float(np.sqrt(np.mean(((z_sim - mm[sel, 1]) / mm[sel, 1]) ** 2)))
    else:
        out["rms_rel_err_martin_moyce_T3"] = float("nan")
    out["martin_moyce_points"] = int(sel.sum())
    return out


class FrontGauge:
    """Records x_front(t) (and, with ``wall_height``, eta(t) at the back wall) on a schedule;
    the run summary gets the errors against the experiments that fit the column and
    ``front.csv`` is written to the output directory."""

    @hookimpl
    def sph_options(self):
        return {"front_gauge": {
            "every_dt": Option(0.005, "float", "s", "sampling interval of the front", positive=True),
            "band": Option(2.0, "float", doc="floor band height, in particle spacings", positive=True),
            "gap": Option(2.0, "float", doc="largest gap inside the connected front, in spacings", positive=True),
            "column_width": Option(None, "float", "m", "initial column width a for Martin & Moyce's scaling; "
                                   "the first fluid block's extent along x when unset", positive=True, nullable=True),
            "reference": Option("auto", "str", doc="experiment to compare with; auto: chosen from the first fluid "
                                "block's shape (height 2a: Martin & Moyce n^2 = 2; a = 0.114 m also Cruchaga)",
                                choices=REFERENCES),
            "wall_height": Option(False, "bool", doc="also record the residual column height at the back wall "
                                  "(depth-probe definition, one dx from the wall) against Martin & Moyce"),
        }}

    @hookimpl
    def sph_configure(self, case):
        self.cfg = case.config["front_gauge"]
        self.floor = float(case.config["domain"]["min"][1]) if case.config["domain"]["min"] else 0.0
        self.x_wall = float(case.config["domain"]["max"][0]) if case.config["domain"]["max"] else math.inf
        self.references, self.reference_note = select_references(case, self.cfg["reference"])
        col = column_of(case)
        self.a = self.cfg["column_width"] or (col[0] if col else None)
        self.next_t = 0.0

    @hookimpl
    def sph_setup(self, ctx):
        if self.a is None:  # measured on the initial particles, kept for a restart
            if "column_width" not in ctx.kept(self):
                x = ctx.state.pos[:, 0]
                ctx.kept(self)["column_width"] = float(x.max() - x.min() + 2 * ctx.state.radius.max())
            self.a = ctx.kept(self)["column_width"]
        # samples live in ctx.kept(self), which the checkpoint keeps: a restarted run continues
        # the series instead of starting a new one
        self.samples = ctx.kept(self).setdefault("samples", [])
        if self.cfg["wall_height"]:
            self._height_setup(ctx)
        if not self.samples:
            self._sample(ctx)
        self.next_t = (math.floor(ctx.t / self.cfg["every_dt"] + 1e-9) + 1) * self.cfg["every_dt"]

    def _height_setup(self, ctx):
        case, dim = ctx.case, ctx.case.dim
        self.heights = ctx.kept(self).setdefault("heights", [])
        g = np.asarray(ctx.params.gravity, float)[:dim]
        self.up = -g / np.linalg.norm(g)
        blocks = [b for b in case.config["blocks"] if b.get("kind", "fluid") == "fluid"]
        lo = np.asarray(blocks[0]["min"][:dim], float)
        x0 = lo.copy()
        if blocks[0].get("max") is not None:  # the line runs through the block's middle across the tank (3D)
            x0 = 0.5 * (lo + np.asarray(blocks[0]["max"][:dim], float))
        x0[0] = lo[0] + case.dx
        x0[1] = self.floor
        self.height_point = x0
        self.normals = np.ascontiguousarray(case.planes.normals, dtype=float)
        self.offsets = np.ascontiguousarray(case.planes.offsets, dtype=float)
        top = x0 + 1e3 * self.up  # far enough: select_near keeps what is near the line
        self.seg_a, self.seg_b = np.ascontiguousarray(x0[None, :]), np.ascontiguousarray(top[None, :])
        self.h, self.kernel_id, self.dx = float(ctx.params.h), int(ctx.params.kernel_id), case.dx

    def wall_height(self, state) -> float:
        """eta (m): the depth-probe water depth one dx from the back wall."""
        idx = np.empty(state.pos.shape[0], np.int64)
        c = select_near(np.ascontiguousarray(state.pos), state.kind, self.seg_a, self.seg_b, SUPPORT * self.h, idx)
        near = idx[:c]
        return float(depth_above(self.height_point, self.up, 0.25 * self.dx, state.pos[near], state.rho[near],
                                 state.m[near], self.kernel_id, self.h, self.normals, self.offsets))

    def _sample(self, ctx):
        st = ctx.state
        self.samples.append((ctx.t, front_position(st.pos, st.radius, self.floor, self.cfg["band"], self.cfg["gap"])))
        if self.cfg["wall_height"]:
            self.heights.append((ctx.t, self.wall_height(st)))

    @hookimpl
    def sph_after_step(self, ctx):
        if ctx.t >= self.next_t - 1e-12:
            self._sample(ctx)
            self.next_t = (math.floor(ctx.t / self.cfg["every_dt"] + 1e-9) + 1) * self.cfg["every_dt"]

    @hookimpl
    def sph_summary(self, ctx):
        if not self.samples:
            return None
        t, x = np.array(self.samples).T
        cols, header = [t, x], "t_s,x_front_m"
        if self.cfg["wall_height"] and len(self.heights) == len(t):
            cols.append(np.array(self.heights)[:, 1])
            header += ",eta_back_wall_m"
        if ctx.output_dir is not None and ctx.output_dir.exists():
            # atomically: a full disk keeps the previous front.csv, no temporary left
            write_atomically(ctx.output_dir / "front.csv", lambda tmp: np.savetxt(
                tmp, np.column_stack(cols), delimiter=",", header=header, comments="", fmt="%.8g"))
        out = compare(t, x, self.a, self.x_wall - 2 * float(np.median(ctx.state.radius)), self.references)
        out["column_width_m"] = self.a
        out["front_reference"] = self.reference_note
        if self.cfg["wall_height"]:
            th, eta = np.array(self.heights).T
            out["eta_back_wall_final_m"] = float(eta[-1])
            if "martin_moyce_n2" in self.references:
                out.update(compare_height(th, eta, self.a))
        return out
