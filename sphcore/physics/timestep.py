"""Time-step control.

Fixed, or adaptive with three limits (Monaghan 1992; Morris et al. 1997):

    dt = min( cfl * h / (c0 + |v|max),              acoustic (Courant)
              force_factor * sqrt(h / |a|max),       force
              viscous_factor * h^2 / nu )            viscous (only when nu > 0)

with the constants from the case's [time] table (defaults cfl = 0.3, force_factor = 0.25,
viscous_factor = 0.125). A limit whose denominator is zero does not apply. Plugins may
lower dt through the ``sph_max_dt`` hook.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from sphcore.jit.parallel import CHUNKS, by_size


@by_size
def max_norms(vel, acc):
    """Largest |v| (m/s) and |a| (m/s^2) over the particles, in CHUNKS ranges that may run
    in parallel (:class:`sphcore.jit.parallel.by_size`; a maximum does not depend on the order)."""
    n, dim = vel.shape
    part = np.zeros((CHUNKS, 2))
    for k in prange(CHUNKS):
        vm = 0.0
        am = 0.0
        for i in range(k * n // CHUNKS, (k + 1) * n // CHUNKS):
            sv = 0.0
            sa = 0.0
            for d in range(dim):
                sv += vel[i, d] * vel[i, d]
                sa += acc[i, d] * acc[i, d]
            vm = max(vm, sv)
            am = max(am, sa)
        part[k, 0] = vm
        part[k, 1] = am
    vm = 0.0
    am = 0.0
    for k in range(CHUNKS):
        vm = max(vm, part[k, 0])
        am = max(am, part[k, 1])
    return math.sqrt(vm), math.sqrt(am)


def adaptive_dt(h, c0, nu, vmax, amax, cfl, force_factor, viscous_factor):
    """The smallest of the acoustic, force and viscous limits (s); inf if none applies."""
    limits = [math.inf]
    if c0 + vmax > 0:
        limits.append(cfl * h / (c0 + vmax))
    if amax > 0:
        limits.append(force_factor * math.sqrt(h / amax))
    if nu > 0:
        limits.append(viscous_factor * h * h / nu)
    return min(limits)
