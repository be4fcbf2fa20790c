"""Gauges: plugins that measure a run against reference data and report in its summary.

``front_gauge`` (dam-break surge front against Cruchaga 2007 and Martin & Moyce 1952) and
``pressure_gauge`` (a tank at rest against hydrostatics). Sweeps collect their figures.
"""

from .front import FrontGauge, compare, front_position
from .hydrostatic import PressureGauge

__all__ = ["FrontGauge", "PressureGauge", "compare", "front_position"]
