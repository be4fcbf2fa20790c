"""numba helpers: serial or parallel builds by size, the on-disk cache kept consistent with
the sources, and :func:`prepare`, the process-wide settings made before the first kernel runs."""

from __future__ import annotations

import os

_prepared = False


def prepare() -> None:
    """Make the process ready for sphcore's compiled kernels; once per process, before the
    first kernel runs (a run, ``sph``, the test suite and the helpers of
    :mod:`sphcore.testing` call it; later calls do nothing).

    - OpenMP's wait policy. numba's OpenMP threads wait at the end of every parallel loop
      for the next one. Spinning without bound hurts when the cores are shared (a sweep
      running several cases, a busy CI machine): the spinning threads are descheduled and
      one parallel call then costs ~10 ms instead of ~50 us (measured on two cores: 12 ms
      against 45 us a call under load), so the wait is passive. A passive thread sleeps at
      once, though, and waking it costs more than a small loop's work, so a short spin
      (``GOMP_SPINCOUNT`` = 1,000 busy-wait iterations, ~25 us) bridges the gaps inside a
      call; longer spins made two fixed threads 2.5 times slower than one with a core busy
      (docs/explanation/performance.md). libgomp reads both when numba first loads its threading layer, so
      they are set here, before any parallel kernel; a user's explicit setting wins.
    - numba's on-disk cache: :func:`sphcore.jit.cache.refresh` removes the caches of edited
      sources and of what was compiled into other functions.
    """
    global _prepared
    if _prepared:
        return
    os.environ.setdefault("OMP_WAIT_POLICY", "passive")
    os.environ.setdefault("GOMP_SPINCOUNT", "1000")
    from sphcore.jit import cache

    cache.refresh()
    _prepared = True
