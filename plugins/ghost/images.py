"""The ghost images of a run: :class:`MirrorImages` keeps the output buffers (grown
geometrically) and runs the passes of :mod:`.mirror` (fixed walls) or :mod:`.moving` (a
moving tank); :func:`inverse_tait` is the density of a ghost's pressure.
"""

from __future__ import annotations

import numpy as np

from sphcore.api import Sources, eos

from .mirror import (
    MAX_PLANES,
    PARALLEL_MIN,
    TOL_REL,
    count_images,
    count_images_serial,
    exclusive_scan,
    fill_images,
    fill_images_serial,
)
from .moving import fill_images_moving, fill_images_moving_serial
from .records import GhostPressure, Images, MirrorRule, Passes, PlaneGroup


class MirrorImages:
    """Ghost generator for one set of planes, with output buffers reused between calls.

    ``normals`` (k, dim) unit vectors into the domain, ``offsets`` (k,) n . X0 (m).
    ``free_slip`` selects the velocity rule, ``hydrostatic`` the pressure correction.
    ``max_order`` is the largest number of planes one image is mirrored across (dim by
    default: corners in 2D, corners and edges in 3D).
    """

    def __init__(self, normals, offsets, free_slip=True, hydrostatic=True, max_order=None):
        self.walls = PlaneGroup(np.ascontiguousarray(normals, dtype=np.float64),
                                np.ascontiguousarray(offsets, dtype=np.float64))
        if self.walls.normals.shape[0] > MAX_PLANES:
            raise ValueError(f"at most {MAX_PLANES} wall planes, got {self.walls.normals.shape[0]}")
        self.dim = self.walls.normals.shape[1]
        self.free_slip, self.hydrostatic = bool(free_slip), bool(hydrostatic)
        self.max_order = self.dim if max_order is None else int(max_order)
        self.n = 0  # ghosts made by the last call
        self.capacity = 0
        self.reallocations = 0
        self._passes = Passes(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(1, np.int64))
        self._alloc(0)

    def _alloc(self, cap):
        dim = self.dim
        self.capacity = cap
        self._out = Images(np.zeros((cap, dim)), np.zeros((cap, dim)), np.zeros(cap), np.zeros(cap), np.zeros(cap),
                           np.zeros(cap, np.int64))

    def generate(self, fluid, kind, constants, walls=None, motion=None):
        """Ghosts of the current fluid as :class:`sphcore.api.Sources`.

        ``fluid``: :class:`sphcore.api.Fields` of the particles (pos m, vel m/s, rho
        kg/m^3, m kg; p the pressure the momentum equation uses, Pa); ``kind`` (n,) int8
        codes (only FLUID particles are mirrored); ``constants``: a :class:`FluidConstants`
        or the run's :class:`sphcore.api.Params` (support, gravity, rho0, c0, gamma,
        p_background, rho_ref). Walls that move: ``walls``, a :class:`PlaneGroup` of the
        planes where they are now (the same planes in the same order as at construction),
        and ``motion``, their :class:`WallMotion` now (a row per plane); without ``motion`` the images are
        those of fixed walls (the fixed-wall kernels). The arrays returned are views of
        this object's buffers, valid until the next call (the core copies them into its
        source arrays).
        """
        walls = self.walls if walls is None else walls
        if walls.normals.shape != self.walls.normals.shape:
            raise ValueError(f"expected {self.walls.normals.shape[0]} planes in {self.dim}D, got normals of shape "
                             f"{walls.normals.shape}")
        if motion is not None and any(v.shape != (walls.normals.shape[0], 3) for v in motion):
            raise ValueError(f"expected a WallMotion row (3 components) for each of the {walls.normals.shape[0]} "
                             "planes")
        n = fluid.pos.shape[0]
        if self._passes.counts.shape[0] != n:
            self._passes = Passes(np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n + 1, np.int64))
        passes = self._passes
        support = constants.support
        rule = MirrorRule(float(support), TOL_REL * support, self.max_order, self.free_slip)
        parallel = n >= PARALLEL_MIN
        count = count_images if parallel else count_images_serial
        fill = fill_images if parallel else fill_images_serial
        count(fluid, kind, walls, rule, passes)
        total = int(exclusive_scan(passes.counts, passes.start))
        if total > self.capacity:
            # geometric growth: a wave running up a wall raises the count a little at a time
            self._alloc(max(total, int(1.5 * self.capacity) + 64))
            self.reallocations += 1
        rho0, c0, gamma = float(constants.rho0), float(constants.c0), float(constants.gamma)
        ghost = GhostPressure(self.hydrostatic, self._gravity(constants.gravity), float(constants.rho_ref), rho0,
                              float(eos.tait_b(c0, rho0, gamma)), 1.0 / gamma, float(constants.p_background), c0, gamma)
        if motion is None:
            fill(fluid, walls, rule, ghost, passes, self._out)
        else:
            fill = fill_images_moving if parallel else fill_images_moving_serial
            fill(fluid, walls, rule, ghost, motion, passes, self._out)
        self.n = total
        out = self._out
        return Sources(out.pos[:total], out.vel[:total], out.rho[:total], out.p[:total], out.m[:total])

    @staticmethod
    def _gravity(g):
        """(3,) float64, zero-padded: the core's ctx.params.gravity already is; tests may pass (dim,)."""
        out = np.zeros(3)
        g = np.asarray(g, dtype=np.float64).ravel()
        out[: g.size] = g
        return out

    @property
    def source_index(self) -> np.ndarray:
        """Index (into the arrays of the last call) of the particle each ghost mirrors."""
        return self._out.src[: self.n]


def inverse_tait(p, rho0, c0, gamma, p_background=0.0):
    """Density (kg/m^3) whose Tait pressure is p (Pa), base clamped (numpy arrays)."""
    return eos.density_of(p, rho0, c0, gamma, p_background)
