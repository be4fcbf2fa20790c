"""A run's output directory: where it is, the marker that proves sph made it, the manifest
of the files sph wrote there, ``--overwrite`` that deletes only those, and atomic writes.

The marker ``.sphcore-output`` is a JSON file::

    {"written_by": "sphcore", "dir": "/abs/out", "case": "/abs/case/case.toml",
     "files": ["particles.nc", "vtu/frame_0000.vtu", ...], "dirs": ["vtu"]}

``--overwrite`` trusts it only when it is a regular file (not a link), names this very
directory (a marker copied elsewhere names another one) and this case; it then deletes
the regular files it lists (never through a symbolic link, never outside the directory)
and the listed directories left empty. Anything else in the directory (a user's plot, a
note, files copied in) is kept. The manifest is brought up to date with every checkpoint
and at the end of a run: it records the files already listed plus every file this process
wrote there since the run (segment) began, as each write announces it
(:func:`sphcore.io.atomic.mark_written`), never by modification times: a file a user saves
into the directory while the run goes on is not sph's and stays out of it. Entries that
are not relative paths (a hand-edited marker) name no file and are ignored.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import sys
from pathlib import Path

from sphcore.errors import CaseError, OutputError
from sphcore.io import atomic
from sphcore.io.atomic import temporary_name, write_text_atomically

MARKER = ".sphcore-output"
LOCK = ".sphcore-lock"  # held by the run writing the directory (WriterLock)


# -- where -------------------------------------------------------------------------------

NAME_MAX = 255  # bytes in one folder name on the usual file systems (ext4, xfs, tmpfs, APFS)


def resolve(case, output=None) -> Path:
    """The output directory: ``--output`` as given, else ``output.dir`` under the case
    directory. ``output.dir`` may not leave the case directory (an absolute path or ``..``):
    writing, and overwriting, elsewhere takes an explicit ``--output``."""
    if output is not None:
        return Path(output)
    rel = case.config["output"]["dir"]
    norm = os.path.normpath(rel)
    if not rel or os.path.isabs(rel) or norm == ".." or norm.startswith(".." + os.sep) or norm == ".":
        raise CaseError(case.file, "output.dir", f"expected a sub-directory of the case directory, got {rel!r} "
                        "(write elsewhere with --output DIR)")
    if "\0" in rel or any(len(part.encode()) > NAME_MAX for part in Path(norm).parts):
        raise CaseError(case.file, "output.dir", f"expected folder names without NUL bytes, of at most {NAME_MAX} "
                        f"bytes each, got {rel[:40]!r}...")
    blocked = _not_a_folder(case.dir, Path(norm))
    if blocked is not None:
        raise CaseError(case.file, "output.dir", f"{blocked} is a file, not a folder: expected a directory to "
                        f"write into, got {rel!r}")
    return case.dir / norm


def _not_a_folder(base: Path, rel: Path) -> Path | None:
    """The first path of ``base``/``rel`` on the way to it that exists and is not a directory."""
    p = base
    for part in rel.parts:
        p = p / part
        if p.exists() and not p.is_dir():
            return p
    return None


# -- the marker and manifest ---------------------------------------------------------------

def read_marker(out: Path) -> dict | None:
    """The marker's content, or None when it is missing, a link, not a file or not ours."""
    m = Path(out) / MARKER
    try:
        if m.is_symlink() or not m.is_file() or m.stat().st_size > 64 << 20:
            return None
        data = json.loads(m.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("written_by") != "sphcore":
        return None
    if not isinstance(data.get("files"), list) or not isinstance(data.get("dirs"), list):
        return None
    for key in ("files", "dirs"):  # an entry that is not a relative path names no file of the run
        data[key] = [r for r in data[key] if isinstance(r, str) and r and "\0" not in r]
    for key in ("dir", "case"):
        if not isinstance(data.get(key, ""), str):
            data[key] = repr(data[key])
    return data


def _identity(path) -> str:
    return str(Path(path).resolve()) if path is not None else ""


def _inside(out: Path, rel: str) -> Path | None:
    """``out/rel`` if rel is a plain relative path with no link on the way; else None."""
    if not isinstance(rel, str) or not rel or os.path.isabs(rel):
        return None
    parts = Path(rel).parts
    if any(p in ("..", ".") for p in parts):
        return None
    p = out
    for part in parts:
        p = p / part
        if p.is_symlink():
            return None
    return p


def _linked(out: Path, rel: str) -> bool:
    """Whether a link lies on the way to ``out/rel`` (a harmless bad entry is just skipped)."""
    p = out
    for part in Path(rel).parts:
        if part in ("..", ".") or os.path.isabs(part):
            return False
        p = p / part
        if p.is_symlink():
            return True
    return False


class WriterLock:
    """One writer per output directory: an exclusive lock (``flock``) on ``LOCK`` inside it,
    held while a run writes there and released by the operating system when the process
    ends, however it ends. A second run, ``--overwrite`` or ``--restart`` into a directory a
    live run holds is refused (OutputError, exit status 2) before it deletes or writes
    anything. The lock file holds the process id of its holder, for the message. On a file
    system without locks (some network mounts) the run goes on unlocked, and says so."""

    def __init__(self, out: Path):
        self.fd = None
        self.path = path = Path(out) / LOCK
        if path.is_symlink():
            raise OutputError(f"{path} is a symbolic link: sph never writes through one; remove it")
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
        except OSError as e:
            raise OutputError(f"{path}: cannot create: {e.strerror or e}") from e
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
                os.close(fd)
                raise OutputError(f"{out}: another sph run (process {holder}) is writing this directory: wait for "
                                  "it to end, or pass --output DIR") from None
            os.close(fd)  # no locks on this file system
            print(f"sph: warning: {path}: cannot lock ({e.strerror or e}); nothing stops a second run from "
                  "writing this directory at the same time", file=sys.stderr)
            return
        self.fd = fd

    def record(self) -> None:
        """Write this process's id into the lock file (for a refused writer's message); done
        when the run starts writing, so that a refused restart changes nothing on disk."""
        if self.fd is None:
            return
        try:
            os.ftruncate(self.fd, 0)
            os.write(self.fd, f"{os.getpid()}\n".encode())
        except OSError as e:
            self.release()
            raise OutputError(f"{Path(self.path)}: cannot write: {e.strerror or e}") from e

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def __del__(self):  # a lock nobody holds any more (an error path) frees the directory
        self.release()


class Manifest:
    """Keeps the marker's list of sph's files up to date during one run segment, and holds
    the directory's writer lock until :meth:`release`. Listens, until then, to every file
    this process writes (:func:`sphcore.io.atomic.mark_written`) and records those inside
    the directory."""

    def __init__(self, out: Path, case_file=None, lock: WriterLock | None = None):
        self.out = Path(out)
        self.lock = lock
        self.case = _identity(case_file)
        self._root = os.path.realpath(self.out)
        old = read_marker(self.out) or {}
        self.files = set(old.get("files", []))
        self.dirs = set(old.get("dirs", []))
        atomic.listen(self.wrote)

    def wrote(self, path: Path) -> None:
        """Record ``path`` (a file sph created or replaced) when it lies in this directory."""
        full = os.path.join(os.path.realpath(os.path.dirname(os.path.abspath(path))), os.path.basename(path))
        rel = os.path.relpath(full, self._root)
        if rel.startswith(os.pardir + os.sep) or rel in (os.pardir, os.curdir, MARKER, LOCK):
            return
        self.files.add(rel)
        parent = os.path.dirname(rel)
        while parent:
            self.dirs.add(parent)
            parent = os.path.dirname(parent)

    def update(self) -> None:
        """Write the marker: the files listed before plus those written in this segment
        that still exist."""
        self.files = {f for f in self.files if os.path.lexists(self.out / f)}
        self.write()

    def release(self) -> None:
        """Let another run write this directory (the end of the run)."""
        atomic.forget(self.wrote)
        if self.lock is not None:
            self.lock.release()

    def write(self) -> None:
        data = {"written_by": "sphcore", "dir": _identity(self.out), "case": self.case,
                "files": sorted(self.files), "dirs": sorted(self.dirs)}
        write_text_atomically(self.out / MARKER, json.dumps(data, indent=1) + "\n")


# -- preparing the directory ----------------------------------------------------------------

def _remove_listed(out: Path, marker: dict) -> list[str]:
    """Delete the marker's files (regular files only) and its directories left empty;
    returns what stays (not sph's). A listed path that has become a symbolic link (or lies
    behind one) is refused before anything is deleted: the new run would write through it."""
    for rel in marker["files"] + marker["dirs"]:
        if isinstance(rel, str) and _inside(out, rel) is None and _linked(out, rel):
            raise OutputError(f"refusing to overwrite {out}: {rel} is a symbolic link now (sph never deletes or "
                              "writes through one); remove the link or pass --output DIR")
    for rel in marker["files"]:
        p = _inside(out, rel)
        if p is not None and p.is_file() and not p.is_symlink():
            try:
                p.unlink()
            except OSError as e:
                raise OutputError(f"cannot remove {p}: {e.strerror}") from e
    for rel in sorted(marker["dirs"], key=lambda r: -len(Path(r).parts)):
        p = _inside(out, rel)
        if p is not None and p.is_dir() and not any(p.iterdir()):
            p.rmdir()
    (out / MARKER).unlink(missing_ok=True)
    return sorted(str(p.relative_to(out)) for p in out.rglob("*"))


def _remove_stale_temporaries(out: Path, marker: dict | None) -> None:
    """A SIGKILL in the middle of an atomic write leaves its temporary (``.NAME.tmp``, or
    ``checkpoint.tmp.npz``): remove those of sph's own files, and only those."""
    names = set((marker or {}).get("files", [])) | {"summary.json", "front.csv", MARKER, "checkpoint.npz"}
    for rel in names:
        p = _inside(out, rel) if isinstance(rel, str) else None
        if p is None:
            continue
        # the second: the checkpoint's temporary name before every write went through sphcore.io.atomic
        for tmp in (temporary_name(p), p.with_suffix(".tmp.npz") if p.suffix == ".npz" else None):
            if tmp is not None and tmp.is_file() and not tmp.is_symlink():
                try:
                    tmp.unlink()
                except OSError:
                    pass  # harmless: the next write of that file replaces it


def prepare(out: Path, case_file=None, overwrite=False, restart=False, lock: WriterLock | None = None) -> Manifest:
    """Create (or reuse, on restart) the output directory; never clobber what is not sph's.
    Raises OutputError (exit status 2: nothing written). ``lock``: the directory's writer
    lock when the caller took it already (a restart takes it before reading the checkpoint);
    on an error the lock is released."""
    out = Path(out)
    try:
        return _prepare(out, case_file, overwrite, restart, lock)
    except BaseException:
        if lock is not None:
            lock.release()
        raise


def _prepare(out: Path, case_file, overwrite, restart, lock) -> Manifest:
    if out.is_symlink():
        raise OutputError(f"output directory {out} is a symbolic link: sph writes only into a real directory "
                          f"(pass the link's target with --output)")
    if out.exists() and not out.is_dir():
        raise OutputError(f"output path {out} exists and is not a directory")
    blocked = _not_a_folder(Path(out.anchor), out.relative_to(out.anchor)) if out.is_absolute() else \
        _not_a_folder(Path("."), out)
    if blocked is not None:
        raise OutputError(f"output path {out}: {blocked} is a file, not a folder")
    own = []  # the lock taken here, released on an error below

    def take() -> WriterLock:
        own.append(WriterLock(out))
        return own[-1]

    try:
        if restart and out.is_dir():
            lock = lock or take()  # before anything is touched: a live run may hold it
            marker = read_marker(out)
            _refuse_links_on_restart(out, marker)
            _remove_stale_temporaries(out, marker)
        # a lock file alone (a run that failed before its marker) leaves the directory empty
        if out.exists() and any(p.name != LOCK for p in out.iterdir()) and not restart:
            if not overwrite:
                if (out / LOCK).is_file() and not (out / LOCK).is_symlink():
                    WriterLock(out).release()  # a live run writing it is named (refused here)
                raise OutputError(f"output directory {out} exists and is not empty: pass --overwrite, --restart or "
                                  "--output DIR")
            marker = read_marker(out)
            if marker is None:
                raise OutputError(f"refusing to overwrite {out}: it was not written by sph (no valid {MARKER} file "
                                  "listing sph's files; an empty one, from an older sph, lists none: delete it "
                                  "yourself)")
            if marker.get("dir") != _identity(out):
                raise OutputError(f"refusing to overwrite {out}: its {MARKER} was written for {marker.get('dir')!r} "
                                  "(a copied marker proves nothing)")
            if case_file is not None and marker.get("case") not in ("", _identity(case_file)):
                raise OutputError(f"refusing to overwrite {out}: it holds the output of another case "
                                  f"({marker.get('case')}); pass --output DIR")
            lock = lock or take()  # sph's own directory: locked before anything of it is deleted
            _remove_listed(out, marker)  # refuses (before deleting) when a listed path became a link
            _remove_stale_temporaries(out, marker)
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise OutputError(f"cannot create output directory {out}: {e.strerror}") from e
        manifest = Manifest(out, case_file, lock or take())
        manifest.lock.record()
        manifest.write()
        return manifest
    except BaseException:
        for held in own:
            held.release()
        raise


def _refuse_links_on_restart(out: Path, marker: dict | None) -> None:
    """A restart appends to files of the run: refuse if one of them, or a folder on the way,
    is a symbolic link now (the marker's list; without a marker, anything in the directory)."""
    if marker is not None:
        listed = [r for r in marker.get("files", []) + marker.get("dirs", []) if isinstance(r, str)]
        linked = [r for r in listed if _linked(out, r)]
    else:
        linked = [str(p.relative_to(out)) for p in out.rglob("*") if p.is_symlink()]
    if linked:
        raise OutputError(f"refusing to restart in {out}: {linked[0]} is a symbolic link now (sph never writes "
                          "through one); put the file back or restart into a copy")
