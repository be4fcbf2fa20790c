"""Particle state as a struct of contiguous float64 arrays, and lattice blocks."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np

FLUID, SPHERE, GHOST = 0, 1, 2


@dataclass
class ParticleState:
    """All integrated particles. Arrays share their first axis (the particle index).

    pos, vel: (n, dim) in m and m/s; rho (kg/m^3), p (Pa), m (kg), radius (m): (n,);
    kind: int8 code (FLUID, SPHERE); id: int64, stable across reordering.
    """

    pos: np.ndarray
    vel: np.ndarray
    rho: np.ndarray
    p: np.ndarray
    m: np.ndarray
    radius: np.ndarray
    kind: np.ndarray
    id: np.ndarray
    #: particles of the blocks not created because a finite wall covers them or, in a block
    #: with ``clip``, they lie beyond a wall plane (not a field:
    #: no array, not saved; set by the filling)
    removed_by_walls = 0

    @property
    def n(self) -> int:
        return self.pos.shape[0]

    @property
    def dim(self) -> int:
        return self.pos.shape[1]

    def arrays(self):
        return [(f.name, getattr(self, f.name)) for f in fields(self)]

    def permute(self, order: np.ndarray) -> None:
        """Reorder every array by ``order`` (a permutation of 0..n-1): each array is gathered
        into a spare of its shape, which then replaces it, and the replaced one becomes the
        spare for the next reorder (no allocation once the spares exist)."""
        spares = self.__dict__.setdefault("_spares", {})
        for name, a in self.arrays():
            spare = spares.get(name)
            if spare is None or spare.shape != a.shape or spare.dtype != a.dtype:
                spare = np.empty_like(a)
            np.take(a, order, axis=0, out=spare, mode="clip")  # "raise" would buffer: allocate
            setattr(self, name, spare)
            spares[name] = a

    def append(self, other: "ParticleState") -> None:
        """Add particles (e.g. from a plugin's set-up); ids continue after the largest."""
        other.id = other.id + (self.id.max() + 1 if self.n else 0)
        for name, a in self.arrays():
            setattr(self, name, np.ascontiguousarray(np.concatenate([a, getattr(other, name)])))

    def copy(self) -> "ParticleState":
        return ParticleState(**{name: a.copy() for name, a in self.arrays()})

    @classmethod
    def empty(cls, dim: int) -> "ParticleState":
        z = np.zeros(0)
        return cls(np.zeros((0, dim)), np.zeros((0, dim)), z, z.copy(), z.copy(), z.copy(),
                   np.zeros(0, np.int8), np.zeros(0, np.int64))


class Fields(NamedTuple):
    """The fields the pair sums read of source particles: pos, vel (n, dim) in m and m/s;
    rho (kg/m^3), p (Pa, the pressure the momentum equation uses), m (kg): (n,). One force
    evaluation's sources are the fluid first, then what plugins add; a named tuple, so that
    it is one argument to a numba kernel."""

    pos: np.ndarray
    vel: np.ndarray
    rho: np.ndarray
    p: np.ndarray
    m: np.ndarray

    @property
    def n(self) -> int:
        return self.pos.shape[0]


#: neighbour-only particles a plugin adds to a force evaluation (``sph_extra_sources``, e.g.
#: ghosts): the same five fields
Sources = Fields


def lattice(lo, hi, dx: float, count=None) -> np.ndarray:
    """Centres of a block filled on a square lattice of spacing dx (m).

    Centres sit at ``lo + (i + 1/2) dx``; along each axis there are ``count[k]`` of them,
    or ``round((hi - lo) / dx)`` when no count is given.
    """
    lo = np.asarray(lo, float)
    if count is None:
        count = np.rint((np.asarray(hi, float) - lo) / dx).astype(int)
    axes = [lo[k] + (np.arange(int(c)) + 0.5) * dx for k, c in enumerate(count)]
    grid = np.meshgrid(*axes, indexing="ij")
    return np.ascontiguousarray(np.stack([g.ravel() for g in grid], axis=1))


def make_block(pos, vel, rho0: float, dx: float, radius: float, kind: int) -> ParticleState:
    n, dim = pos.shape
    return ParticleState(
        pos=np.ascontiguousarray(pos, dtype=np.float64),
        vel=np.ascontiguousarray(np.broadcast_to(np.asarray(vel, float), (n, dim))),
        rho=np.full(n, rho0),
        p=np.zeros(n),
        m=np.full(n, rho0 * dx**dim),
        radius=np.full(n, radius),
        kind=np.full(n, kind, np.int8),
        id=np.arange(n, dtype=np.int64),
    )


class StateMark:
    """The particles' positions, ids and a time that something derived from them was
    computed at, kept in buffers reused from step to step: :meth:`holds` says whether the
    state is still that one (so the derived quantity can be reused), :meth:`clear` forgets it."""

    def __init__(self):
        self._pos = np.zeros((0, 0))
        self._id = np.zeros(0, np.int64)
        self._t = None
        self._set = False

    def holds(self, st: ParticleState, t=None) -> bool:
        return (self._set and self._t == t and self._pos.shape == st.pos.shape
                and np.array_equal(self._pos, st.pos) and np.array_equal(self._id, st.id))

    def mark(self, st: ParticleState, t=None) -> None:
        if self._pos.shape != st.pos.shape:
            self._pos = np.empty_like(st.pos)
            self._id = np.empty_like(st.id)
        np.copyto(self._pos, st.pos)
        np.copyto(self._id, st.id)
        self._t = t
        self._set = True

    def permute(self, order: np.ndarray) -> None:
        """Follow a reordering of the particles (new index k = old index ``order[k]``): the
        mark holds the reordered state if and only if it held the state before."""
        if self._set:
            self._pos = self._pos[order]
            self._id = self._id[order]

    def clear(self) -> None:
        self._set = False
