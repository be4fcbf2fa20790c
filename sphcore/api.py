"""Everything a plugin needs, from one module: ``from sphcore.api import ...``.

- declaring: :data:`hookimpl` (mark hook implementations), :class:`Option` (declare a case
  table's keys in ``sph_options``), :func:`validate_table` (validate a nested table);
- errors: :class:`CaseError` (bad input: file, key, what was expected; exit 2),
  :class:`Instability` (stop the run: exit 1, last good output kept), :class:`OutputError`;
- the run: :class:`RunContext` (what every hook receives as ``ctx``; its docstring lists
  every attribute), :class:`Params` (the run's constants), :class:`ParticleState`,
  :class:`Sources` (neighbour-only particles for ``sph_extra_sources``),
  :class:`WallTerms` (the per-particle boundary terms of ``sph_wall_terms``), particle kinds
  :data:`FLUID`, :data:`SPHERE`, :data:`GHOST`;
- geometry: :class:`Planes`, and for numba kernels :func:`plane_distance`,
  :func:`particle_distance`; finite walls :class:`Faces` (``ctx.case.faces``) with their
  :class:`FaceGrid` (:func:`build_grid`), and for numba kernels :func:`nearest_point`,
  :func:`box_cells`,
  :func:`face_distance`, :func:`first_contact` (swept sphere), :func:`cell_span`;
- neighbours and kernels for numba kernels: :class:`CellGrid` (its ``.view`` is a
  :class:`Grid`), :func:`cell_of`, :func:`cell_range` (the one neighbour walk),
  :func:`kernel_w`, :func:`kernel_f`, :data:`SUPPORT`, the kernel ids;
- :class:`by_size` (a prange kernel compiled serial and parallel, run parallel only where
  it pays) and :func:`on_threads_by_size` (a kernel with one prange loop, run on one thread where
  a launch on several would cost more than the work);
- the equation of state: :mod:`sphcore.eos` as :data:`eos`;
- output: :class:`ScheduledWriter` (base of a writer plugin: schedule, restart, write errors),
  :class:`Schedule`, :func:`write_atomically` (a file replaced whole or not at all).

Hook specifications: :mod:`sphcore.hookspecs`. A plugin template: ``examples/plugin_template``.
"""

from __future__ import annotations

from . import eos
from .context import RunContext
from .equations import Fields, WallTerms
from .errors import CaseError, Instability, OutputError
from .facegeom import face_distance, first_contact, nearest_point
from .facegrid import FaceGrid, box_cells, build_grid, cell_span
from .faces import Faces
from .geometry import Planes, particle_distance, plane_distance
from .hookspecs import hookimpl
from .kernels import CUBIC_SPLINE, KERNEL_IDS, SUPPORT, WENDLAND_C2, kernel_f, kernel_w
from .neighbours import CellGrid, Grid, cell_of, cell_range
from .options import Option, validate_table
from .outdir import write_atomically
from .parallel import by_size, on_threads_by_size
from .params import Params
from .particles import FLUID, GHOST, SPHERE, ParticleState, Sources
from .schedule import Schedule, schedule_options
from .writer import ScheduledWriter

__all__ = [
    "hookimpl", "Option", "CaseError", "Instability", "OutputError",
    "RunContext", "Params", "ParticleState", "Sources", "Fields", "WallTerms", "FLUID", "SPHERE", "GHOST",
    "Planes", "plane_distance", "particle_distance",
    "Faces", "FaceGrid", "build_grid", "cell_span", "box_cells", "nearest_point", "face_distance", "first_contact",
    "CellGrid", "Grid", "cell_of", "cell_range", "kernel_w", "kernel_f", "SUPPORT",
    "KERNEL_IDS", "CUBIC_SPLINE", "WENDLAND_C2", "validate_table",
    "eos", "ScheduledWriter", "Schedule", "schedule_options", "write_atomically", "by_size", "on_threads_by_size",
]
