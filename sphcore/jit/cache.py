"""numba's on-disk cache kept consistent with the sources of sphcore and its plugins.

numba keys each cached function on its own source file only. Code it compiled into that
function from another module (a call, or ``inline="always"``, such as the pair loop's
kernels of :mod:`sphcore.physics.pairterms` inside :mod:`sphcore.physics.equations`) is
not checked: after an edit of the callee's file the caller's cache keeps the old machine
code, silently (an edited inlined function had no effect on a run until the caller's file
was touched).

:func:`refresh` runs once per process (:func:`sphcore.jit.prepare`), before any compiled function is called:
it compares a stamp of every Python source file of sphcore and of its plugins (path,
size, modification time) with the stamp saved beside the caches; when they differ it
removes those packages' cache files (``*.nbi`` / ``*.nbc``, numba's own; nothing else) from
every place numba may keep them (``__pycache__`` beside the sources, ``NUMBA_CACHE_DIR``,
numba's user-wide directory), so that the next call recompiles, and saves the new stamp.
An installed package whose sources do not change pays one ``os.stat`` per source file
(0.7 ms for the 79 files of this tree). Unwritable places are left as they are: a cache that
cannot be written is not used by numba either.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
from pathlib import Path

STAMP = "sphcore-sources.stamp"  # in sphcore's own __pycache__
SUFFIXES = (".nbi", ".nbc")


def source_roots() -> list[Path]:
    """The directories of sphcore and of the bundled plugins package (if installed)."""
    roots = [Path(__file__).resolve().parents[1]]
    spec = importlib.util.find_spec("sphcore_plugins")
    if spec is not None and spec.submodule_search_locations:
        roots += [Path(p).resolve() for p in spec.submodule_search_locations]
    return roots


def source_files(roots) -> list[Path]:
    """Every ``*.py`` under ``roots``, sorted (no caches, no hidden directories)."""
    files = []
    for root in roots:
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames[:] = sorted(d for d in dirnames if d != "__pycache__" and not d.startswith("."))
            files += [Path(dirpath) / f for f in sorted(filenames) if f.endswith(".py")]
    return files


def stamp_of(files) -> str:
    """sha256 of (path, size, modification time in ns) of every file."""
    h = hashlib.sha256()
    for f in files:
        st = f.stat()
        h.update(f"{f}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
    return h.hexdigest()


def cache_dirs(files) -> list[Path]:
    """Where numba may keep the caches of functions defined in ``files``: ``__pycache__``
    beside each source directory, and the same directory's place under ``NUMBA_CACHE_DIR``
    and under numba's user-wide cache directory (numba's own path rule)."""
    dirs = sorted({f.parent for f in files})
    out = [d / "__pycache__" for d in dirs]
    try:
        from numba.core.caching import UserWideCacheLocator
        from numba.misc.appdirs import AppDirs
    except ImportError:  # another numba layout: the in-tree caches are still handled
        return out
    bases = [Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)]
    if os.environ.get("NUMBA_CACHE_DIR"):
        bases.append(Path(os.environ["NUMBA_CACHE_DIR"]))
    for base in bases:
        out += [base / UserWideCacheLocator.get_suitable_cache_subpath(str(d / "x.py")) for d in dirs]
    return out


def on_disk(source, pattern: str) -> bool:
    """Whether numba's disk cache holds an index file matching ``pattern`` (e.g.
    ``"equations._sph_rates_2d*.nbi"``) of a function defined in the file ``source``,
    wherever numba may keep it (:func:`cache_dirs`)."""
    return any(any(d.glob(pattern)) for d in cache_dirs([Path(source).resolve()]) if d.is_dir())


def remove_caches(dirs) -> int:
    """Remove numba's cache files from ``dirs``; returns how many. Errors are skipped."""
    removed = 0
    for d in dirs:
        try:
            entries = list(d.iterdir())
        except OSError:
            continue
        for e in entries:
            if e.suffix in SUFFIXES:
                try:
                    e.unlink()
                    removed += 1
                except OSError:
                    pass
    return removed


def refresh(roots=None) -> bool:
    """Remove stale numba caches if any source changed since the last check; True if it did.

    Never raises for file-system reasons (an unwritable tree keeps what it has)."""
    try:
        roots = source_roots() if roots is None else [Path(r) for r in roots]
        files = source_files(roots)
        stamp = stamp_of(files)
        path = roots[0] / "__pycache__" / STAMP
        try:
            if path.read_text() == stamp:
                return False
        except OSError:
            pass
        remove_caches(cache_dirs(files))
        path.parent.mkdir(exist_ok=True)
        tmp = path.with_name(f"{STAMP}.{os.getpid()}.tmp")
        tmp.write_text(stamp)
        os.replace(tmp, path)
        return True
    except OSError:
        return False
