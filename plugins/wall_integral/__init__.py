"""Semi-analytical (boundary-integral) walls as the sphcore plugin ``wall_integral``.

The reflective boundary keeps particles inside but leaves their kernel support truncated at
the walls: a particle near a wall misses part of its density sum and feels no wall pressure.
This plugin supplies, through the core's ``sph_wall_terms`` hook, the wall's exact share of
each particle's kernel support, computed from the wall planes (``share.py``: closed forms
for planes, corners and wedges of any angle, 2D and 3D): the share s, its gradient G, the
hydrostatic moment T g, and the projector onto the near walls' normals (``normals.py``),
for the particles within 2h of a plane only (``planes.py``). The core completes the sums with them
(:func:`.completion.complete_at_wall`, compiled into the core's pair loop):

    drho_i/dt = sum_j m_j v_ij . grad W_ij + 2 rho_i v_i . G_w
    dv_i/dt   = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad W_ij
                  - 2 (p_i/rho_i) G_w - ((rho_i - rho_ref)/rho_i) A_w g,

the missing support filled with the mirror image of the fluid, its pressure extrapolated
hydrostatically (the boundary-integral walls of Kulasegaram et al. 2004 and Ferrand et al.
2013, in the mirror form that makes the wall do no net work). The wall gradient G_w is the
exact G minus the lattice error of the truncated sum on the initial lattice, tabulated once
per run for one, two and three perpendicular walls (``lattice.py``): a function of position,
so the wall pushes harder the closer a particle comes, and a uniform pressure exerts no
force on the initial lattice, corners included. A_w g is the discrete complement of the
particle's own first moment along the walls' normals and lambda (T g + s g) - F g along
them (lambda the interior's lattice normalisation, F the side wall's lattice error), so
that a column along a side wall is held up as the interior is. Why this formulation: it
needs no wall particles (the paper's walls stay planes), it is exact for the geometry, and
it is consistent with the interior on the lattice the blocks are filled with. Its measured
state (hydrostatic tank, wall-pressure experiments) is in docs/explanation/wall_model.md and the validation pages.

Finite walls (``[[domain.walls]]``: obstacles, meshes) add their exact terms too
(:mod:`.facewalls`, :mod:`.meshfaces`), without the lattice-error correction the planes
have (see :mod:`.facewalls`); with ``faces = "table"`` they are computed once per run on a
grid and interpolated (:mod:`.facetable`: next to fine meshes the exact integrals cost
most of a step).

Walls that move (``[[domain.motion]]``, ``[[domain.walls.motion]]``): the tank's planes are
taken where they are, a moving group's faces in its own frame, continuity takes the
velocity relative to the walls and the wall pressure the walls' acceleration
(:mod:`.moving`); each moving group's load (the wall pressure's force and moment) goes to
``ctx.add_wall_load`` for the ``wall_loads`` writer. Moving faces use the exact integrals
(``faces = "table"`` tabulates the fixed faces only).

Use it beside ``reflective``, which keeps every particle inside:
``[plugins] use = ["reflective", "wall_integral", ...]``. Options (``[wall_integral]``):
``faces`` ("exact" or "table"), ``table_spacing`` (in h), ``table_max_nodes``.

Run summary (under "wall_integral"): ``near_wall_last``, particles within 2h of a wall at
the last force evaluation; with finite walls ``face_terms`` ("exact" or "table") and, when
a table was asked for, ``face_table_nodes`` (0: too large, the exact terms were used).
"""

from __future__ import annotations

import numpy as np

from sphcore.api import CaseError, Option, hookimpl, impulse_load, on_threads_by_size, tank_load


class WallIntegralPlugin:
    """Boundary-integral wall terms of the case's planes; one instance per run."""

    def __init__(self):
        self._near = np.zeros(0, np.int64)  # indices of the particles near a plane (scratch)
        self._table = None
        self.walls = None  # finite faces (sphcore.geometry.faces.Faces) or None
        self.bodies = set()
        self._faces = None
        self._epoch = 0
        self._solved_parts = {}  # {group: [(indices, G_k, G)]}: see _solved_loads

    @hookimpl
    def sph_options(self):
        return {"wall_integral": {
            "faces": Option("exact", "str", doc="wall terms of finite faces (meshes, boxes, polygons): 'exact' "
                            "integrates every face within 2h of every particle every step; 'table' computes them "
                            "once on a grid and interpolates them (much faster next to fine meshes, ~1% error in "
                            "G: docs/explanation/wall_model.md)", choices=("exact", "table")),
            "table_spacing": Option(0.25, "float", doc="node spacing of the faces' table, in units of h",
                                    positive=True),
            "table_max_nodes": Option(2_000_000, "int", doc="largest table (14 numbers, 112 bytes, a node); a larger one "
                                      "is not built and the exact integrals are used", min=1),
        }}

    @hookimpl
    def sph_configure(self, case):
        file = getattr(case, "file", "case.toml")
        self.cfg = case.config["wall_integral"]
        if not case.config["physics"]["sph"]:
            raise CaseError(file, "plugins.use", "wall_integral completes SPH sums; physics.sph is false")
        faces = getattr(case, "faces", None)
        self.walls = faces if faces is not None and faces.count else None
        if case.planes.count == 0 and self.walls is None:
            raise CaseError(file, "plugins.use", "wall_integral needs walls ([domain] min/max, planes or walls)")
        self.normals = np.ascontiguousarray(case.planes.normals, dtype=np.float64)
        self.offsets = np.ascontiguousarray(case.planes.offsets, dtype=np.float64)
        self._faces = None  # (verts, flat parts, grid arrays, stamps, table), built on first use (the grid needs h)
        self._epoch = 0
        # walls that move (sphcore.geometry.motion.MovingGroup): the tank's planes follow
        # ctx.planes; each group's faces get their own grid in the group's frame (.moving)
        groups = tuple(getattr(case, "moving", ()))
        self.plane_groups = tuple(g for g in groups if len(g.planes))
        self.face_groups = tuple(g for g in groups if len(g.faces))
        # floating bodies (their motion answers begin_step): their loads come from the reaction
        self.bodies = {g.name for g in self.face_groups if hasattr(g.motion, "begin_step")}
        self._fixed = None
        if self.walls is not None and self.face_groups:
            moving = np.zeros(self.walls.count, bool)
            for g in self.face_groups:
                moving[np.asarray(g.faces, np.int64)] = True
            self._fixed = np.flatnonzero(~moving)
        self._moving_faces = None  # per face group: (verts, flat parts, grid arrays, stamps), built on first use
        self._within = np.empty(0, np.int64)  # scratch: the particles near a body
        # one group holding every wall (a tank): its load from the fluid's momentum balance
        nf = self.walls.count if self.walls is not None else 0
        self.tank = groups[0] if len(groups) == 1 and len(groups[0].planes) == case.planes.count \
            and len(groups[0].faces) == nf else None

    @hookimpl
    def sph_moving_walls(self):
        # the planes where the tank is, the faces in their group's frame, the walls' velocity
        # in continuity and their acceleration in the wall pressure (moving.py)
        return True

    @hookimpl
    def sph_wall_completion(self, dim):
        from .completion import complete_at_moving_wall, complete_at_wall

        # the terms of moving walls are compiled only into the runs that have them
        return complete_at_moving_wall if self.plane_groups or self.face_groups else complete_at_wall

    @hookimpl
    def sph_wall_terms(self, ctx, terms):
        # the kernels are imported on first use: every run loads every installed plugin to
        # validate its tables, and these modules build their tables at import (~0.15 s)
        from .lattice import lattice_error_tables
        from .planes import PARALLEL_NEAR, add_plane_terms, near_planes

        st, prm = ctx.state, ctx.params
        n, dim = st.n, prm.dim
        if self._near.shape[0] < n:
            self._near = np.empty(n + n // 4, np.int64)
        if self._table is None:
            self._table = lattice_error_tables(prm.kernel_id, prm.h, prm.dx, dim, prm.moment_norm)
        normals, offsets = self.normals, self.offsets
        if self.plane_groups:  # the planes where they are now
            planes = ctx.planes
            normals = np.ascontiguousarray(planes.normals, dtype=np.float64)
            offsets = np.ascontiguousarray(planes.offsets, dtype=np.float64)
        # the terms of the planes, for the particles within 2h of one (the core zeroed the arrays)
        count = near_planes(st.pos, normals, offsets, prm.support, self._near)
        if count:  # no particle near a plane (a tank of faces alone): no launch
            on_threads_by_size(count, PARALLEL_NEAR, add_plane_terms, self._near, count, st.pos, normals,
                               offsets, prm.kernel_id, prm.h, prm.gravity, *self._table, prm.support,
                               prm.moment_norm, terms.share, terms.grad, terms.hydro, terms.fill, terms.normals)
        loads = {}
        # a scheme that solves for its pressure (ctx.solved_impulse): each group's part of the
        # wall gradient of the particles it reaches, to split the solves' wall kicks by group
        solving = ctx.solved_impulse is not None
        parts = {}
        for g in self.plane_groups:
            if count:
                loads[g.name] = self._plane_group_terms(ctx, terms, count, g, normals, offsets)
                if solving and g is not self.tank:
                    parts[g.name] = [self._plane_group_parts(ctx, terms, count, g, normals, offsets)]
        if self.walls is not None:
            if self._fixed is None or len(self._fixed):
                self._add_face_terms(ctx, terms)
            members = {}
            for k, g in enumerate(self.face_groups):
                reached = g.name in self.bodies or (solving and g is not self.tank)
                near = self._near_body(ctx, k, g) if reached else None
                before = terms.grad[near] if near is not None else None
                force, moment = self._moving_face_terms(ctx, terms, k, g)
                if near is not None and g.name in self.bodies:  # the particles a body's faces reach, and how much
                    part = np.sqrt(((terms.grad[near] - before) ** 2).sum(axis=1))
                    members[g.name] = (near, part)
                elif near is not None:
                    parts.setdefault(g.name, []).append((near, terms.grad[near] - before))
                if g.name in loads:  # the tank's walls: its planes and faces together
                    force, moment = force + loads[g.name][0], moment + loads[g.name][1]
                loads[g.name] = (force, moment)
        if self.walls is not None and self.bodies:
            # each body's particles, weighted by the body's part of their wall gradient: the
            # load is the reaction of what the completion gives them (ctx.wall_members)
            for name, (near, part) in members.items():
                reached = part > 0.0
                idx = near[reached]
                total = np.sqrt((terms.grad[idx] ** 2).sum(axis=1))
                ctx.wall_members[name] = (idx, np.minimum(1.0, part[reached] / total))
        for name, (force, moment) in loads.items():
            if name not in self.bodies:  # a body's load is the exact reaction (the run sums it)
                ctx.set_wall_force(name, force, moment)
        # each part with the whole gradient it is a part of (the solves kick along that)
        self._solved_parts = {name: [(idx, k, terms.grad[idx]) for idx, k in found] for name, found in parts.items()}
        if self.plane_groups or self.face_groups:  # kept for the next step's load (restart too)
            ctx.kept(self)["loads"] = {name: [float(v) for v in f] + [float(v) for v in m]
                                       for name, (f, m) in loads.items() if name not in self.bodies}
        ctx.stats(self)["near_wall_last"] = int(np.count_nonzero(terms.share))

    @hookimpl
    def sph_after_integrate(self, ctx, pos0, pos, vel, acc, dt):
        """The step's load on each moving group, times dt: a tank holding every wall from the
        fluid's momentum balance (:func:`sphcore.api.tank_load`, exact), otherwise the wall
        pressure's force and moment of the evaluation the step started from (:mod:`.moving`)."""
        if not self.plane_groups and not self.face_groups:
            return
        if self.tank is not None:  # every wall the tank's: the exact momentum balance
            force, moment = tank_load(ctx, self.tank, pos0, acc)
            ctx.add_wall_load(self.tank.name, force * dt, moment * dt)
            self._solved_loads(ctx, pos0)  # dfsph: its density solve's walls
            return
        dim = ctx.params.dim
        for name, row in ctx.kept(self).get("loads", {}).items():
            force, moment = np.asarray(row[:dim]), np.asarray(row[dim:])
            ctx.add_wall_load(name, force * dt, moment * dt)
        self._solved_loads(ctx, pos0)  # dfsph: its density solve's walls

    @hookimpl
    def sph_after_step(self, ctx):
        """dfsph: the moving groups' loads of the divergence solve that closed the step."""
        if self.plane_groups or self.face_groups:
            self._solved_loads(ctx, ctx.state.pos)

    def _solved_loads(self, ctx, pos):
        """Each moving group's part of a solved pressure (``ctx.solved_impulse``, set by a
        scheme that solves for its pressure after each solve; the rates, and so
        :func:`tank_load`, hold none of it), the opposite of what its walls gave the fluid at
        the positions of the solve, which are those of the last wall terms. A tank holding
        every wall takes all of it; otherwise the kick of particle i is a multiple c_i of its
        wall gradient G_i, and a group's share is c_i G_k,i with G_k,i the group's part of
        G_i (taken with the terms, :meth:`sph_wall_terms`)."""
        j = ctx.solved_impulse
        if j is None:
            return
        if self.tank is not None:
            impulse, angular = impulse_load(ctx, self.tank, pos, j)
            ctx.add_wall_load(self.tank.name, impulse, angular)
            return
        groups = {g.name: g for g in self.plane_groups + self.face_groups}
        for name, found in self._solved_parts.items():
            for idx, k, grad in found:
                norm = (grad * grad).sum(axis=1)
                c = np.divide((j[idx] * grad).sum(axis=1), norm, out=np.zeros(idx.shape[0]), where=norm > 0.0)
                impulse, angular = impulse_load(ctx, groups[name], pos[idx], c[:, None] * k)
                ctx.add_wall_load(name, impulse, angular)

    def _plane_group_parts(self, ctx, terms, count, group, normals, offsets):
        """(indices, G_k) of the particles near a plane: the group's part of their wall
        gradient (:func:`.moving.group_parts`)."""
        from .moving import group_parts

        st, prm = ctx.state, ctx.params
        member = np.zeros(normals.shape[0], np.bool_)
        member[group.planes] = True
        idx = self._near[:count].copy()
        k = np.zeros((count, prm.dim))
        group_parts(idx, count, st.pos, normals, offsets, member, prm.support, terms.grad, k)
        return idx, k

    def _load_coefs(self, ctx):
        """(2 m p / rho, m lambda (rho - rho_ref) / rho) per particle: the coefficients of G and
        of the first moment in the wall's load (:mod:`.moving`)."""
        st, prm = ctx.state, ctx.params
        return (2.0 * st.m * ctx.force_pressure / st.rho,
                st.m * prm.moment_norm * (st.rho - prm.rho_ref) / st.rho)

    @staticmethod
    def _gravity3(prm):
        g = np.zeros(3)
        g[:prm.dim] = np.asarray(prm.gravity, np.float64)[:prm.dim]
        return g

    def _plane_group_terms(self, ctx, terms, count, group, normals, offsets):
        """A moving group's planes (:func:`.moving.plane_group_terms`)."""
        from .moving import empty_load, load_of, plane_group_terms, pose_arrays

        st, prm = ctx.state, ctx.params
        rot, centre, origin, vel, acc, omega, alpha = pose_arrays(group.motion.pose(ctx.t), prm.dim)
        member = np.zeros(normals.shape[0], np.bool_)
        member[group.planes] = True
        own_normals = np.ascontiguousarray(normals[group.planes])
        own_offsets = np.ascontiguousarray(offsets[group.planes])
        load = empty_load()
        plane_group_terms(self._near, count, st.pos, normals, offsets, member, own_normals, own_offsets, prm.support,
                          prm.kernel_id, prm.h, origin, vel, acc, omega, alpha, self._gravity3(prm),
                          *self._load_coefs(ctx), terms.share, terms.grad, terms.hydro, terms.flux, terms.accel, load)
        return load_of(load, prm.dim)

    def _near_body(self, ctx, k, group):
        """The particles that body ``group``'s faces may reach: within the support of the
        sphere round its centre that holds its faces (one compiled pass over the particles;
        the body's share of their terms is then taken over these alone)."""
        from .moving import within

        st, prm = ctx.state, ctx.params
        pose = group.motion.pose(ctx.t)
        reach = group.reach + prm.support  # the faces' largest distance from the centre, from the case
        if self._within.shape[0] < st.n:
            self._within = np.empty(st.n + st.n // 4, np.int64)
        count = within(st.pos, np.ascontiguousarray(pose.centre + pose.shift, dtype=np.float64), reach, self._within)
        return self._within[:count].copy()

    def _moving_face_terms_setup(self, ctx, k, group):
        """The faces of moving group k in its own frame, their grid and marks (built once)."""
        from sphcore.api import build_grid

        from .facewalls import flat_parts, stamps_for

        if self._moving_faces is None:
            self._moving_faces = [None] * len(self.face_groups)
        if self._moving_faces[k] is None:
            verts = np.ascontiguousarray(self.walls.verts[np.asarray(group.faces, np.int64)], dtype=np.float64)
            self._moving_faces[k] = (verts, flat_parts(verts), build_grid(verts, ctx.params.support).arrays(),
                                     stamps_for(verts.shape[0]))

    def _moving_face_terms(self, ctx, terms, k, group):
        """A moving group's faces in its own frame (:func:`.moving.moving_face_terms`)."""
        from .moving import empty_load, load_of, pose_arrays, moving_face_terms

        st, prm = ctx.state, ctx.params
        self._moving_face_terms_setup(ctx, k, group)
        verts, flat, grid, stamps = self._moving_faces[k]
        pose = group.motion.pose(ctx.t)
        rot, centre, origin, vel, acc, omega, alpha = pose_arrays(pose, prm.dim)
        world = self._gravity3(prm)
        gravity = np.zeros(3)
        gravity[:prm.dim] = rot.T @ world[:prm.dim]  # g in the group's frame
        full = float(self._table[1][self._table[1].shape[0] - 1, 2])
        load = empty_load()
        self._epoch += 2  # two marks a particle (moving_face_terms)
        moving_face_terms(st.pos, rot, centre, origin, vel, acc, omega, alpha, verts, flat, *grid, stamps, self._epoch,
                          prm.kernel_id, prm.h, gravity, world, full, *self._load_coefs(ctx), terms.share, terms.grad,
                          terms.hydro, terms.fill, terms.normals, terms.flux, terms.accel, load)
        return load_of(load, prm.dim)

    def _add_face_terms(self, ctx, terms):
        """The finite faces' terms: from the table (built on the first call) or exact."""
        from sphcore.api import build_grid

        from .facetable import build_table, table_wall_terms
        from .facewalls import face_wall_terms, flat_parts, stamps_for

        st, prm = ctx.state, ctx.params
        full = float(self._table[1][self._table[1].shape[0] - 1, 2])  # interior lattice sum
        if self._faces is None:  # cells of 2h: a particle's support box spans <= 3 per axis
            verts = self.walls.verts if self._fixed is None else self.walls.verts[self._fixed]
            verts = np.ascontiguousarray(verts, dtype=np.float64)
            grid = build_grid(verts, prm.support).arrays()
            flat = flat_parts(verts)
            table = None
            if self.cfg["faces"] == "table":
                spacing = self.cfg["table_spacing"] * prm.h
                table = build_table(verts, flat, grid, prm.kernel_id, prm.h, prm.gravity, spacing,
                                    self.cfg["table_max_nodes"])
            self._faces = (verts, flat, grid, stamps_for(verts.shape[0]), table)
        verts, flat, grid, stamps, table = self._faces
        stats = ctx.stats(self)  # in the summary: which terms the faces got, and the table's size
        stats["face_terms"] = "table" if table is not None else "exact"
        if self.cfg["faces"] == "table":
            stats["face_table_nodes"] = int(table.tab.shape[0]) if table is not None else 0
        if table is not None:
            table_wall_terms(st.pos, table.lo, table.inv, table.shape, table.tab, full, terms.share, terms.grad,
                             terms.hydro, terms.fill, terms.normals)
            return
        self._epoch += 1  # the face marks of this call differ from every earlier one's
        face_wall_terms(st.pos, verts, flat, *grid, stamps, self._epoch, prm.kernel_id, prm.h, prm.gravity,
                        full, terms.share, terms.grad, terms.hydro, terms.fill, terms.normals)
