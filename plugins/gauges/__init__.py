"""Gauges: plugins that measure a run against reference data and report in its summary.

``front_gauge`` (dam-break surge front, and optionally the residual height at the back wall,
against the experiment that fits the column: Martin & Moyce 1952, Cruchaga 2007) and
``pressure_gauge`` (a tank at rest against hydrostatics). Sweeps collect their figures.
``reference`` loads the published data shipped in ``data/`` (also the wall-pressure series
the ``probes`` plugin compares with).
"""

from .front import FrontGauge, compare, front_position
from .hydrostatic import PressureGauge

__all__ = ["FrontGauge", "PressureGauge", "compare", "front_position"]
