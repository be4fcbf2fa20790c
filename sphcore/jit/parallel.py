"""Parallel where it pays, serial where a launch costs more than the work.

A numba kernel whose outer loop is a ``prange`` over particles can run in parallel or,
compiled without ``parallel=True``, as a plain loop. A parallel launch costs ~10-20 us on
a quiet machine and far more when the machine is shared (a per-step kernel of 2,592
particles took 0.58 ms with two threads under load, 0.05 ms with one); below
``PARALLEL_MIN`` particles the serial build runs. Measure before using it: numba's serial
build of a kernel with a large, rarely taken branch (the wall model's per-particle terms)
ran 4x slower per particle than its parallel build even on one thread, so those kernels
stay ``parallel=True``. Both builds give identical results: the
loop bodies are independent per particle (a ``+=`` reduction over the loop is summed in
integers or compared, never accumulated in floating point across threads).

    reflect = by_size(_reflect)          # _reflect: a plain Python function using prange
    reflect(pos0, pos, ...)              # the first argument's rows decide
"""

from __future__ import annotations

import types

import numba
from numba import njit

PARALLEL_MIN = 20_000  # particles (rows of the first argument)
# contiguous ranges of particles that a reduction (a bounding box, the largest norms, the
# instability scan) handles alone, perhaps in parallel, then combines in order: the answer
# is the serial loop's for any thread count. A module constant compiled into those kernels;
# sphcore.jit.cache recompiles them when it changes.
CHUNKS = 16


def twin(pyfunc, suffix: str, **constants):
    """A copy of the Python function ``pyfunc`` named ``name + suffix``, whose global names
    ``constants`` are replaced (numba compiles module globals as constants, so a twin with
    ``DIM=2`` is compiled for 2D only, its ``if DIM == 3`` branches removed). numba's disk
    cache is indexed by the qualified name: every twin is cached under its own. The twin's
    globals are a copy taken now, and numba's cache checks the source file, not the values:
    constants must be written in that file (not set or patched at run time), and every
    name the function uses must exist when the twin is made."""
    glob = pyfunc.__globals__
    if constants:
        glob = dict(glob)
        glob.update(constants)
    f = types.FunctionType(pyfunc.__code__, glob, pyfunc.__name__ + suffix, pyfunc.__defaults__, pyfunc.__closure__)
    f.__qualname__ = pyfunc.__qualname__ + suffix
    f.__doc__ = pyfunc.__doc__
    f.__module__ = pyfunc.__module__
    return f


def on_threads_by_size(n: int, minimum: int, kernel, *args):
    """``kernel(*args)``, a ``parallel=True`` kernel whose loop runs over n items, on one
    thread when n < ``minimum``, else on the count set; the count is restored after the call.

    One prange loop then serves both sizes, where :class:`by_size` compiles a serial and a
    parallel build: a serial copy of a large loop body beside the parallel one doubles what
    numba compiles, and its parallel passes grow faster than the body (the wall model's
    plane terms: 107-118 -> 48-67 s to compile; with OpenMP, sphcore's threading layer, the
    one-thread call ran as fast as the serial loop). The count is set from
    Python because numba cannot cache a kernel that sets it. Use it where the loop's
    iterations are independent (the result does not depend on the thread count)."""
    if n >= minimum:
        return kernel(*args)
    before = numba.get_num_threads()
    if before == 1:
        return kernel(*args)
    numba.set_num_threads(1)
    try:
        return kernel(*args)
    finally:
        numba.set_num_threads(before)


def serial_and_parallel(pyfunc, **njit_options):
    """(serial, parallel) numba builds of a prange kernel, each cached on disk under its own
    name: numba's cache is indexed by the function's qualified name, not by the parallel
    flag, so a second build of the same function would load the first one's code
    (measured: both ran serial)."""
    serial = njit(cache=True, **njit_options)(pyfunc)
    return serial, njit(cache=True, parallel=True, **njit_options)(twin(pyfunc, "_parallel"))


class by_size:
    """A kernel compiled twice (serial, parallel; both cached on disk), called by size."""

    def __init__(self, pyfunc, **njit_options):
        self.serial, self.parallel = serial_and_parallel(pyfunc, **njit_options)
        self.__doc__ = pyfunc.__doc__
        self.__name__ = pyfunc.__name__
        self.__wrapped__ = pyfunc

    def __call__(self, *args):
        kernel = self.parallel if args[0].shape[0] >= PARALLEL_MIN else self.serial
        return kernel(*args)
