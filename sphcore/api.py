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
  :func:`particle_distance`, :func:`normal_parts`; finite walls :class:`Faces` (``ctx.case.faces``) with their
  :class:`FaceGrid` (:func:`build_grid`), and for numba kernels :func:`nearest_point` (and
  :func:`nearest_feature`, which also says which part of the face holds it),
  :func:`box_cells`,
  :func:`face_distance`, :func:`first_contact` (swept sphere), :func:`cell_span`;
  :func:`outline` (the faces of the region planes enclose, for drawing); walls that move:
  :class:`MovingGroup` (``ctx.case.moving``), its :class:`Motion` and :class:`Pose`, and
  :func:`rotation_vector` (a rotation matrix's axis times angle);
- neighbours and kernels for numba kernels: :class:`CellGrid` (its ``.view`` is a
  :class:`Grid`), :func:`cell_of`, :func:`cell_range` (the one neighbour walk),
  :func:`kernel_w`, :func:`kernel_f`, :data:`SUPPORT`, the kernel ids;
- :class:`by_size` (a prange kernel compiled serial and parallel, run parallel only where
  it pays) and :func:`on_threads_by_size` (a kernel with one prange loop, run on one thread where
  a launch on several would cost more than the work);
- the equation of state: :mod:`sphcore.physics.eos` as :data:`eos`;
- output: :class:`ScheduledWriter` (base of a writer plugin: schedule, restart, write errors),
  :func:`check_series`, :func:`leading_complete`, :func:`new_record`, :func:`record_frame` (what a
  restart checks a series file against),
  :class:`Schedule`, :func:`write_atomically` (a file replaced whole or not at all),
  :func:`mark_written` (a file written by other means is sph's: ``--overwrite`` deletes it).

Hook specifications: :mod:`sphcore.plugin.hookspecs`. A plugin template: ``examples/plugin_template``.
"""

from __future__ import annotations

from sphcore.case.options import Option, validate_table
from sphcore.errors import CaseError, Instability, OutputError
from sphcore.geometry.facegeom import face_distance, first_contact, nearest_feature, nearest_point
from sphcore.geometry.facegrid import FaceGrid, box_cells, build_grid, cell_span
from sphcore.geometry.faces import Faces
from sphcore.geometry.motion import Motion, MovingGroup, Pose, plane_groups, planes_at
from sphcore.geometry.planes import Planes, normal_parts, outline, particle_distance, plane_distance
from sphcore.io.atomic import mark_written, write_atomically
from sphcore.io.schedule import Schedule, schedule_options
from sphcore.io.writer import ScheduledWriter, check_series, leading_complete, new_record, record_frame
from sphcore.jit.parallel import by_size, on_threads_by_size
from sphcore.neighbours.cellgrid import CellGrid, Grid, cell_of, cell_range
from sphcore.physics import eos
from sphcore.physics.loads import impulse_load, tank_load
from sphcore.physics.equations import WallTerms
from sphcore.physics.kernels import CUBIC_SPLINE, KERNEL_IDS, SUPPORT, WENDLAND_C2, kernel_f, kernel_w
from sphcore.physics.params import Params
from sphcore.physics.particles import FLUID, GHOST, SPHERE, Fields, ParticleState, Sources
from sphcore.physics.rigid import rotation_vector
from sphcore.plugin.context import RunContext
from sphcore.plugin.hookspecs import hookimpl

__all__ = [
    "hookimpl", "Option", "CaseError", "Instability", "OutputError",
    "RunContext", "Params", "ParticleState", "Sources", "Fields", "WallTerms", "FLUID", "SPHERE", "GHOST",
    "Planes", "plane_distance", "particle_distance", "normal_parts", "outline", "Motion", "MovingGroup", "Pose", "plane_groups", "planes_at", "tank_load", "impulse_load",
    "rotation_vector",
    "Faces", "FaceGrid", "build_grid", "cell_span", "box_cells", "nearest_point", "nearest_feature", "face_distance",
    "first_contact",
    "CellGrid", "Grid", "cell_of", "cell_range", "kernel_w", "kernel_f", "SUPPORT",
    "KERNEL_IDS", "CUBIC_SPLINE", "WENDLAND_C2", "validate_table",
    "eos", "ScheduledWriter", "check_series", "leading_complete", "new_record", "record_frame", "Schedule", "schedule_options", "write_atomically", "mark_written", "by_size", "on_threads_by_size",
]
