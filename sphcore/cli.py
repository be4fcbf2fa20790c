"""The ``sph`` command: run, check, plugins, options, sweep (:mod:`sphcore.sweep`).

Exit status: 0 done; 1 the run went unstable or could not write its output (what was
written is kept); 2 bad input (case, options, output directory), nothing written; 128 + signal number when stopped by SIGINT
or SIGTERM after writing a checkpoint, or before the run began (one line, nothing written).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys

from sphcore import __version__
from sphcore.errors import CaseError, OutputError
from sphcore.jit import prepare


def _parser():
    p = argparse.ArgumentParser(prog="sph", description="Weakly compressible SPH with pluggable boundaries.")
    p.add_argument("--version", action="version", version=f"sph (sphcore) {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run a case directory")
    r.add_argument("case_dir")
    r.add_argument("--output", help="output directory (default: <case>/output)")
    r.add_argument("--t-end", type=float, help="simulated time to reach (s), overrides time.t_end")
    r.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
                   help="override a case key (value read as TOML), repeatable")
    r.add_argument("--overwrite", action="store_true", help="replace an existing output directory written by sph")
    r.add_argument("--restart", action="store_true", help="continue from the output directory's checkpoint")
    r.add_argument("--progress", choices=("auto", "bar", "log", "off"))
    c = sub.add_parser("check", help="validate a case without running it")
    c.add_argument("case_dir")
    c.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    c.add_argument("--t-end", type=float, help="as for run")
    c.add_argument("--output", help="as for run: the output directory it would write")
    sub.add_parser("plugins", help="list installed plugins, the hooks they implement, and broken ones")
    o = sub.add_parser("options", help="every case key with its default, unit and meaning")
    o.add_argument("plugin", nargs="?", help="only this plugin's tables (or 'core')")
    _sweep_parser(sub)
    return p


# -- sph sweep: the grid of variants on Dask lives in sphcore/sweep/ ----------------------
def _sweep_parser(sub):
    w = sub.add_parser("sweep", help="run a grid of case variants on Dask, gather them in sweep.nc",
                       description="Run every combination of the --vary values as a Dask task; write "
                       "<output>/sweep.nc, print a table and draw <output>/pareto.png. See docs/howto/sweeps.md.")
    w.add_argument("case_dir")
    w.add_argument("--vary", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="values of a case key, split on commas outside brackets, each read as TOML like --set "
                   "(plugins.use=[\"ghost\"],[\"reflective\"]); linked keys: K1,K2=[a1,a2],[b1,b2]; "
                   "KEY may index an array of tables (blocks[0].count); repeatable: the Cartesian product")
    w.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case key in every variant (value read as TOML), repeatable")
    w.add_argument("--t-end", type=float, help="simulated time to reach (s) in every variant")
    w.add_argument("--output", help="sweep directory (default: <case>/sweep)")
    w.add_argument("--overwrite", action="store_true", help="replace a sweep directory written by sph")
    w.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler (tcp://host:8786) instead of a local "
                   "cluster; its workers must see the case and output paths")
    w.add_argument("--workers", type=int, help="local cluster size (default: one per core)")
    w.add_argument("--timeout", type=float, metavar="SECONDS", help="stop a variant after this wall time (status "
                   "'timeout', checkpoint written)")
    w.add_argument("--error", metavar="KEY", help="summary key plotted against wall time, as plugin.figure "
                   "(default: the first figure named err* or rms* that a variant reported)")
    w.add_argument("--progress", choices=("auto", "bar", "log", "off"))
    w.add_argument("--dry-run", action="store_true", help="validate and list the variants, run nothing")


def _fail(msg, status):
    print(f"sph: error: {msg}", file=sys.stderr)
    return status


def _starting(signum, frame):
    """SIGINT or SIGTERM while sph starts (imports, set-up): one line and the exit status,
    at once. An exception raised here could be lost (Python drops one raised inside a
    finaliser that the garbage collector happens to be running), and the run would go on;
    nothing of the run is written before its own handlers replace this one."""
    what = "interrupted" if signum == signal.SIGINT else "terminated"
    os.write(2, f"sph: error: {what} while starting; nothing written\n".encode())
    os._exit(128 + signum)


def main(argv=None) -> int:
    # SIGINT and SIGTERM while the modules load or the case is set up end with one line; a
    # run installs its own handlers (checkpoint, then stop)
    caught = threading_main() and signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    if caught:
        signal.signal(signal.SIGTERM, _starting)
        signal.signal(signal.SIGINT, _starting)
    try:
        return _main(argv)
    except BrokenPipeError:  # `sph options | head`: the reader left; stop quietly, as other tools do
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # Python's own flush at exit must not fail again
        return 128 + signal.SIGPIPE
    except KeyboardInterrupt:  # a caller's own SIGINT handling (sph started from Python)
        return _fail("interrupted while starting; nothing written", 128 + signal.SIGINT)
    finally:
        if caught:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            signal.signal(signal.SIGINT, signal.default_int_handler)


def default_termination() -> None:
    """SIGTERM and SIGINT back to Python's defaults (a command that starts processes of its
    own: they must not inherit sph's start-up handler)."""
    if threading_main() and signal.getsignal(signal.SIGTERM) is _starting:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)


def threading_main() -> bool:
    """Whether this is the main thread (only it may install signal handlers)."""
    import threading

    return threading.current_thread() is threading.main_thread()


def _main(argv=None) -> int:
    args = _parser().parse_args(argv)
    prepare()
    if args.command == "sweep":
        from sphcore.sweep import main as sweep_main

        default_termination()  # the sweep's cluster and variants are processes of their own
        return sweep_main(args)
    from sphcore.plugin import pluginhost
    from sphcore.run import runner

    try:
        if args.command == "plugins":
            for row in pluginhost.describe():
                what = f"BROKEN: {row['broken']}" if row["broken"] else f"hooks: {', '.join(row['hooks'])}"
                print(f"{row['name']:<16} {row['dist']} {row['version']}  {what}")
            return 0
        if args.command == "options":
            return _options(args.plugin)
        if args.command == "check":
            # the same validation as `sph run` (case, memory estimate, output path, first
            # step), so that whatever check accepts, run starts
            from sphcore.run.build import build

            case, pm = runner.load(args.case_dir, args.overrides, args.t_end)
            out = runner.output_path(case, args.output)
            try:
                sim = build(case, pm, settle=False)  # particles, sound speed, plugin set-up; no step
            except CaseError as e:  # as run says it: a key given on the command line names the option
                raise runner.blame_option(e, args.overrides, args.t_end) from None
            dt = runner.first_step(sim, args.overrides, args.t_end)
            clip = any(b["clip"] for b in case.blocks)
            why = ("beyond a wall plane (clip), " if clip else "") + "inside a solid or closer than a radius to a face"
            walls = (f"{case.faces.count} wall faces ({sim.state.removed_by_walls} particles of the blocks "
                     f"not created: {why}), " if case.faces.count or clip else "")
            print(f"{case.file}: ok: {case.dim}D, {sim.state.n} particles, {case.planes.count} wall planes, {walls}"
                  f"h = {sim.params.h:.4g} m, c0 = {sim.params.c0:.4g} m/s, first dt ~ {dt:.3g} s, "
                  f"plugins: {', '.join(case.config['plugins']['use']) or 'none'}; output: {out.resolve()}")
            if case.config["relax"]["time"] > 0:
                print(f"relax: {case.config['relax']['time']:g} s of damped motion before t = 0, done by sph run "
                      "(not by check; its first step is sized here from the unrelaxed start)")
            if out.exists() and (not out.is_dir() or any(out.iterdir())):  # what run would say about it
                print(f"{out.resolve()}: exists and is not empty: sph run needs --overwrite (sph's files only), "
                      "--restart or --output DIR")
            return 0
        result = runner.run(args.case_dir, args.output, args.overrides, args.t_end, args.overwrite,
                            args.restart, args.progress)
    except CaseError as e:
        return _fail(str(e), 2)
    except (OutputError, pluginhost.PluginLoadError) as e:
        return _fail(str(e), 2)
    except KeyboardInterrupt:  # Ctrl-C before the run's own handler is installed (set-up)
        return _fail("interrupted during set-up; nothing written", 128 + signal.SIGINT)
    summary, status = result.summary, result.status
    print(f"{summary['case']}: {status}: t = {summary['t']:.6g} s, {summary['steps']} steps, "
          f"{summary['n_particles']} particles, {summary['wall_time_s']:.2f} s wall, "
          f"{summary['particle_steps_per_s']:.3g} particle-steps/s, "
          f"peak memory {summary['peak_memory_mb']:.0f} MB")
    print(f"{summary['case']}: wrote {summary['output_dir']}")
    if status in ("unstable", "output_error"):
        return _fail(summary["message"], 1)
    if status == "stopped":
        print(f"sph: {summary['message']}", file=sys.stderr)
        return 128 + int(result.signum or signal.SIGINT)
    return 0


def _options(only=None) -> int:
    """Print every case key: the core's tables and each usable plugin's."""
    from sphcore.case.options import Option
    from sphcore.plugin import pluginhost

    tables = pluginhost.option_tables()
    owners = {o for o, _ in tables}
    usable = {name for name, info in pluginhost.available().items() if not info.error}
    if only is not None and only not in owners:
        if only in usable:  # a plugin that takes no options is still a plugin
            print(f"plugin {only}: no options (select it with [plugins] use = [..., \"{only}\"])")
            return 0
        return _fail(f"no plugin {only!r} (known: {', '.join(sorted(owners | usable))})", 2)
    for (owner, table), schema in tables.items():
        if only is not None and owner != only:
            continue
        rows = schema.items() if isinstance(schema, dict) else [("", schema)]
        print(f"[{table}]" + ("" if owner == "core" else f"  (plugin {owner})"))
        for key, opt in rows:
            if isinstance(opt, Option):
                default = "derived" if opt.default is None else repr(opt.default)
                print(f"  {key or table:<18} = {default:<12} {opt.describe()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
