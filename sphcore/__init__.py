"""sphcore: weakly compressible SPH with boundary treatments as pluggy plugins."""

import os

# numba's OpenMP threads spin while waiting at the end of a parallel loop. When the cores
# are shared (a sweep running several cases, a busy CI machine) the spinning threads are
# descheduled and one parallel call then costs ~10 ms instead of ~50 us (measured on the
# 2-core machine: 12 ms vs 45 us per call under load). Passive waiting costs little when
# the machine is quiet; a user's explicit setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

__version__ = "0.1.0"
