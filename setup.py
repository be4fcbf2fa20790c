"""Package discovery for the one mapping pyproject.toml cannot express to ``find``: the
folder ``plugins/`` installs as ``sphcore_plugins``. Everything else is in pyproject.toml."""

from setuptools import find_packages, setup

plugins = find_packages("plugins")
setup(packages=find_packages(include=["sphcore", "sphcore.*"])
      + ["sphcore_plugins"] + [f"sphcore_plugins.{name}" for name in plugins])
