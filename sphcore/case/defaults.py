"""Every core case key, its default, unit and meaning: the one place defaults live.

A ``case.toml`` holds only overrides of these. Plugins declare their own tables
through the ``sph_options`` hook (see :mod:`sphcore.plugin.hookspecs`).
"""

from __future__ import annotations

from sphcore.case.options import Option as O

CORE: dict[str, dict[str, O]] = {
    "case": {
        "name": O("", "str", doc="a label for outputs; the directory name when empty"),
        "dim": O(2, "int", doc="spatial dimension", choices=(), extra={"max": 3}, min=2),
        "description": O("", "str", doc="free text, copied into output metadata"),
    },
    "domain": {
        "min": O(None, "vector", "m", "lower corner of an axis-aligned box of wall planes (optional)", nullable=True),
        "max": O(None, "vector", "m", "upper corner of that box", nullable=True),
        "planes": O([], "table_list", doc="extra wall planes: {normal = [...], point = [...]}; the normal points into the fluid"),
        "walls": O([], "table_list", doc="finite walls: boxes, polygons, polylines and mesh files (keys: WALL); "
                   "obstacles inside the planes' region, or a closed tank of their own"),
        "motion": O([], "table_list", doc="prescribed motion of the tank (every plane without a motion of its own, "
                    "and the walls with tank = true): parts that add up (keys: sphcore.case.motion.PART); none: the "
                    "tank is fixed"),
    },
    # [[bodies]] is an array of tables; each entry is checked against BODY below.
    "bodies": O([], "table_list", doc="floating bodies: finite walls moved by the fluid's loads, gravity and "
                "springs (keys: BODY)"),
    # [[blocks]] is an array of tables; each entry is checked against BLOCK below.
    "blocks": O([], "table_list", doc="particle blocks filled on a lattice of spacing dx"),
    "particles": {
        "dx": O(0.01, "float", "m", "initial particle spacing", positive=True),
        "radius": O(None, "float", "m", "particle radius for wall contact; dx/2 when unset", positive=True, nullable=True),
        "memory_limit_gib": O(None, "float", "GiB", "refuse a case whose estimated memory exceeds this; the "
                              "machine's available memory when unset", positive=True, nullable=True),
    },
    "fluid": {
        "rho0": O(1000.0, "float", "kg/m^3", "reference density, up to 1e6", positive=True, extra={"max": 1e6}),
        "nu": O(0.0, "float", "m^2/s", "kinematic viscosity (laminar term, Morris 1997); 0 switches it off", min=0.0),
    },
    "physics": {
        "sph": O(True, "bool", doc="compute SPH forces and density; false: free particles + plugins only"),
        "gravity": O([0.0, -9.81, 0.0], "vector", "m/s^2", "body acceleration; first dim components are used"),
        "hydrostatic_init": O(True, "bool", doc="start each fluid block at rest in hydrostatic equilibrium below its "
                              "top: exact Tait pressure and density, masses scaled by rho / rho0"),
        "modified_pressure": O(False, "bool", doc="Batchelor's modified pressure: the EOS gives P = p - p_hydrostatic, "
                               "gravity acts as buoyancy g (1 - rho0/rho); for fluid at rest in a container"),
    },
    "relax": {
        "time": O(0.0, "float", "s", "settle the start before t = 0: this long of the case's own dynamics with damped "
                  "velocities (dynamic relaxation, sphcore/run/relax.py), for water at rest in its container; 0 is off",
                  min=0.0),
        "damping_time": O(0.3, "float", "s", "velocities decay as exp(-t / damping_time) while relaxing; "
                          "about the period of the slowest motion to settle over 2 pi", positive=True),
        "jitter": O(1e-3, "float", doc="random start velocities moving the particles by about this many dx "
                    "(seeded), to leave a symmetric but unstable arrangement such as the square lattice", min=0.0),
    },
    "corrections": {
        "kernel_gradient": O(False, "bool", doc="Bonet & Lok (1999) corrected kernel gradient, symmetrised "
                             "(L_i + L_j)/2, restores first-order consistency near walls and the free surface"),
        "shepard_every": O(0, "int", doc="reinitialise density with a Shepard filter every N steps (Chen et al. 1999 "
                           "CSPH zeroth-order density correction); 0 is off", min=0),
    },
    "kernel": {
        "name": O("wendland_c2", "str", doc="smoothing kernel", choices=("wendland_c2", "cubic_spline")),
        "h_over_dx": O(1.3, "float", doc="smoothing length h in units of dx (support radius 2h); from 0.5 "
                       "(the support reaches the nearest neighbour) to 5", positive=True, min=0.5, extra={"max": 5.0}),
    },
    "eos": {
        "c0": O(None, "float", "m/s", "reference sound speed, up to 1e6; derived from c0_factor when unset", positive=True,
                nullable=True, extra={"max": 1e6}),
        "c0_factor": O(10.0, "float", doc="c0 = c0_factor * sqrt(2 g H), H the fluid height (Monaghan 1994); up to 1e4",
                       positive=True, extra={"max": 1e4}),
        "gamma": O(7.0, "float", doc="Tait exponent, up to 100", positive=True, extra={"max": 100.0}),
        "p_background": O(0.0, "float", "Pa", "constant added to the Tait pressure", min=None),
    },
    "viscosity": {
        "alpha": O(0.1, "float", doc="Monaghan artificial viscosity, linear term, 0 to 10", min=0.0, extra={"max": 10.0}),
        "beta": O(0.0, "float", doc="Monaghan artificial viscosity, quadratic term, 0 to 10", min=0.0, extra={"max": 10.0}),
    },
    "density_diffusion": {
        "delta": O(0.0, "float", doc="Molteni & Colagrossi (2009) density diffusion coefficient, 0 to 1; 0 is off",
                   min=0.0, extra={"max": 1.0}),
        "hydrostatic": O(False, "bool", doc="diffuse only the departure from the hydrostatic density "
                         "stratification (Fourtakas et al. 2019), so that water at rest is not disturbed"),
    },
    "integrator": {
        "scheme": O("leapfrog", "str", doc="time integration of the weakly compressible scheme",
                    choices=("leapfrog", "euler")),
    },
    "scheme": {
        "name": O("wcsph", "str", doc="wcsph: weakly compressible (pressure from the density, step from an artificial "
                  "sound speed); dfsph: divergence-free incompressible (pressure from two solves a step, step from the "
                  "flow's velocity; docs/explanation/incompressible_scheme.md)", choices=("wcsph", "dfsph")),
        "cfl": O(0.3, "float", positive=True, doc="dfsph: dt <= cfl * h / |v|max (the flow's Courant number)"),
        "force_factor": O(0.1, "float", positive=True,
                          doc="dfsph: dt <= force_factor * sqrt(h / |a|max), a the non-pressure acceleration (water at "
                              "rest in cases/hydrostatic_tank is unstable with 0.25, time.force_factor's default)"),
        "density_tolerance": O(1e-4, "float", positive=True,
                               doc="dfsph: the density solve stops when the mean |rho* - rho0| / rho0 is below this"),
        "divergence_tolerance": O(1e-3, "float", positive=True,
                                  doc="dfsph: the divergence solve stops when the mean dt |D rho / Dt| / rho0 is below this"),
        "error": O("both", "str", choices=("both", "compression"),
                   doc="dfsph: what a solve's mean error counts: both, compression and expansion (|rho* - rho0|, a free "
                       "surface's expansion left out); compression, max(rho* - rho0, 0) only, as SPlisHSPlasH counts it "
                       "(at the same tolerance its solves stop sooner: docs/explanation/incompressible_scheme.md)"),
        "max_iterations": O(500, "int", positive=True,
                            doc="dfsph: a solve that has not converged after this many iterations stops the run (the "
                                "first step's, from the hydrostatic start, needs the most: 86 in the 2D dam break)"),
    },
    "time": {
        "t_end": O(1.0, "float", "s", "simulated time", positive=True),
        "dt": O(None, "float", "s", "fixed time step; adaptive (CFL) when unset", positive=True, nullable=True),
        "cfl": O(0.3, "float", positive=True,
                 doc="acoustic Courant number for the adaptive step (docs/explanation/time_integration.md: 0.45 is still stable for the "
                     "dam breaks, 0.4 is not for a ghost tank at rest)"),
        "force_factor": O(0.25, "float", doc="dt <= force_factor * sqrt(h / |a|max)", positive=True),
        "viscous_factor": O(0.125, "float", doc="dt <= viscous_factor * h^2 / nu", positive=True),
        "dt_max": O(None, "float", "s", "upper bound on the adaptive step", positive=True, nullable=True),
        "max_steps": O(100_000_000, "int", doc="refuse a case whose first step predicts more steps than this to "
                       "reach t_end (a time step too small to finish)", positive=True),
    },
    "checks": {
        "rho_min": O(0.5, "float", doc="stop when a density falls below rho_min * rho0", positive=True),
        "rho_max": O(1.5, "float", doc="stop when a density exceeds rho_max * rho0", positive=True),
        "every": O(1, "int", doc="check for NaN and density bounds every N steps (energy every 10 N)", positive=True),
        "energy_growth": O(0.01, "float", doc="stop when kinetic + potential + internal energy exceeds its start "
                           "by this fraction of M |g| H + the start's kinetic energy (walls with CR <= 1 and "
                           "viscosity only remove energy, so growth is a numerical instability); 0 is off; not checked when a "
                           "plugin adds accelerations (it may do work)", min=0.0),
    },
    "neighbours": {
        "sort_every": O(10, "int", doc="reorder particles by cell every N steps (memory locality; with a kept "
                        "pair list only if it was rebuilt since the last reorder)", positive=True),
        "skin": O(0.2, "float", doc="keep each particle's pair candidates within (1 + skin) 2h and reuse them until "
                  "a particle has moved skin h (Verlet lists; the same pairs, fewer searches); 0: search "
                  "the cells at every force evaluation; dfsph keeps no Verlet list (it lists its pairs every step)", min=0.0),
    },
    "parallel": {
        "threads": O(0, "int", doc="most threads to use; 0: as many as numba uses when the run starts "
                     "(NUMBA_NUM_THREADS, all cores by default)", min=0),
        "adapt": O(True, "bool", doc="time the steps with all, half and one of those threads now and then and "
                   "use the fastest (a shared machine can make more threads slower); the results are the "
                   "same bits for any thread count"),
    },
    "plugins": {
        "use": O([], "str_list", doc="plugins to load, by entry-point name (e.g. reflective, ghost, vtu)"),
    },
    "output": {
        "dir": O("output", "str", doc="output directory, a sub-directory of the case directory (elsewhere: sph run --output)"),
        "progress": O("auto", "str", doc="progress display", choices=("auto", "bar", "log", "off")),
        "log_interval_s": O(10.0, "float", "s", "wall time between progress lines when not on a terminal", positive=True),
        "checkpoint_every_s": O(300.0, "float", "s", "wall time between periodic checkpoints (checkpoint.npz, "
                                "replaced atomically); 0 is off", min=0.0),
        "checkpoint_every_dt": O(None, "float", "s", "simulated time between periodic checkpoints, as well as "
                                 "checkpoint_every_s; off when unset", positive=True, nullable=True),
    },
}

#: keys of one ``[[blocks]]`` entry
BLOCK: dict[str, O] = {
    "min": O(None, "vector", "m", "lower corner of the block (required)", nullable=True),
    "max": O(None, "vector", "m", "upper corner; particle centres at min + (i + 1/2) dx inside [min, max]", nullable=True),
    "count": O(None, "list", doc="particles per axis instead of max (e.g. [36, 71])", nullable=True),
    "velocity": O(None, "vector", "m/s", "initial velocity; zero when unset", nullable=True),
    "kind": O("fluid", "str", doc="fluid (SPH) or sphere (rigid, only moved by integration)", choices=("fluid", "sphere")),
    "clip": O(False, "bool", doc="true: leave out the lattice's particles beyond a wall plane (water over a "
              "sloping beach); false: such a particle is an error naming the block"),
}

#: keys of one ``[[domain.walls]]`` entry
WALL: dict[str, O] = {
    "shape": O(None, "str", doc="box, polygon (2D), polyline (an open thin wall) or mesh (a file)",
               choices=("box", "polygon", "polyline", "mesh"), nullable=True),
    "min": O(None, "vector", "m", "box: lower corner", nullable=True),
    "max": O(None, "vector", "m", "box: upper corner", nullable=True),
    "points": O(None, "list", "m", "polygon, polyline: the vertices in order ([[x, y], ...])", nullable=True),
    "file": O(None, "str", doc="mesh: a file meshio reads (STL, OBJ, VTU/VTK, PLY), relative to the case "
              "directory; 3D: triangles or polygons, 2D: lines or a triangulated region", nullable=True),
    "fluid": O("outside", "str", doc="closed walls: where the fluid is: outside (an obstacle) or inside "
               "(the walls are the tank)", choices=("outside", "inside")),
    "tank": O(False, "bool", doc="the wall moves with the tank ([[domain.motion]])"),
    "motion": O([], "table_list", doc="prescribed motion of this wall alone: parts that add up (keys: "
                "sphcore.case.motion.PART); none: fixed (or moving with the tank)"),
}

#: keys of one ``[[bodies]]`` entry: a closed finite wall that the fluid moves
BODY: dict[str, O] = {
    "wall": O(None, "int", doc="index of the closed [[domain.walls]] entry (box, polygon or mesh) that is the "
              "body's surface (required)", min=0, nullable=True),
    "density": O(None, "float", "kg/m^3", "uniform density of the body (or give mass)", positive=True, nullable=True),
    "mass": O(None, "float", "kg", "the body's mass (2D: per metre of span), the density then uniform",
              positive=True, nullable=True),
    "velocity": O(None, "vector", "m/s", "initial velocity of the centre of mass; zero when unset", nullable=True),
    "orientation": O(None, "vector", "deg", "turns the wall about its centre of mass before the run (2D: [angle], "
                     "counter-clockwise; 3D: a rotation vector, its direction the axis, its length the angle): "
                     "a heeled box; the body's rotation is measured from there", nullable=True),
    "angular_velocity": O(None, "vector", "rad/s", "initial angular velocity (2D: [wz]; 3D: [wx, wy, wz]); "
                          "zero when unset", nullable=True),
    "free": O(None, "str_list", doc="the world axes the centre of mass may move along, e.g. [\"y\"] (heave only "
              "in 2D); all when unset", nullable=True),
    "rotation": O("free", "str", doc="free, fixed (translation only) or hinge (turns about hinge_axis through "
                  "hinge_point, nothing else)", choices=("free", "fixed", "hinge")),
    "hinge_point": O(None, "vector", "m", "hinge: a point of the hinge's axis", nullable=True),
    "hinge_axis": O(None, "vector", doc="hinge in 3D: the axis' direction (2D: about z)", nullable=True),
    "release": O(0.0, "float", "s", "the body is held where case.toml draws it until this time (the water settles "
                 "round it), then the loads move it", min=0.0),
    "restitution": O(0.5, "float", doc="coefficient of restitution of the body's contacts with the fixed walls "
                     "and the other bodies (0: plastic, 1: elastic)", min=0.0, extra={"max": 1.0}),
    "springs": O([], "table_list", doc="linear springs and dashpots to fixed anchors, a simple mooring (keys: "
                 "SPRING)"),
}

#: keys of one ``[[bodies.springs]]`` entry
SPRING: dict[str, O] = {
    "anchor": O(None, "vector", "m", "the fixed end (required)", nullable=True),
    "attach": O(None, "vector", "m", "the body's end, a point of the body where case.toml draws it; the centre of "
                "mass when unset", nullable=True),
    "stiffness": O(None, "float", "N/m", "spring constant (2D: N/m per metre of span) (required)", min=0.0,
                   nullable=True),
    "damping": O(0.0, "float", "N s/m", "dashpot constant along the spring", min=0.0),
    "rest_length": O(0.0, "float", "m", "length of the unloaded spring", min=0.0),
}

#: keys of one ``[[domain.planes]]`` entry
PLANE: dict[str, O] = {
    "normal": O(None, "vector", doc="normal pointing into the domain (normalised on load)", nullable=True),
    "point": O(None, "vector", "m", "a point on the plane", nullable=True),
    "motion": O([], "table_list", doc="prescribed motion of this plane alone (a piston wave maker): parts that "
                "add up (keys: sphcore.case.motion.PART); none: the plane is the tank's"),
}

