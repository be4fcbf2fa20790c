"""The one atomic write of sphcore: a file is replaced whole or not at all.

``write(tmp)`` writes the new content to a temporary file beside ``path`` (``.NAME.tmp``,
same directory, so the rename is atomic on one file system); it is flushed to the disk
(fsync, unless the caller opts out for a file it rewrites often and can lose, such as a
VTU frame) and renamed over ``path``. A reader, a crash or a full disk sees the old file or
the new one, never half of one; a failure removes the temporary file and raises
:class:`sphcore.errors.OutputError` naming ``path``.

Every file written here is announced (:func:`mark_written`) to the output directories open
in this process (:class:`sphcore.io.outdir.Manifest`), whose marker lists exactly what sph
wrote, so that ``--overwrite`` deletes those files and no other. A writer that makes a file
by other means (a netCDF library) calls :func:`mark_written` itself.
"""

from __future__ import annotations

import os
from pathlib import Path

from sphcore.errors import OutputError


#: called with the path of each file sph writes (the open output directories' manifests)
_LISTENERS: list = []


def mark_written(path) -> None:
    """Record that sph created or replaced the file ``path`` (the output directory's marker
    lists it: ``--overwrite`` deletes only such files)."""
    for listener in list(_LISTENERS):
        listener(Path(path))


def listen(listener) -> None:
    """Call ``listener(path)`` for every file written from now on (until :func:`forget`)."""
    _LISTENERS.append(listener)


def forget(listener) -> None:
    if listener in _LISTENERS:
        _LISTENERS.remove(listener)


def temporary_name(path: Path) -> Path:
    """Where :func:`write_atomically` writes before the rename (a killed run may leave it)."""
    path = Path(path)
    return path.with_name(f".{path.name}.tmp")


def write_atomically(path: Path, write, fsync: bool = True, what: str = "") -> None:
    """``write(tmp_path)``, fsync (unless ``fsync=False``), then rename over ``path``;
    the error reads "PATH: cannot write: REASON", or with ``what`` "PATH: cannot write WHAT: REASON"."""
    path = Path(path)
    tmp = temporary_name(path)
    try:
        write(tmp)
        if fsync:
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass  # the directory itself is unwritable: nothing was left behind
        raise OutputError(f"{path}: cannot write{' ' + what if what else ''}: {e.strerror or e}") from e
    mark_written(path)


def write_text_atomically(path: Path, text: str, fsync: bool = True) -> None:
    write_atomically(path, lambda tmp: Path(tmp).write_text(text), fsync)
