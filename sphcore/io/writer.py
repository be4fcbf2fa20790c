"""What every output writer shares: its case table holds its schedule, a restart puts its
files in order at the first output call, and after a write error it stays silent (the run
is stopping and must not fail again on the same disk).

A restart trusts no file it continues: each writer records in the checkpoint (its kept
state) how many frames it has written, the time and step of the last one and a checksum of
every frame's time (:func:`record_frame`); at set-up a
restart compares that with the frames its file holds (:func:`check_series`) and refuses,
with a CaseError naming the file (exit status 2, nothing written), a file that is missing,
cut, unreadable or holds other frames than the checkpoint counts. Frames written after the
checkpoint (a kill) are expected and dropped when the file is reopened.
"""

from __future__ import annotations

import math
import struct
import zlib
from pathlib import Path

from sphcore.errors import CaseError, OutputError
from sphcore.io.schedule import Schedule, schedule_options
from sphcore.plugin.hookspecs import hookimpl


def leading_complete(times, steps=None, last_step=None) -> int:
    """How many leading frames are complete and in order: a finite time, later than the one
    before (a cut file reads as zeros or NaN where its frames were lost), and with ``steps``
    and ``last_step`` given, a step at most ``last_step`` (the restart point)."""
    n, prev = 0, -math.inf
    for k, t in enumerate(times):
        t = float(t)
        if not (math.isfinite(t) and t > prev) or (last_step is not None and int(steps[k]) > last_step):
            break
        n, prev = n + 1, t
    return n


def record_frame(record: dict, t: float, step) -> None:
    """Count one more frame at time ``t`` (s) and ``step`` in a writer's ``record``."""
    crc = zlib.crc32(struct.pack("<d", float(t)), record.get("crc") or 0)
    record.update(frames=record.get("frames", 0) + 1, t=float(t), step=None if step is None else int(step), crc=crc)


def new_record(record: dict, frames=()) -> dict:
    """Make ``record`` count exactly ``frames`` ((time, step) pairs; none: a fresh run)."""
    record.update(frames=0, t=None, step=None, crc=0)
    for t, step in frames:
        record_frame(record, t, step)
    return record


def check_series(path: Path, frames, record: dict, t: float, step: int) -> int:
    """Check the frames a file holds against the checkpoint's ``record`` of its writer
    (``frames``: how many it wrote, ``t`` and ``step`` of the last); ``frames`` here is the
    file's list of ``(time, step or None)`` (None: the file is missing). Returns how many
    frames stay (those up to the restart at ``t``, ``step``); raises a CaseError naming
    ``path`` when a frame the checkpoint counts is missing or differs. A record without
    ``frames`` (nothing recorded) is not checked."""
    n = record.get("frames")
    if not isinstance(n, int) or isinstance(n, bool):
        return -1
    redo = "restore it, or run again with --overwrite (or --output DIR)"
    if frames is None:
        if n:
            raise CaseError(path, "--restart", f"missing: the checkpoint at t = {t:.6g} s counts {n} frames "
                            f"written to it; {redo}")
        return 0
    times = [f[0] for f in frames]
    steps = [f[1] if f[1] is not None else -1 for f in frames]
    good = leading_complete(times)
    here = [f for f in frames[:good] if (f[1] <= step if f[1] is not None else f[0] <= t)]
    if len(here) < n:
        raise CaseError(path, "--restart", f"holds {len(here)} complete frames up to t = {t:.6g} s, the checkpoint "
                        f"counts {n}: the file was cut, emptied or replaced; {redo}")
    if n and (here[n - 1][0] != record.get("t") or (frames[n - 1][1] is not None and steps[n - 1] != record.get("step"))):
        raise CaseError(path, "--restart", f"frame {n} is at t = {here[n - 1][0]!r} s, step {here[n - 1][1]}, the "
                        f"checkpoint recorded t = {record.get('t')!r} s, step {record.get('step')}: the file holds "
                        f"another run's frames; {redo}")
    if record.get("crc") is not None and new_record({}, here[:n])["crc"] != record["crc"]:
        raise CaseError(path, "--restart", f"the times of its first {n} frames are not those the checkpoint "
                        f"recorded: the file holds another run's frames; {redo}")
    if len(here) > n + 1 or (len(here) == n + 1 and here[n][0] != t):
        raise CaseError(path, "--restart", f"holds {len(here)} frames up to t = {t:.6g} s, the checkpoint counts {n}: "
                        f"the file holds frames of another run; {redo}")
    return len(here)


class ScheduledWriter:
    """Base of the ``vtu`` and ``netcdf`` plugins; subclasses set ``table`` and ``what``
    and implement ``write_frame(ctx)`` and ``reopen_for_restart(ctx)``; ``frames_on_disk(ctx)``
    lets a restart check the file against the checkpoint (see :func:`check_series`)."""

    table = ""  # the case table, named after the plugin
    what = ""  # what one frame is, for the option docs

    def __init__(self):
        self.schedule = Schedule()  # replaced from the case in sph_configure
        self._failed = False
        self._restart_pending = False

    @hookimpl
    def sph_options(self):
        return {self.table: schedule_options(self.what)}

    @hookimpl
    def sph_configure(self, case):
        self.schedule = Schedule.from_config(case, self.table)

    @hookimpl
    def sph_moving_walls(self):
        # a writer writes what the run holds, wherever its walls are
        return True

    @hookimpl
    def sph_setup(self, ctx):
        # the restart's files are trimmed to the checkpoint at the first output call, where
        # ctx.t and ctx.step are those of the restart point
        self._restart_pending = ctx.restarting
        self._record = ctx.kept(self) if hasattr(ctx, "kept") else {}  # a stand-in context keeps nothing
        if not ctx.restarting:
            new_record(self._record)
        elif ctx.output_dir is not None:
            found = self.frames_on_disk(ctx)
            if found is not None:
                kept = check_series(found[0], found[1], self._record, ctx.t, ctx.step)
                if kept >= 0:
                    new_record(self._record, (found[1] or [])[:kept])

    @hookimpl
    def sph_output(self, ctx, final):
        if self._failed:
            return
        try:
            if self._restart_pending:
                self._restart_pending = False
                self.reopen_for_restart(ctx)
            if self.schedule.due(ctx.t, ctx.step, final):
                self.write_frame(ctx)
                if getattr(self, "_record", None) is not None:
                    record_frame(self._record, ctx.t, ctx.step)
        except OutputError:
            self._failed = True
            raise

    def write_frame(self, ctx):  # pragma: no cover - abstract
        raise NotImplementedError

    def reopen_for_restart(self, ctx):  # pragma: no cover - abstract
        raise NotImplementedError

    def frames_on_disk(self, ctx):
        """(path, frames) of the file a restart continues: frames its ``(time, step or None)``
        in file order, None when the file is missing; None for no check (the default). A file
        that cannot be read is a CaseError naming it."""
        return None
