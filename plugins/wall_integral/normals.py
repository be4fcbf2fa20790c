"""The projector onto the normals of the walls near each particle (``WallTerms.normals``).

It tells the core in which directions a particle's missing kernel support is wall (to be
completed with the wall pressure) rather than free surface (left empty): n n^T within 2h of
one plane, the identity where planes of independent normals meet (corners, edges).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from sphcore.api import particle_distance

TOL = 1e-6  # a normal within this (squared) of the span already held adds no direction


@njit(cache=True, inline="always")
def add_direction(basis, count, dim, v0, v1, v2):
    """Gram-Schmidt: add (v0, v1, v2) to the orthonormal basis (a 9-tuple of three rows, the
    first ``count`` in use); returns (basis, count). Tuples, so no allocation per particle."""
    for b in range(count):
        e0, e1, e2 = basis[3 * b], basis[3 * b + 1], basis[3 * b + 2]
        c = v0 * e0 + v1 * e1 + v2 * e2
        v0 -= c * e0
        v1 -= c * e1
        v2 -= c * e2
    nn = v0 * v0 + v1 * v1 + v2 * v2
    if nn <= TOL or count >= dim:
        return basis, count
    r = 1.0 / np.sqrt(nn)
    if count == 0:
        basis = (v0 * r, v1 * r, v2 * r, basis[3], basis[4], basis[5], basis[6], basis[7], basis[8])
    elif count == 1:
        basis = (basis[0], basis[1], basis[2], v0 * r, v1 * r, v2 * r, basis[6], basis[7], basis[8])
    else:
        basis = (basis[0], basis[1], basis[2], basis[3], basis[4], basis[5], v0 * r, v1 * r, v2 * r)
    return basis, count + 1


@njit(cache=True, inline="always")
def project_one(i, pos, normals, offsets, support, q):
    """q[i] (dim, dim) <- projector onto span(q[i], normals of the planes with d < support);
    q[i] stays as it is for a particle farther than ``support`` from every plane."""
    dim = pos.shape[1]
    near = False
    for k in range(normals.shape[0]):
        near = near or particle_distance(normals, offsets, k, pos, i) < support
    if not near:
        return
    basis = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    count = 0
    for a in range(dim):  # what another wall plugin put there: its columns span its walls
        basis, count = add_direction(basis, count, dim, q[i, 0, a], q[i, 1, a],
                                      q[i, 2, a] if dim == 3 else 0.0)
    for k in range(normals.shape[0]):
        if particle_distance(normals, offsets, k, pos, i) < support:
            basis, count = add_direction(basis, count, dim, normals[k, 0], normals[k, 1],
                                          normals[k, 2] if dim == 3 else 0.0)
    set_projector(q[i], dim, basis, count)


@njit(cache=True, inline="always")
def set_projector(qi, dim, basis, count):
    """qi (dim, dim) <- the projector onto the span of the first ``count`` rows of ``basis``
    (orthonormal rows of 3, from :func:`add_direction`)."""
    for a in range(dim):
        for b in range(dim):
            acc = 0.0
            for c in range(count):
                acc += basis[3 * c + a] * basis[3 * c + b]
            qi[a, b] = acc
