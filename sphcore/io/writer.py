"""What every output writer shares: its case table holds its schedule, a restart puts its
files in order at the first output call, and after a write error it stays silent (the run
is stopping and must not fail again on the same disk)."""

from __future__ import annotations

from sphcore.errors import OutputError
from sphcore.io.schedule import Schedule, schedule_options
from sphcore.plugin.hookspecs import hookimpl


class ScheduledWriter:
    """Base of the ``vtu`` and ``netcdf`` plugins; subclasses set ``table`` and ``what``
    and implement ``write_frame(ctx)`` and ``reopen_for_restart(ctx)``."""

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
        except OutputError:
            self._failed = True
            raise

    def write_frame(self, ctx):  # pragma: no cover - abstract
        raise NotImplementedError

    def reopen_for_restart(self, ctx):  # pragma: no cover - abstract
        raise NotImplementedError
