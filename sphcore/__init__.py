"""sphcore: weakly compressible SPH with boundary treatments as pluggy plugins."""

import os

# numba's OpenMP threads wait at the end of every parallel loop for the next one. Spinning
# without bound hurts when the cores are shared (a sweep running several cases, a busy CI
# machine): the spinning threads are descheduled and one parallel call then costs ~10 ms
# instead of ~50 us (measured on the 2-core machine: 12 ms vs 45 us per call under load),
# so the wait is passive. A passive thread sleeps at once, though, and waking it costs
# more than a small loop's work: the pair loop of PySPH's dam break (2,278 particles, two
# parallel phases a call) took 233 us a call on two threads and 290 on one. A short spin
# (GOMP_SPINCOUNT: libgomp's busy-wait iterations before the thread sleeps; 1,000 are
# ~25 us on the 2-core AMD EPYC machine) bridges the gaps inside a call: 167 us. Longer
# spins (10,000: ~0.25 ms, across the gaps of a whole step) gained a little more on a quiet
# machine but made two fixed threads 2.5 times slower than one with a core busy, 1,000
# 1.18 times (docs/speed.md). A user's explicit setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")
os.environ.setdefault("GOMP_SPINCOUNT", "1000")

from sphcore.jit import cache as _jitcache  # noqa: E402  (after the OpenMP settings: numba must see them)

_jitcache.refresh()  # numba's caches of edited sources, and of what was compiled into others

__version__ = "0.1.0"
