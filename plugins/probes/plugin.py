"""The ``probes`` plugin: wall-pressure sensors and water-depth gauges sampled during a run.

Samples on its own schedule (``[probes] every_dt``, every step by default), appends each
sample to ``probes.nc``, rewrites ``probes.csv`` at the end, and reports per pressure probe
its peak and, where the probe names a shipped experiment, the error figures of
:mod:`sphcore_plugins.probes.figures` in the run summary. Sampling itself is
:mod:`sphcore_plugins.probes.sampling` (numba, plain arrays).

Walls that move: a sensor with ``attach`` rides with its wall group (see
:mod:`sphcore_plugins.probes.config`): at each sample its points are those of case.toml
carried to the group's pose at ``t`` (``pose.to_world``), its face's normal turned with
the group, and a wall-mode sensor reads with the apparent gravity g - a_w at each of its
points (a_w the wall's acceleration there: in the wall's frame water at rest has grad p =
rho (g - a_w)). An attached depth gauge measures along the group's up (-g turned with the
group). Depth gauges read the planes where they are at ``t`` (``ctx.planes``) whenever the
tank moves. A case where nothing is attached and no plane moves samples as with fixed
walls, with the arrays computed once at set-up.

Reads from the run context: ``state`` (pos, rho, p, m, kind), ``t``, ``step``,
``output_dir``, ``params`` (h, kernel_id, rho0, gravity), ``restarting``, ``planes``
(where they are at ``t``) and ``case`` (config, file, dir, dim, dx, moving).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sphcore.api import SUPPORT, CaseError, OutputError, Schedule, check_series, hookimpl, new_record, record_frame

from . import figures
from .config import OPTIONS, TABLE, parse
from .sampling import depth_above, interpolate_pressure, select_near
from .store import CSV_NAME, ProbeFile, write_csv

DEPTH_STEP = 0.25  # depth scan step, in particle spacings dx


def ceiling_distance(x0, up, normals, offsets) -> float:
    """Distance (m) from ``x0`` along ``up`` to the first wall plane it meets."""
    facing = normals @ up
    dist = (normals @ x0 - offsets)
    ahead = facing < -1e-12
    return float(np.min(dist[ahead] / -facing[ahead])) if ahead.any() else 0.0


@dataclass
class Placement:
    """Where one probe samples at one time: ``points`` (k, dim), the segment [``a``, ``b``]
    whose neighbourhood holds the particles it reads, the face's normal ``face_n`` (zeros:
    none), ``gravity`` (k, dim) the apparent gravity at each point (None: g, a fixed
    probe), ``up`` the direction a depth gauge measures along, and the tank's planes
    (``normals``, ``offsets``) at that time."""

    points: np.ndarray
    a: np.ndarray
    b: np.ndarray
    face_n: np.ndarray
    gravity: np.ndarray | None
    up: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray


class ProbesPlugin:
    """Pluggy plugin ``probes`` (case table ``[probes]``, see :mod:`sphcore_plugins.probes.config`)."""

    def __init__(self):
        self.probes = []
        self.schedule = Schedule(every_steps=1)
        self.times, self.steps, self.values, self.dry = [], [], [], []
        self.file: ProbeFile | None = None
        self._failed = False
        self._restart_step: int | None = None
        self._record: dict = {}  # samples written to probes.nc (kept by the checkpoint)
        self._csv_rows = -1  # samples in the last probes.csv written
        self.motions, self.planes_move, self.moves = [], False, False

    @hookimpl
    def sph_options(self):
        return {TABLE: OPTIONS}

    @hookimpl
    def sph_configure(self, case):
        every_dt, self.probes = parse(case)
        self.schedule = Schedule(every_dt=every_dt) if every_dt > 0 else Schedule(every_steps=1)
        moving = getattr(case, "moving", ())
        # the motion of each probe's wall group (None: fixed), and whether the tank's planes move
        self.motions = [next(g.motion for g in moving if g.name == p.group) if p.group else None
                        for p in self.probes]
        self.planes_move = any(len(g.planes) for g in moving)
        # where probes or planes move, the probes are placed anew at every sample (place)
        self.moves = self.planes_move or any(m is not None for m in self.motions)

    @hookimpl
    def sph_moving_walls(self):
        return True

    @hookimpl
    def sph_setup(self, ctx):
        case, dim = ctx.case, ctx.case.dim
        self.h, self.kernel_id = float(ctx.params.h), int(ctx.params.kernel_id)
        self.gravity = np.ascontiguousarray(np.asarray(ctx.params.gravity, float)[:dim])
        self.g = float(np.linalg.norm(self.gravity))
        self.normals = np.ascontiguousarray(case.planes.normals, dtype=float)
        self.offsets = np.ascontiguousarray(case.planes.offsets, dtype=float)
        self.ds = DEPTH_STEP * case.dx
        self.up = -self.gravity / self.g if self.g > 0 else np.zeros(dim)
        seg_a, seg_b = [], []
        for p in self.probes:
            if p.kind == "depth":
                if self.g == 0:
                    raise CaseError(case.file, f"{p.key}.point", "a depth probe needs gravity (it measures along -g)")
                seg_a.append(p.start)
                seg_b.append(p.start + ceiling_distance(p.start, self.up, self.normals, self.offsets) * self.up)
            else:
                seg_a.append(p.start)
                seg_b.append(p.end)
        self.seg_a, self.seg_b = np.ascontiguousarray(seg_a), np.ascontiguousarray(seg_b)
        self.idx = np.empty(ctx.state.pos.shape[0], np.int64)  # candidate indices, reused every sample
        self.is_pressure = np.array([p.kind == "pressure" for p in self.probes])
        self.work = [(np.zeros(len(p.points)), np.zeros(len(p.points))) for p in self.probes]
        # the face each wall sensor sits on (zeros: none, every particle is read)
        self.face_n = [np.ascontiguousarray(p.face_n if p.face_n is not None else np.zeros(dim))
                       for p in self.probes]
        self.case_planes = case.planes
        self.rho0 = float(ctx.params.rho0)
        self.config, self.case_name = case.config, case.config["case"]["name"] or case.dir.name
        # a restart keeps the samples up to the checkpoint's step, found at the first output;
        # probes.nc must hold those the checkpoint counts (the record of what was written)
        self._restart_step = ctx.step if ctx.restarting else None
        self._record = ctx.kept(self) if hasattr(ctx, "kept") else {}  # a stand-in context keeps nothing
        if not ctx.restarting:
            new_record(self._record)
        elif ctx.output_dir is not None:
            found = ProbeFile(ctx.output_dir).on_disk()
            if found is not None:
                kept = check_series(found[0], found[1], self._record, ctx.t, ctx.step)
                if kept >= 0:
                    new_record(self._record, (found[1] or [])[:kept])

    # ------------------------------------------------------------------ sampling

    def place(self, t, planes) -> list[Placement]:
        """Where every probe samples at time ``t`` (s), the tank's ``planes`` being where they
        are then: see :class:`Placement`. A fixed probe keeps its set-up arrays."""
        poses = {}
        normals = np.ascontiguousarray(planes.normals, dtype=float)
        offsets = np.ascontiguousarray(planes.offsets, dtype=float)
        out = []
        for k, p in enumerate(self.probes):
            motion = self.motions[k]
            if motion is None:
                points, face_n, up, gravity = p.points, self.face_n[k], self.up, None
            else:
                pose = poses.get(p.group)
                if pose is None:
                    pose = poses[p.group] = motion.pose(t)
                points = np.ascontiguousarray(pose.to_world(p.points))
                face_n = np.ascontiguousarray(pose.direction_to_world(self.face_n[k]))
                up = np.ascontiguousarray(pose.direction_to_world(self.up))
                gravity = np.ascontiguousarray(self.gravity[None, :] - pose.point_acceleration(points))
            if p.kind == "depth":
                x0 = points[0]
                a, b = x0, x0 + ceiling_distance(x0, up, normals, offsets) * up
            elif motion is None:
                a, b = p.start, p.end
            else:
                a, b = pose.to_world(p.start), pose.to_world(p.end)
            out.append(Placement(points, a, b, face_n, gravity, up, normals, offsets))
        return out

    def sample(self, state, t=0.0, planes=None):
        """(values, dry) of every probe for the particle arrays of ``state`` at time ``t``
        (s), the tank's ``planes`` being where they are then (None: those of case.toml;
        only read where probes or planes move)."""
        n = state.pos.shape[0]
        if self.idx.shape[0] < n:
            self.idx = np.empty(n, np.int64)
        if self.moves:
            return self._sample_moving(state, self.place(t, self.case_planes if planes is None else planes))
        pos = np.ascontiguousarray(state.pos)
        c = select_near(pos, np.ascontiguousarray(state.kind), self.seg_a, self.seg_b, SUPPORT * self.h, self.idx)
        near = self.idx[:c]
        pc, rc, mc, prc = pos[near], state.rho[near], state.m[near], state.p[near]
        values, dry = np.zeros(len(self.probes)), np.zeros(len(self.probes), np.int8)
        for k, p in enumerate(self.probes):
            if p.kind == "pressure":
                out_p, out_w = self.work[k]
                interpolate_pressure(p.points, pc, prc, rc, mc, self.kernel_id, self.h, self.gravity,
                                     p.mode == "wall", self.face_n[k], out_p, out_w)
                values[k] = out_p.mean()  # a dry part of a line sensor reads 0 (gauge)
                dry[k] = not (out_w > 0).any()
            else:
                values[k] = depth_above(p.start, self.up, self.ds, pc, rc, mc, self.kernel_id, self.h,
                                        self.normals, self.offsets)
                dry[k] = values[k] == 0.0
        return values, dry

    def _sample_moving(self, state, placed):
        """:meth:`sample` with the probes where ``placed`` (:meth:`place`) puts them."""
        pos = np.ascontiguousarray(state.pos)
        seg_a = np.ascontiguousarray([q.a for q in placed])
        seg_b = np.ascontiguousarray([q.b for q in placed])
        c = select_near(pos, np.ascontiguousarray(state.kind), seg_a, seg_b, SUPPORT * self.h, self.idx)
        near = self.idx[:c]
        pc, rc, mc, prc = pos[near], state.rho[near], state.m[near], state.p[near]
        values, dry = np.zeros(len(self.probes)), np.zeros(len(self.probes), np.int8)
        for k, (p, q) in enumerate(zip(self.probes, placed)):
            if p.kind == "pressure":
                out_p, out_w = self.work[k]
                wall = p.mode == "wall"
                if q.gravity is None:
                    interpolate_pressure(q.points, pc, prc, rc, mc, self.kernel_id, self.h, self.gravity,
                                         wall, q.face_n, out_p, out_w)
                else:  # the apparent gravity differs from point to point on a turning wall
                    for s in range(q.points.shape[0]):
                        interpolate_pressure(q.points[s:s + 1], pc, prc, rc, mc, self.kernel_id, self.h,
                                             q.gravity[s], wall, q.face_n, out_p[s:s + 1], out_w[s:s + 1])
                values[k] = out_p.mean()
                dry[k] = not (out_w > 0).any()
            else:
                values[k] = depth_above(q.points[0], q.up, self.ds, pc, rc, mc, self.kernel_id, self.h,
                                        q.normals, q.offsets)
                dry[k] = values[k] == 0.0
        return values, dry

    # ------------------------------------------------------------------ output

    @hookimpl
    def sph_output(self, ctx, final):
        if self._restart_step is not None:
            self._reopen(ctx)
        if self.schedule.due(ctx.t, ctx.step, final):
            values, dry = self.sample(ctx.state, ctx.t, ctx.planes) if self.moves else self.sample(ctx.state)
            self.times.append(float(ctx.t))
            self.steps.append(int(ctx.step))
            self.values.append(values)
            self.dry.append(dry)
            self._append(ctx, values, dry)
        if final:
            self._write_csv(ctx)

    def _reopen(self, ctx):
        last, self._restart_step = self._restart_step, None
        if ctx.output_dir is None:
            return
        self.file = ProbeFile(ctx.output_dir)
        try:
            kept = self.file.reopen(last)
        except OutputError:
            self._failed = True
            raise
        if kept is None:
            self.file = None
            return
        vals = np.where(self.is_pressure[None, :], kept["pressure"], kept["depth"])
        self.times, self.steps = list(kept["time"]), list(kept["step"])
        self.values, self.dry = list(vals), list(kept["dry"])
        if self.times:
            self.schedule.resume(self.times[-1], self.steps[-1] if self.steps[-1] == ctx.step else None)

    def _append(self, ctx, values, dry):
        if ctx.output_dir is None or self._failed:
            return
        try:
            if self.file is None or self.file.ds is None:
                self.file = ProbeFile(ctx.output_dir)
                self.file.create(self.probes, ctx.case.dim, self.rho0, self.g, self.config, self.case_name)
            is_p = self.is_pressure
            self.file.append(ctx.t, ctx.step, np.where(is_p, values, np.nan), np.where(is_p, np.nan, values), dry)
            record_frame(self._record, ctx.t, ctx.step)
        except OutputError:
            self._failed = True
            raise

    def _write_csv(self, ctx):
        if ctx.output_dir is None or not ctx.output_dir.exists() or not self.times:
            return
        if len(self.times) != self._csv_rows:
            write_csv(ctx.output_dir / CSV_NAME, self.probes, self.times, np.array(self.values))
            self._csv_rows = len(self.times)

    # ------------------------------------------------------------------ end of run

    def series(self, name):
        """(t (s), values) of the probe called ``name``, as sampled so far."""
        k = [p.name for p in self.probes].index(name)
        return np.array(self.times), np.array(self.values)[:, k] if self.values else np.zeros(0)

    @hookimpl
    def sph_summary(self, ctx):
        if not self.times:
            return None
        t, vals = np.array(self.times), np.array(self.values)
        out = {"probes_samples": len(t)}
        for k, p in enumerate(self.probes):
            i = int(np.argmax(vals[:, k]))
            if p.kind == "depth":
                out[f"probe_{p.name}_max_m"] = float(vals[i, k])
                out[f"probe_{p.name}_max_t_s"] = float(t[i])
                continue
            out[f"probe_{p.name}_peak_pa"] = float(vals[i, k])
            out[f"probe_{p.name}_peak_t_s"] = float(t[i])
            if p.reference:
                errs = figures.errors(p.reference, t, vals[:, k], self.rho0, self.g, p.height)
                out.update({f"probe_{p.name}_{key}": value for key, value in errs.items()})
        return out

    @hookimpl
    def sph_finish(self, ctx):
        file, self.file = self.file, None
        if file is not None:
            file.close()
        if not self._failed:
            self._write_csv(ctx)
