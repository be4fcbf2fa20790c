"""Python entries to the reflective kernel and the clearance checks: what the plugin, the
tests and the benchmarks call with plain arrays (:func:`reflect_particles`, :func:`outside`,
:func:`clearance`, :func:`face_arrays`), converting and checking the arguments the
kernel (:func:`.collision.reflect_step`) takes as records.
"""

from __future__ import annotations

import numba
import numpy as np

from sphcore.api import build_grid, by_size, particle_distance

from .collision import CELL_RADII, Paths, Response, Tally, WallGroup, contact_limit, reflect_step
from .corner import scratch
from .facecontact import FaceSet, empty_grid


@by_size
def min_clearance(pos, radius, normals, offsets):
    """(n,) min over planes of d - r (m), with the kernel's own arithmetic for d."""
    n, dim = pos.shape
    out = np.empty(n)
    for i in numba.prange(n):
        c = np.inf
        for k in range(normals.shape[0]):
            c = min(c, particle_distance(normals, offsets, k, pos, i) - radius[i])
        out[i] = c
    return out


@by_size
def outside_mask(pos, radius, normals, offsets):
    """(n,) bool: True where some plane has d < r - tol, exactly the kernel's collision test."""
    n, dim = pos.shape
    out = np.zeros(n, np.bool_)
    for i in numba.prange(n):
        lim = contact_limit(radius[i])
        for k in range(normals.shape[0]):
            if particle_distance(normals, offsets, k, pos, i) < lim:
                out[i] = True
    return out


def _plane_arrays(planes, dim=None):
    """(normals, offsets) as C-contiguous float64 from a Planes or a (normals, offsets) pair
    (None: no planes, the walls are faces only)."""
    if planes is None:
        normals, offsets = np.zeros((0, dim)), np.zeros(0)
    elif hasattr(planes, "normals"):
        normals, offsets = planes.normals, planes.offsets
    else:
        normals, offsets = planes
    return (np.ascontiguousarray(normals, dtype=np.float64),
            np.ascontiguousarray(offsets, dtype=np.float64).reshape(-1))


def _inout(name, a, shape):
    """Arrays changed in place must not be silently copied by a conversion."""
    if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.c_contiguous
            and a.flags.writeable and a.shape == shape):
        raise ValueError(f"{name} must be a writeable C-contiguous float64 array of shape {shape}")
    return a


def face_arrays(faces, dim, radius):
    """The :class:`.facecontact.FaceSet` of ``faces`` (a :class:`sphcore.geometry.faces.Faces`
    or None), the grid's cells CELL_RADII radii wide (``radius`` in m)."""
    if faces is None or faces.count == 0:
        return empty_grid(dim)
    grid = build_grid(faces.verts, CELL_RADII * float(radius))
    return FaceSet(np.ascontiguousarray(faces.verts, dtype=np.float64), *grid.arrays())


def reflect_particles(pos0, pos, vel, acc, radius, planes, cr=1.0, max_reflections=1000,
                      velocity_at_contact=True, guarded_flags=None, reflection_counts=None,
                      faces=None):
    """Python entry to :func:`reflect_step`: checks and converts arguments, returns the guard count.

    pos (m) and vel (m/s), (n, dim) writeable C-contiguous float64, are changed in place.
    pos0 (m) and acc (m/s^2, None for zero) are converted as needed; radius is a scalar
    or (n,) (m); planes a :class:`sphcore.geometry.planes.Planes` or ``(normals, offsets)``;
    faces a :class:`sphcore.geometry.faces.Faces` (finite walls) or None.
    guarded_flags ((n,) int8) and reflection_counts ((n,) int32), when given, receive the
    per-particle guard flags and reflection counts.
    """
    n, dim = np.shape(pos)
    pos = _inout("pos", pos, (n, dim))
    vel = _inout("vel", vel, (n, dim))
    # the read-only inputs as writeable C arrays, as a run passes them: numba compiles the
    # kernel once per array type, and a read-only array is another type (two more builds
    # of the kernel, 12 s, in the test suite)
    pos0 = np.require(pos0, np.float64, ["C", "W"])
    acc = np.zeros((n, dim)) if acc is None else np.require(acc, np.float64, ["C", "W"])
    if pos0.shape != (n, dim) or acc.shape != (n, dim):
        raise ValueError(f"pos0 and acc must have shape {(n, dim)}")
    radius = np.require(np.broadcast_to(np.asarray(radius, np.float64), (n,)), np.float64, ["C", "W"])
    normals, offsets = _plane_arrays(planes, dim)
    if normals.shape[1:] != (dim,) or offsets.shape != (normals.shape[0],):
        raise ValueError(f"planes must have normals (k, {dim}) and offsets (k,)")
    if not 0.0 <= cr <= 1.0:
        raise ValueError(f"cr must lie in [0, 1], got {cr!r}")
    if guarded_flags is None:
        guarded_flags = np.empty(n, np.int8)
    if reflection_counts is None:
        reflection_counts = np.empty(n, np.int32)
    if guarded_flags.dtype != np.int8 or guarded_flags.shape != (n,):
        raise ValueError(f"guarded_flags must be int8 of shape {(n,)}")
    if reflection_counts.dtype != np.int32 or reflection_counts.shape != (n,):
        raise ValueError(f"reflection_counts must be int32 of shape {(n,)}")
    walls = WallGroup.of(normals, offsets, face_arrays(faces, dim, radius.max() if n else 1.0))
    response = Response(float(cr), int(max_reflections), bool(velocity_at_contact))
    return int(reflect_step(Paths(pos0, pos, vel, acc, radius), walls, response,
                            Tally(guarded_flags, reflection_counts), scratch())[0])


def clearance(pos, radius, planes):
    """(n,) min over planes of d - r (m) for particles ``pos`` of ``radius`` (scalar or (n,))."""
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    radius = np.ascontiguousarray(np.broadcast_to(np.asarray(radius, np.float64), (pos.shape[0],)))
    normals, offsets = _plane_arrays(planes)
    return min_clearance(pos, radius, normals, offsets)


def outside(pos, radius, planes):
    """(n,) bool: particles ``pos`` of ``radius`` (scalar or (n,)) beyond a wall (d < r - tol)."""
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    radius = np.ascontiguousarray(np.broadcast_to(np.asarray(radius, np.float64), (pos.shape[0],)))
    normals, offsets = _plane_arrays(planes)
    return outside_mask(pos, radius, normals, offsets)
