"""``sph sweep``: a grid of case variants run as Dask tasks, gathered in one xarray Dataset.

Built on the public run API (:func:`sphcore.run.runner.run`) and the ``--set`` grammar of
:mod:`sphcore.case.overrides`; it knows no plugin. Modules: :mod:`.grid` (``--vary`` and the
variants), :mod:`.task` (one variant in a fresh process), :mod:`.results` (Dataset, table,
Pareto plot), :mod:`.command` (the command itself).
"""

from .command import main

__all__ = ["main"]
