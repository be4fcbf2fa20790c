"""sphcore: weakly compressible SPH with boundary treatments as pluggy plugins."""

__version__ = "0.1.0"
