"""The pluggy host: plugins come from the entry-point group ``sphcore``, built-in or not.

Entry points are read once per process. Each plugin is checked alone when it is first
loaded: an import error, a hook whose name is not specified, or a hook argument the
specification does not have marks that plugin *broken* with a one-line reason naming it and
its distribution. A broken plugin spoils nothing else: cases that do not select it run,
``sph plugins`` lists it as broken, and a case that selects it (or sets its table) gets
the reason as a clean error (exit 2).

Each run gets its own PluginManager holding one fresh instance of each plugin its case
names, so plugin state never leaks between runs.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib.metadata import entry_points

import pluggy

from sphcore.case import defaults
from sphcore.errors import CaseError
from sphcore.plugin import hookspecs

GROUP = "sphcore"


class PluginLoadError(Exception):
    """A plugin cannot be used: it failed to import, implements a hook that does not exist,
    takes an argument its hook does not have, or failed while declaring its options."""


@dataclass(frozen=True)
class PluginInfo:
    name: str
    value: str  # "module:Class"
    dist: str
    version: str
    cls: type | None
    error: str = ""  # why the plugin is broken; "" when it is usable
    tables: dict | None = None  # {table: {key: Option}} it declares (None when unknown)

    @property
    def label(self) -> str:
        return f"plugin {self.name!r} ({self.value}, distribution {self.dist} {self.version})"

    def fail(self):
        raise PluginLoadError(f"{self.label} is broken: {self.error}")


def _manager() -> pluggy.PluginManager:
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    return pm


def _one_line(e: Exception) -> str:
    return " ".join(f"{type(e).__name__}: {e}".split())


def _tables_of(plugin) -> dict:
    """The case tables an instance declares through ``sph_options`` (called directly),
    checked to be {table: {key: Option}}."""
    from sphcore.case.options import Option

    declare = getattr(plugin, "sph_options", None)
    tables = declare() if declare else None
    tables = {} if tables is None else tables
    if not isinstance(tables, dict) or not all(
            isinstance(t, str) and isinstance(body, dict)
            and all(isinstance(k, str) and isinstance(o, Option) for k, o in body.items())
            for t, body in tables.items()):
        raise TypeError("sph_options must return {table: {key: sphcore.api.Option}}")
    return dict(tables)


def _inspect(name, value, dist, version, load) -> PluginInfo:
    """Load and check one plugin alone; a failure makes it broken, never raises."""
    try:
        cls = load()
    except Exception as e:  # any import-time error of third-party code
        return PluginInfo(name, value, dist, version, None, f"import failed: {_one_line(e)}")
    tables = None
    try:
        instance = cls()
        tables = _tables_of(instance)
        pm = _manager()
        pm.register(instance, name=name)
        pm.check_pending()
    except pluggy.PluginValidationError as e:
        return PluginInfo(name, value, dist, version, cls, f"invalid hook: {' '.join(str(e).split())}", tables)
    except Exception as e:
        return PluginInfo(name, value, dist, version, cls, f"failed while loading: {_one_line(e)}", tables)
    return PluginInfo(name, value, dist, version, cls, "", tables)


@functools.lru_cache(maxsize=1)
def _entry_points() -> dict:
    """The entry points of the group by name, read once (nothing imported)."""
    out = {}
    for ep in entry_points(group=GROUP):
        out.setdefault(ep.name, ep)  # the first distribution on sys.path wins, as for any entry point
    return out


@functools.lru_cache(maxsize=None)
def info(name: str) -> PluginInfo | None:
    """One installed plugin, loaded and checked on first use (None: not installed)."""
    ep = _entry_points().get(name)
    if ep is None:
        return None
    dist = ep.dist.name if ep.dist else "?"
    version = ep.dist.version if ep.dist else "?"
    return _inspect(ep.name, ep.value, dist, version, ep.load)


def available() -> dict[str, PluginInfo]:
    """Every plugin installed under the entry-point group, by name (each loaded and checked once)."""
    return {name: info(name) for name in _entry_points()}


def refresh() -> None:
    """Forget the cached entry points (after installing a plugin in the same process)."""
    _entry_points.cache_clear()
    info.cache_clear()


def make_manager(names, file="case.toml") -> pluggy.PluginManager:
    """A manager with one new instance of each named plugin; unknown names are CaseErrors,
    broken plugins PluginLoadErrors naming the plugin and its distribution."""
    pm = _manager()
    for name in names:
        plugin = info(name)
        if plugin is None:
            installed = ", ".join(sorted(_entry_points())) or "none"
            raise CaseError(file, "plugins.use", f"unknown plugin {name!r} (installed: {installed})")
        if pm.get_plugin(name) is not None:
            raise CaseError(file, "plugins.use", f"plugin {name!r} is listed twice")
        if plugin.error:
            plugin.fail()
        pm.register(plugin.cls(), name=name)
    return pm


def option_schemas(file="case.toml", sections=None) -> dict:
    """The case tables that installed plugins declare: {table: {key: Option}}.

    ``sections``: the case (its raw tables); None: every installed plugin's tables. For a
    case, the plugins it uses and those named like one of its tables are loaded; a table
    that neither the core nor they own loads every installed plugin to find its owner, so
    the tables of installed but unselected plugins are validated too (switching plugins is
    one change to ``plugins.use``) while a run imports only what it may need (loading all
    nine built-in plugins cost ~40 ms of every run's start). A table of ``sections`` that
    belongs to a broken plugin raises that plugin's error instead of "unknown section".
    """
    if sections is None:
        plugins = available()
    else:
        names = set(_entry_points())
        wanted = (set(sections) | set(_uses(sections))) & names
        plugins = {name: info(name) for name in wanted}
        owned = set(defaults.CORE).union(*[p.tables or () for p in plugins.values()])
        if not set(sections) <= owned:
            plugins = available()
    schemas, owner = {}, {}
    for name, plugin in sorted(plugins.items()):
        tables = plugin.tables
        if plugin.error:
            known = set(tables or ()) | {name}
            if known & set(sections or ()):
                plugin.fail()
            continue
        for table, schema in (tables or {}).items():
            if table in schemas:
                raise PluginLoadError(f"{plugin.label} declares table [{table}] which plugin {owner[table]!r} owns")
            schemas[table], owner[table] = schema, name
    return schemas


def option_tables() -> dict:
    """Every case table a user can write, in the order ``sph options`` prints them:
    ``{(owner, table): schema}``, owner ``"core"`` or a usable plugin's name, schema
    ``{key: Option}`` (or one Option for a table that is a single value)."""
    tables = {("core", k): v for k, v in defaults.CORE.items()}
    tables.update({("core", "blocks[]"): defaults.BLOCK, ("core", "domain.planes[]"): defaults.PLANE,
                   ("core", "domain.walls[]"): defaults.WALL})
    for name, plugin in sorted(available().items()):
        if not plugin.error:
            tables.update({(name, t): schema for t, schema in (plugin.tables or {}).items()})
    return tables


def _uses(raw) -> list:
    """The plugin names of a raw case's plugins.use, as far as they are strings (the
    validation reports the rest)."""
    use = raw.get("plugins", {}).get("use") if isinstance(raw.get("plugins"), dict) else None
    return [u for u in use if isinstance(u, str)] if isinstance(use, list) else []


def configure(pm, case) -> None:
    """Call every selected plugin's ``sph_configure``; a crash (not a CaseError) there is
    reported as that plugin's fault."""
    for impl in pm.hook.sph_configure.get_hookimpls():
        try:
            impl.function(*[{"case": case}[a] for a in impl.argnames])
        except CaseError:
            raise
        except Exception as e:
            plugin = info(impl.plugin_name)
            label = plugin.label if plugin else f"plugin {impl.plugin_name!r}"
            raise PluginLoadError(f"{label} failed in sph_configure: {_one_line(e)}") from e
    check_moving_walls(pm, case)


#: hooks of a plugin that acts on the output alone: it runs with moving walls unasked
OUTPUT_ONLY = frozenset({"sph_options", "sph_configure", "sph_output", "sph_summary", "sph_finish"})


def check_moving_walls(pm, case) -> None:
    """Refuse a case with moving walls when a selected plugin that acts on the run does not
    say it honours them (``sph_moving_walls``), naming the plugin and the motion's key."""
    if not getattr(case, "moving", ()):
        return
    honours = {impl.plugin_name for impl in pm.hook.sph_moving_walls.get_hookimpls()
               if impl.function(*[{}[a] for a in impl.argnames])}
    for name, plugin in pm.list_name_plugin():
        hooks = {h.name for h in pm.get_hookcallers(plugin) or []}
        if hooks - OUTPUT_ONLY - {"sph_moving_walls"} and name not in honours:
            raise CaseError(getattr(case, "file", "case.toml"), case.moving[0].name,
                            f"plugin {name!r} does not support moving walls; remove the motion or the plugin "
                            "(plugins.use)")


def summaries(pm, ctx) -> dict[str, dict]:
    """Each plugin's figures for summary.json, by plugin name: its ``ctx.stats`` merged with
    what its ``sph_summary`` returns."""
    out = ctx.all_stats()
    for impl in pm.hook.sph_summary.get_hookimpls():
        figures = impl.function(*[{"ctx": ctx}[a] for a in impl.argnames])
        if figures:
            out.setdefault(impl.plugin_name, {}).update(figures)
    return out


def hooks_of(pm: pluggy.PluginManager, name: str) -> list[str]:
    plugin = pm.get_plugin(name)
    return sorted(h.name for h in pm.get_hookcallers(plugin) or [])


def describe() -> list[dict]:
    """Name, distribution, version and implemented hooks (or why it is broken) of every
    installed plugin."""
    rows = []
    for name, info in sorted(available().items()):
        row = {"name": name, "dist": info.dist, "version": info.version, "tables": sorted(info.tables or ()),
               "broken": info.error}
        if not info.error:
            pm = _manager()
            pm.register(info.cls(), name=name)
            row["hooks"] = hooks_of(pm, name)
        else:
            row["hooks"] = []
        rows.append(row)
    return rows


def _no_implementation(**kwargs):
    return []


def _no_first_result(**kwargs):
    return None


def _direct_call(impl, firstresult: bool):
    """The call pluggy makes for a hook with the single implementation ``impl`` (no
    wrapper): its arguments by name, a result of None dropped (a first-result hook returns
    the result itself). Exceptions pass through as pluggy passes them."""
    function, argnames = impl.function, tuple(impl.argnames)

    def call(**kwargs):
        result = function(*[kwargs[a] for a in argnames])
        if firstresult:
            return result
        return [] if result is None else [result]

    return call


class HookRelay:
    """``pm.hook`` for the time loop. A hook that no registered plugin implements is a plain
    function returning [] instead of a pluggy call (~25 us each, seven per step), so hooks
    that do nothing cost nothing; a hook with one implementation and no wrapper calls it
    directly, as pluggy would, without pluggy's dispatch (PySPH's dam break: the reflective
    walls' ``sph_after_integrate`` on every step). Hooks with several implementations or a
    wrapper go through pluggy. Built once the run's plugins are registered; pluggy's call
    tracing (``pm.enable_tracing``) sees only the hooks that go through it."""

    def __init__(self, pm: pluggy.PluginManager):
        self.implemented = set()
        for name in dir(pm.hook):
            if not name.startswith("sph_"):
                continue
            caller = getattr(pm.hook, name)
            impls = caller.get_hookimpls()
            firstresult = bool(caller.spec and caller.spec.opts.get("firstresult"))
            if not impls:
                setattr(self, name, _no_first_result if firstresult else _no_implementation)
                continue
            self.implemented.add(name)
            single = len(impls) == 1 and not (impls[0].hookwrapper or getattr(impls[0], "wrapper", False))
            setattr(self, name, _direct_call(impls[0], firstresult) if single else caller)
