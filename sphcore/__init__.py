"""sphcore: weakly compressible SPH with boundary treatments as pluggy plugins.

Importing sphcore does no work: the process-wide settings of the compiled kernels
(OpenMP's wait policy, numba's cache kept consistent with the sources) are made by
:func:`sphcore.jit.prepare`, which every run calls before its first kernel.
"""

__version__ = "0.1.0"
