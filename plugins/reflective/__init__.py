"""Physical reflective boundary (paper sections 2 and 3) as the sphcore plugin ``reflective``.

After each free-motion step the particles that crossed a wall plane are reflected back
into the domain (collision detection and response, :mod:`.collision`). Case table::

    [reflective]
    cr = 1.0               # restitution coefficient (Eq. 2), 0 <= cr <= 1
    max_reflections = 1000 # reflections per particle and step before the guard
    velocity = "contact"   # Eq. 2 at the contact point ("contact") or the end point ("end")

Run summary (``summary.json`` under ``"reflective"``): ``guard_returns`` counts
particle-steps that needed the guard (put back at the start of the step after
``max_reflections``: no particle ever ends a step outside, so nothing escapes),
``reflected_particle_steps`` the particle-steps with at least one reflection,
``reflection_events`` all reflections.
"""

from __future__ import annotations

import numpy as np

from sphcore.api import CaseError, Option, hookimpl

from .collision import TOL_REL, Paths, Response, Tally, WallGroup, reflect, reflect_step
from .corner import scratch
from .entry import clearance, face_arrays, min_clearance, outside, outside_mask, reflect_particles
from .moving import groups_of, reflect_moving

__all__ = [
    "TOL_REL",
    "Paths",
    "ReflectivePlugin",
    "Response",
    "Tally",
    "WallGroup",
    "clearance",
    "min_clearance",
    "outside",
    "outside_mask",
    "reflect",
    "reflect_particles",
    "reflect_step",
]

TABLE = "reflective"


class ReflectivePlugin:
    """Reflective walls on the case's planes (``case.planes``); one instance per run."""

    def __init__(self):
        self.response = Response(1.0, 1000, True)
        # the kernel's planes and faces; the faces' grid is built at setup (it needs the radius)
        self.group = WallGroup.of(np.zeros((0, 0)), np.zeros(0), face_arrays(None, 0, 1.0))
        self.walls = None  # finite faces (sphcore.geometry.faces.Faces) or None
        self.scratch = scratch()  # per-thread work arrays of corner contacts
        # per-particle kernel outputs, resized when the particle count changes
        self._guarded = np.zeros(0, np.int8)
        self._counts = np.zeros(0, np.int32)

    @hookimpl
    def sph_options(self):
        return {
            TABLE: {
                "cr": Option(
                    1.0, "float",
                    doc="restitution coefficient CR (paper Eq. 2): scales the normal velocity "
                        "(normal kinetic energy by CR^2); 1 elastic, 0 stops the normal motion",
                    min=0.0, extra={"max": 1.0}),
                "max_reflections": Option(
                    1000, "int", positive=True,
                    doc="reflections per particle and step before the guard puts the particle "
                        "back at its start-of-step position"),
                "velocity": Option(
                    "contact", "str", choices=("contact", "end"),
                    doc="where Eq. 2 is applied: 'contact' corrects for the step's acceleration "
                        "between contact and end point (energy-consistent under gravity); "
                        "'end' applies it literally to the end-of-step velocity"),
            }
        }

    @hookimpl
    def sph_configure(self, case):
        """Read [reflective] and the wall planes the core built (``case.planes``)."""
        cfg = case.config[TABLE]
        self.response = Response(float(cfg["cr"]), int(cfg["max_reflections"]), cfg["velocity"] == "contact")
        planes = getattr(case, "planes", None)
        faces = getattr(case, "faces", None)
        if (planes is None or planes.count == 0) and (faces is None or faces.count == 0):
            raise CaseError(getattr(case, "file", "case.toml"), "plugins.use",
                            "the reflective plugin needs walls ([domain] min/max, planes or walls)")
        normals = np.ascontiguousarray(planes.normals, dtype=np.float64)
        offsets = np.ascontiguousarray(planes.offsets, dtype=np.float64)
        self.walls = faces if faces is not None and faces.count else None
        self.group = WallGroup.of(normals, offsets, face_arrays(None, normals.shape[1], 1.0))  # faces at setup
        # walls that move: the groups that move together, each in its own frame (.moving)
        self.groups = groups_of(case, normals, offsets) if getattr(case, "moving", ()) else None

    @hookimpl
    def sph_moving_walls(self):
        return True

    @hookimpl
    def sph_setup(self, ctx):
        # The guard relies on every start-of-step position being inside; check the first.
        st = ctx.state
        if self.groups is not None:
            self._setup_groups(ctx)
            return
        g = self.group
        if self.walls is not None:  # the grid's cells are sized by the radius
            faces = face_arrays(self.walls, g.normals.shape[1], st.radius.max() if st.n else 1.0)
            self.group = g = WallGroup.of(g.normals, g.offsets, faces)
        if st.n == 0:
            return
        bad = outside(st.pos, st.radius, (g.normals, g.offsets))
        if bad.any():
            c = clearance(st.pos, st.radius, (g.normals, g.offsets))
            worst = int(np.argmin(np.where(bad, c / st.radius, np.inf)))
            raise CaseError(getattr(ctx.case, "file", "case.toml"), "blocks",
                            f"particle id {int(st.id[worst])} at {st.pos[worst].tolist()} overlaps "
                            f"a wall by {-c[worst]:.3g} m (a centre needs distance >= radius)")
        if self.walls is not None:
            d = self.walls.distances(st.pos) - st.radius * (1.0 - TOL_REL)
            if (d < 0).any() or not self.walls.in_fluid(st.pos).all():
                worst = int(np.argmin(np.where(self.walls.in_fluid(st.pos), d, -np.inf)))
                raise CaseError(getattr(ctx.case, "file", "case.toml"), "blocks",
                                f"particle id {int(st.id[worst])} at {st.pos[worst].tolist()} lies in a "
                                "solid wall or closer than its radius to a wall face")

    def _setup_groups(self, ctx):
        """Build each group's face grid; check that every particle is inside every group
        where the groups are at ctx.t (a restart starts with them moved)."""
        st = ctx.state
        for g in self.groups:
            g.build_grid(st.radius.max() if st.n else 1.0)
            if st.n == 0:
                continue
            b = g.to_body(st.pos, ctx.t)
            if g.normals.shape[0]:
                bad = outside(b, st.radius, (g.normals, g.offsets))
                if bad.any():
                    c = clearance(b, st.radius, (g.normals, g.offsets))
                    worst = int(np.argmin(np.where(bad, c / st.radius, np.inf)))
                    raise CaseError(getattr(ctx.case, "file", "case.toml"), "blocks",
                                    f"particle id {int(st.id[worst])} at {st.pos[worst].tolist()} overlaps a wall "
                                    f"of {g.name} by {-c[worst]:.3g} m at t = {ctx.t:g} s")
            if g.faces is not None:
                d = g.faces.distances(b) - st.radius * (1.0 - TOL_REL)
                inside = g.faces.in_fluid(b)
                if (d < 0).any() or not inside.all():
                    worst = int(np.argmin(np.where(inside, d, -np.inf)))
                    raise CaseError(getattr(ctx.case, "file", "case.toml"), "blocks",
                                    f"particle id {int(st.id[worst])} at {st.pos[worst].tolist()} lies in a "
                                    f"solid wall of {g.name} or closer than its radius to it at t = {ctx.t:g} s")

    # trylast: walls act after any other plugin has moved particles in this hook
    @hookimpl(trylast=True)
    def sph_after_integrate(self, ctx, pos0, pos, vel, acc, dt):
        """Reflect the particles that crossed a wall this step (``pos``, ``vel`` in place).

        The contact form of Eq. 2 assumes the step was free motion under the constant
        ``acc`` (m/s^2): pos = pos0 + dt (v0 + dt/2 acc) and vel = v0 + dt acc, which is the
        leapfrog drift with the predicted end velocity. Arrays are used only for this call:
        the core may reorder or resize the particles between steps.
        """
        n = pos.shape[0]
        if acc is None:  # no acceleration known: Eq. 2 at the contact equals Eq. 2 (a_n = 0)
            acc = np.zeros_like(pos)
        if self._guarded.shape[0] != n:
            self._guarded = np.zeros(n, np.int8)
            self._counts = np.zeros(n, np.int32)
        tally = Tally(self._guarded, self._counts)
        if self.groups is None:
            guarded, hit, events = reflect_step(Paths(pos0, pos, vel, acc, ctx.state.radius), self.group,
                                                self.response, tally, self.scratch)
        else:
            loads = {}
            guarded, hit, events, pinched = reflect_moving(self.groups, ctx.t, dt, pos0, pos, vel, acc,
                                                           ctx.state.radius, self.response, tally, self.scratch,
                                                           ctx.state.m, loads)
            for name, (impulse, angular) in loads.items():
                ctx.add_contact_impulse(name, impulse, angular)
            stats = ctx.stats(self)
            stats["pinched"] = stats.get("pinched", 0) + pinched
        # ctx.stats: in summary.json under "reflective" and in every checkpoint, so the
        # counts are cumulative across restarts
        stats = ctx.stats(self)
        stats["guard_returns"] = stats.get("guard_returns", 0) + guarded
        stats["reflected_particle_steps"] = stats.get("reflected_particle_steps", 0) + hit
        stats["reflection_events"] = stats.get("reflection_events", 0) + events
