"""The time loop's hook relay (sphcore.plugin.pluginhost.HookRelay) returns what pluggy returns:
no implementation, one (called directly), several, a wrapper, a first-result hook."""

from __future__ import annotations

import pluggy
import pytest

from sphcore.plugin.pluginhost import HookRelay

spec = pluggy.HookspecMarker("relaytest")
impl = pluggy.HookimplMarker("relaytest")


class Specs:
    @spec
    def sph_step(self, ctx, x):
        """A per-step hook."""

    @spec(firstresult=True)
    def sph_first(self, ctx, x):
        """A first-result hook."""

    @spec
    def sph_unused(self, ctx):
        """No plugin implements it."""


class Doubler:
    @impl
    def sph_step(self, x):  # takes a subset of the arguments, as plugins may
        return 2 * x

    @impl
    def sph_first(self, ctx, x):
        return None if x < 0 else x + ctx


class Silent:
    @impl
    def sph_step(self, ctx, x):
        return None


class Failing:
    @impl
    def sph_step(self, x):
        raise ZeroDivisionError("plugin failed")


class Wrapper:
    def __init__(self):
        self.seen = []

    @impl(wrapper=True)
    def sph_step(self, x):
        self.seen.append(x)
        return (yield)


def manager(*plugins):
    pm = pluggy.PluginManager("relaytest")
    pm.add_hookspecs(Specs)
    for p in plugins:
        pm.register(p)
    return pm


@pytest.mark.parametrize("plugins", [(), (Doubler(),), (Silent(),), (Doubler(), Silent()), (Doubler(), Doubler())])
@pytest.mark.parametrize("x", [-3, 0, 5])
def test_relay_returns_what_pluggy_returns(plugins, x):
    pm = manager(*plugins)
    relay = HookRelay(pm)
    for name in ("sph_step", "sph_first", "sph_unused"):
        kwargs = {"ctx": 10} if name == "sph_unused" else {"ctx": 10, "x": x}
        assert getattr(relay, name)(**kwargs) == getattr(pm.hook, name)(**kwargs), name
    assert relay.implemented == {n for n in ("sph_step", "sph_first") if any(hasattr(p, n) for p in plugins)}


def test_one_implementation_is_called_without_pluggy():
    pm = manager(Doubler())
    relay = HookRelay(pm)
    assert relay.sph_step is not pm.hook.sph_step
    assert relay.sph_step(ctx=None, x=4) == [8]
    assert relay.sph_first(ctx=1, x=4) == 5 and relay.sph_first(ctx=1, x=-1) is None


def test_a_failing_plugin_raises_through_the_relay():
    relay = HookRelay(manager(Failing()))
    with pytest.raises(ZeroDivisionError, match="plugin failed"):
        relay.sph_step(ctx=None, x=1)


def test_a_wrapper_goes_through_pluggy():
    w = Wrapper()
    pm = manager(Doubler(), w)
    relay = HookRelay(pm)
    assert relay.sph_step is pm.hook.sph_step
    assert relay.sph_step(ctx=None, x=3) == [6] and w.seen == [3]


class OldWrapper:
    @impl(hookwrapper=True)
    def sph_step(self, x):
        yield


@pytest.mark.parametrize("make", [Wrapper, OldWrapper])
def test_a_lone_wrapper_goes_through_pluggy(make):
    pm = manager(make())
    relay = HookRelay(pm)
    assert relay.sph_step is pm.hook.sph_step
    assert relay.sph_step(ctx=None, x=3) == pm.hook.sph_step(ctx=None, x=3) == []
