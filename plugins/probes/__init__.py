"""Probes: wall-pressure sensors and water-depth gauges sampled during a run (``probes``).

- :mod:`.config`: the ``[probes]`` table and its ``[[probes.pressure]]`` / ``[[probes.depth]]`` entries;
- :mod:`.sampling`: the numba interpolation (pressure, fluid fraction, depth) over plain arrays;
- :mod:`.figures`: error figures against the shipped experiments (Buchner 2002, Lobovsky 2014);
- :mod:`.store`: ``probes.nc`` and ``probes.csv``;
- :mod:`.plugin`: the hooks.
"""

from .plugin import ProbesPlugin

__all__ = ["ProbesPlugin"]
