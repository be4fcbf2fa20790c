"""The pluggy host: plugins come from the entry-point group ``sphcore``, built-in or not.

Entry points are read once per process. Each run gets its own PluginManager holding one
fresh instance of each plugin its case names, so plugin state never leaks between runs.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib.metadata import entry_points

import pluggy

from . import hookspecs
from .errors import CaseError

GROUP = "sphcore"


@dataclass(frozen=True)
class PluginInfo:
    name: str
    value: str  # "module:Class"
    dist: str
    version: str
    cls: type | None
    error: str = ""  # why it failed to import; the plugin is unusable but the others work


class PluginLoadError(Exception):
    """A plugin could not be imported or implements a hook that does not exist."""


@functools.lru_cache(maxsize=1)
def available() -> dict[str, PluginInfo]:
    """Every plugin installed under the entry-point group, by name (loaded once)."""
    out = {}
    for ep in entry_points(group=GROUP):
        if ep.name in out:
            continue  # the first distribution on sys.path wins, as for any entry point
        dist = ep.dist.name if ep.dist else "?"
        version = ep.dist.version if ep.dist else "?"
        try:
            out[ep.name] = PluginInfo(ep.name, ep.value, dist, version, ep.load())
        except Exception as e:  # a broken plugin names itself when used, and spoils no other
            out[ep.name] = PluginInfo(ep.name, ep.value, dist, version, None, f"{type(e).__name__}: {e}")
    return out


def refresh() -> None:
    """Forget the cached entry points (after installing a plugin in the same process)."""
    available.cache_clear()


def _instance(info: PluginInfo):
    if info.cls is None:
        raise PluginLoadError(f"plugin {info.name!r} ({info.value}, {info.dist}) failed to import: {info.error}")
    return info.cls()


def _manager() -> pluggy.PluginManager:
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    return pm


def make_manager(names, file="case.toml") -> pluggy.PluginManager:
    """A manager with one new instance of each named plugin; unknown names are CaseErrors."""
    plugins = available()
    pm = _manager()
    for name in names:
        if name not in plugins:
            raise CaseError(file, "plugins.use", f"unknown plugin {name!r} (installed: {', '.join(sorted(plugins)) or 'none'})")
        if pm.get_plugin(name) is not None:
            raise CaseError(file, "plugins.use", f"plugin {name!r} is listed twice")
        pm.register(_instance(plugins[name]), name=name)
    check(pm)
    return pm


def check(pm: pluggy.PluginManager) -> None:
    """Fail loudly on a hook implementation with no matching specification (a misspelt hook)."""
    try:
        pm.check_pending()
    except pluggy.PluginValidationError as e:
        raise PluginLoadError(f"plugin {pm.get_name(e.plugin) or '?'!r}: {e}") from e


def hooks_of(pm: pluggy.PluginManager, name: str) -> list[str]:
    plugin = pm.get_plugin(name)
    return sorted(h.name for h in pm.get_hookcallers(plugin) or [])


def describe() -> list[dict]:
    """Name, distribution, version and implemented hooks of every installed plugin."""
    rows = []
    for name, info in sorted(available().items()):
        if info.cls is None:
            rows.append({"name": name, "dist": info.dist, "version": info.version, "hooks": [f"BROKEN: {info.error}"]})
            continue
        try:
            pm = _manager()
            pm.register(_instance(info), name=name)
            check(pm)
        except PluginLoadError as e:
            rows.append({"name": name, "dist": info.dist, "version": info.version, "hooks": [f"BROKEN: {e}"]})
            continue
        rows.append({"name": name, "dist": info.dist, "version": info.version, "hooks": hooks_of(pm, name)})
    return rows


def option_schemas() -> dict:
    """The case tables every installed plugin declares: {table: {key: Option}}.

    Tables of installed but unselected plugins are validated too, so switching plugins is
    one change to ``plugins.use``.
    """
    schemas = {}
    for name, info in sorted(available().items()):
        if info.cls is None:
            continue  # its tables are unknown; using it reports the import error
        try:
            pm = _manager()
            pm.register(_instance(info), name=name)
            check(pm)
        except PluginLoadError:
            continue  # broken: reported when a case selects it (make_manager) or by `sph plugins`
        for declared in pm.hook.sph_options():
            for table, schema in (declared or {}).items():
                if table in schemas:
                    raise PluginLoadError(f"plugin {name!r} declares table [{table}] which another plugin owns")
                schemas[table] = schema
    return schemas
