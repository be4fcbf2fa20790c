"""Ghost (mirror) particle walls as the sphcore plugin ``ghost``.

For every force evaluation the fluid particles within the kernel support (2h) of a wall
plane are mirrored across it (and across two or three planes near corners and edges);
the images enter continuity and momentum as neighbour-only sources, so the kernel support
of a wall particle is full and the wall pushes back through the pressure term. This is
the ghost-particle treatment in an extended domain that the seed paper cites as the usual
alternative to its reflective walls (Fraga Filho 2017; mirror ghosts after Libersky et
al. 1993, Colagrossi & Landrini 2003). Geometry and ghost state: :mod:`.mirror`.

Case table::

    [ghost]
    wall = "free_slip"     # or "no_slip": velocity of the images
    hydrostatic = true     # ghost pressure p_i + rho_i g . (x_g - x_i), density by inverse Tait

Ghosts are a force, not a guarantee. The push of a particle's own image vanishes as the
particle reaches the wall (the kernel gradient is zero at r = 0), so a fast particle, or a
thin low-pressure front, can still cross a plane; the core then stops the run with an
Instability (measured: the 0.1 m x 0.2 m column collapse of tests/test_ghost_hydrostatic.py
crosses the floor at its front at t = 0.14 s). ``[plugins] use = ["ghost", "reflective"]``
combines the ghost pressure field with the reflective no-penetration guarantee; the two
plugins act in different hooks (sources before the forces, reflection after the free
motion) and need no coordination.

Walls that move (``[[domain.motion]]``, :mod:`sphcore.case.motion`): the planes of a moving
tank mirror the fluid where they are when the forces are evaluated, and the images take
the wall's velocity and acceleration (:mod:`.moving`: free slip and no slip relative to
the wall, the hydrostatic correction with g - a_w after Adami, Hu & Adams 2012, Eq. 27).
A case with finite wall faces is refused, moving or not (the plugin mirrors across planes
only). A force evaluation sees the planes at ``ctx.t``, the time the particles are at
(the core advances its clock before the leapfrog's end-of-step rates). A case whose walls
do not move takes the fixed-wall path unchanged. The moving walls' load (force and moment
of the fluid on them, for the ``wall_loads`` writer): a tank's is the images' force on the
fluid, reversed, from the fluid's momentum balance (``sph_after_integrate``); with planes
in several groups (a piston) each group's is summed from its images' pair forces
(:mod:`.loads`).

Run summary: ``ghosts_last`` (ghosts of the last force evaluation), ``ghosts_max``,
``ghost_reallocations`` (buffer growths).
"""

from __future__ import annotations

from sphcore.api import CaseError, Fields, Option, hookimpl, plane_groups, tank_load

from .images import MirrorImages, inverse_tait
from .mirror import MAX_PLANES, TAIT_BASE_MIN
from .records import FluidConstants, PlaneGroup, WallMotion

__all__ = ["GhostPlugin", "MirrorImages", "FluidConstants", "PlaneGroup", "WallMotion", "inverse_tait",
           "TAIT_BASE_MIN"]

TABLE = "ghost"


class GhostPlugin:
    """Mirror-particle walls on the case's planes (``case.planes``); one instance per run."""

    def __init__(self):
        self.mirror: MirrorImages | None = None
        # the groups that move planes (sphcore.geometry.motion.MovingGroup): the tank, pistons
        self.groups = ()
        self.tank = None  # the group holding every plane, if one does

    @hookimpl
    def sph_options(self):
        return {
            TABLE: {
                "wall": Option(
                    "free_slip", "str", choices=("free_slip", "no_slip"),
                    doc="velocity of the mirror images: 'free_slip' reverses the normal component "
                        "and keeps the tangential one; 'no_slip' reverses the whole velocity "
                        "(zero wall velocity, felt through the viscous terms)"),
                "hydrostatic": Option(
                    True, "bool",
                    doc="hydrostatic pressure correction of ghost pressure: p_g = p_i + rho_i g . "
                        "(x_g - x_i), ghost density from it by the inverse Tait equation; false "
                        "copies p_i and rho_i"),
            }
        }

    @hookimpl
    def sph_configure(self, case):
        cfg = case.config[TABLE]
        planes = getattr(case, "planes", None)
        file = getattr(case, "file", "case.toml")
        if planes is None or planes.count == 0:
            raise CaseError(file, "plugins.use", "the ghost plugin needs wall planes ([domain] min/max or planes)")
        faces = getattr(case, "faces", None)
        if faces is not None and faces.count:
            moving = " (moving or not)" if any(len(g.faces) for g in getattr(case, "moving", ())) else ""
            raise CaseError(file, "domain.walls", f"the ghost plugin mirrors across wall planes only; the case "
                            f"has {faces.count} finite wall faces{moving}: use reflective and wall_integral")
        if planes.count > MAX_PLANES:
            raise CaseError(file, "domain.planes", f"the ghost plugin handles at most {MAX_PLANES} wall planes, "
                            f"got {planes.count}")
        if not case.config["physics"]["sph"]:
            # no force evaluation ever asks for sources: say so instead of silently doing nothing
            raise CaseError(file, "plugins.use", "the ghost plugin acts through SPH forces; physics.sph is false")
        self.mirror = MirrorImages(planes.normals, planes.offsets, free_slip=cfg["wall"] == "free_slip",
                                   hydrostatic=cfg["hydrostatic"])
        self.groups = plane_groups(getattr(case, "moving", ()))
        # one group holds every plane (a tank): the images' force is all the walls' (the load)
        self.tank = self.groups[0] if len(self.groups) == 1 and len(self.groups[0].planes) == planes.count else None

    @hookimpl
    def sph_moving_walls(self):
        # the planes of a moving tank mirror where they are, with the wall's velocity and
        # acceleration (module docstring); finite faces are refused in sph_configure
        return True

    @hookimpl
    def sph_extra_sources(self, ctx):
        # Read the state now: the core reorders particles by cell every few steps.
        st = ctx.state
        # the pressure the momentum equation uses: with modified pressure, its dynamic part
        fluid = Fields(st.pos, st.vel, st.rho, ctx.force_pressure, st.m)
        if not self.groups:
            src = self.mirror.generate(fluid, st.kind, ctx.params)
        else:
            t = ctx.t
            planes = ctx.planes_at(t)
            motion = WallMotion.of_planes(planes.count, [(g.planes, g.motion.pose(t)) for g in self.groups])
            src = self.mirror.generate(fluid, st.kind, ctx.params, walls=PlaneGroup(planes.normals, planes.offsets),
                                       motion=motion)
            if self.tank is None:  # several groups: each one's load from the images' pair forces
                self._pair_loads(ctx, fluid, src, planes, t)
        stats = ctx.stats(self)  # in the summary and the checkpoint: cumulative across restarts
        stats["ghosts_max"] = max(stats.get("ghosts_max", 0), src.n)
        stats["ghosts_last"] = src.n
        return src

    @hookimpl
    def sph_after_integrate(self, ctx, pos0, pos, vel, acc, dt):
        """The moving walls' load over the step: a tank's from the fluid's momentum balance
        (:func:`sphcore.api.tank_load`: exact, every wall is the tank's), each group's of
        several from the loads the images gave at the step's start (:mod:`.loads`); times
        dt to ``ctx.add_wall_load``."""
        if not self.groups or acc is None:
            return
        import numpy as np

        if self.tank is None:  # several groups: the loads of the evaluation the step started from
            dim = ctx.params.dim
            for name, row in ctx.kept(self).get("loads", {}).items():
                ctx.add_wall_load(name, np.asarray(row[:dim]) * dt, np.asarray(row[dim:]) * dt)
            return

        force, moment = tank_load(ctx, self.tank, pos0, acc)
        ctx.add_wall_load(self.tank.name, force * dt, moment * dt)

    def _pair_loads(self, ctx, fluid, src, planes, t):
        """Each plane group's load from the images' pair forces (:mod:`.loads`), kept for the
        step (and across a restart)."""
        import numpy as np

        from .loads import group_loads

        prm = ctx.params
        owner = np.full(planes.count, -1, np.int64)
        origins = np.zeros((len(self.groups), 3))
        for k, g in enumerate(self.groups):
            owner[g.planes] = k
            pose = g.motion.pose(t)
            origins[k, :prm.dim] = pose.centre + pose.shift
        out = np.zeros((len(self.groups), 6))
        group_loads(fluid.pos, fluid.rho, fluid.p, fluid.m, src.pos, src.rho, src.p, src.m,
                    np.ascontiguousarray(planes.normals), np.ascontiguousarray(planes.offsets), owner, origins,
                    prm.kernel_id, prm.h, out)
        ctx.kept(self)["loads"] = {g.name: [float(v) for v in out[k, :prm.dim]] + [float(v) for v in out[k, 3:]]
                                   for k, g in enumerate(self.groups)}

    @hookimpl
    def sph_summary(self, ctx):
        m = self.mirror
        return {"ghost_reallocations": m.reallocations if m else 0}
