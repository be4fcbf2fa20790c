"""The run state: everything that makes a run what it is at one instant, in one object.

A :class:`RunState` holds

- ``particles``: the integrated particles (:class:`sphcore.physics.particles.ParticleState`);
- ``clock``: t, step, dt and t_end (:class:`Clock`);
- ``rates``: the accelerations and density rates of the current particles, and whether they
  are current (:class:`Rates`; the leapfrog reuses them at the start of the next step);
- ``stats`` and ``kept``: each plugin's figures (merged into summary.json) and the state it
  keeps across a restart, by plugin name;
- ``counters``: how often each core kernel ran;
- the pair-list anchor: the positions the kept pair list was built from
  (:class:`sphcore.neighbours.pairlist.PairList`), so that a restart finds the same pairs.

What needs the state whole uses this object and nothing else: a checkpoint writes
:meth:`RunState.payload` and a restart reads it back with :meth:`RunState.from_payload`;
the start-up probe (:mod:`sphcore.run.budget`) takes a :meth:`RunState.snapshot` before it
evaluates the first rates and puts it back with :meth:`RunState.restore`. Arrays are only
read and written through numpy's array interface here, so that they could live on another
device behind the same methods.

Where the arrays live: on the host today. Two kinds of code read them. The kernels (the
core's and the boundary plugins') take the arrays as they are, where they are; a device
backend gives them device arrays and device kernels together. Everything that takes the
particles out of the run (the particle writers, the checkpoint's payload) asks for
:meth:`RunState.host`, the particles as host numpy arrays, and never reads
``particles`` directly, so that those paths need no change when the arrays move.
"""

from __future__ import annotations

import copy
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from sphcore.physics.particles import ParticleState


@dataclass
class Clock:
    """Simulated time (s) at the start of the next step, steps completed, the last step (s;
    0 before the first) and the time the run goes to (s)."""

    t: float = 0.0
    step: int = 0
    dt: float = 0.0
    t_end: float = 0.0


class Rates:
    """The rates of the current particles: ``acc`` (n, dim) in m/s^2 and ``drho`` (n,) in
    kg/m^3/s; ``fresh`` says whether they are those of the particles as they are now."""

    def __init__(self, n: int, dim: int):
        self.acc = np.zeros((n, dim))
        self.drho = np.zeros(n)
        self.fresh = False

    def fits(self, n: int, dim: int) -> bool:
        return self.acc.shape == (n, dim) and self.drho.shape == (n,)


@dataclass
class Snapshot:
    """A copy of a :class:`RunState` (:meth:`RunState.snapshot`); nothing in it is shared
    with the live state."""

    particles: dict[str, np.ndarray]
    clock: Clock
    acc: np.ndarray
    drho: np.ndarray
    fresh: bool
    stats: dict
    kept: dict
    counters: Counter
    anchor: np.ndarray | None
    extra: dict = field(default_factory=dict)


class RunState:
    """See the module docstring. ``pairs``, when set, is the run's kept pair list, whose
    anchor belongs to the state."""

    def __init__(self, particles: ParticleState, t_end: float):
        self.particles = particles
        self.clock = Clock(t_end=t_end)
        self.rates = Rates(particles.n, particles.dim)
        self.stats: dict[str, dict] = {}
        self.kept: dict[str, dict] = {}
        self.counters: Counter = Counter()
        self.pairs = None
        self._anchor = None  # a pair-list anchor read from a checkpoint, until a pair list is attached

    def host(self) -> ParticleState:
        """The particles as numpy arrays in host memory, for what leaves the run (files,
        checkpoints). Read-only by contract; today the particles themselves (no copy)."""
        return self.particles

    # -- pieces ---------------------------------------------------------------------------

    def fit_rates(self) -> bool:
        """Rates arrays of the particles' size (after a plugin added particles); True when
        they were reallocated (and so are not current)."""
        st = self.particles
        if self.rates.fits(st.n, st.dim):
            return False
        self.rates = Rates(st.n, st.dim)
        return True

    def attach_pairs(self, pairs) -> None:
        """Make ``pairs`` (a PairList, or None) the run's kept pair list; an anchor read from
        a checkpoint rebuilds its lists from the same positions."""
        self.pairs = pairs
        if pairs is not None and self._anchor is not None:
            pairs.restore(self._anchor)
        self._anchor = None

    def anchor(self) -> np.ndarray | None:
        """The positions the kept pair list was built from (None: no list is kept)."""
        return self.pairs.checkpoint() if self.pairs is not None else self._anchor

    # -- snapshot and restore -------------------------------------------------------------

    def snapshot(self) -> Snapshot:
        anchor = self.anchor()
        return Snapshot({name: a.copy() for name, a in self.particles.arrays()}, copy.copy(self.clock),
                        self.rates.acc.copy(), self.rates.drho.copy(), self.rates.fresh,
                        copy.deepcopy(self.stats), copy.deepcopy(self.kept), self.counters.copy(),
                        None if anchor is None else anchor.copy())

    def restore(self, snap: Snapshot) -> None:
        """Put ``snap`` back, in place: the particle and rate arrays keep their identity
        (kernels and plugins may hold them), and so do the plugins' stats and kept dicts
        and the lists in them (a series a plugin appends to)."""
        for name, a in self.particles.arrays():
            a[...] = snap.particles[name]
        self.clock = copy.copy(snap.clock)
        self.rates.acc[...] = snap.acc
        self.rates.drho[...] = snap.drho
        self.rates.fresh = snap.fresh
        _restore_namespaces(self.stats, snap.stats)
        _restore_namespaces(self.kept, snap.kept)
        self.counters.clear()
        self.counters.update(snap.counters)
        if self.pairs is not None:
            if snap.anchor is None:
                self.pairs.invalidate()  # built anew from the positions at the next evaluation
            else:
                self.pairs.restore(snap.anchor)

    # -- checkpoint payload ---------------------------------------------------------------

    def payload(self) -> tuple[dict, dict[str, np.ndarray]]:
        """(metadata, arrays) of a checkpoint: every particle array, the rates, the pair-list
        anchor, each plugin's kept arrays; the clock, stats, kept values and counters."""
        arrays = {f"state_{name}": a for name, a in self.host().arrays()}
        arrays["acc"] = self.rates.acc
        arrays["drho"] = self.rates.drho
        anchor = self.anchor()
        if anchor is not None:
            arrays["pair_list_positions"] = anchor  # the lists are rebuilt from these
        kept = {}
        for plugin, values in self.kept.items():
            kept[plugin] = {}
            for key, value in values.items():
                if isinstance(value, np.ndarray):
                    arrays[f"kept_{plugin}_{key}"] = value
                    kept[plugin][key] = {"__array__": f"kept_{plugin}_{key}"}
                else:
                    kept[plugin][key] = value
        c = self.clock
        meta = {"t": c.t, "step": c.step, "dt": c.dt, "stats": self.stats, "kept": kept,
                "counters": dict(self.counters), "fresh": bool(self.rates.fresh)}
        return meta, arrays

    def load_payload(self, meta: dict, arrays: dict[str, np.ndarray]) -> None:
        """Take the particles, clock, rates, stats, kept state and counters of a checkpoint
        (:meth:`payload`); t_end stays the case's."""
        names = [name for name, _ in self.particles.arrays()]
        self.particles = ParticleState(**{name: arrays[f"state_{name}"] for name in names})
        self.clock = Clock(meta["t"], meta["step"], meta["dt"], self.clock.t_end)
        self.rates = Rates(self.particles.n, self.particles.dim)
        if arrays["acc"].shape != self.rates.acc.shape:
            raise ValueError(f"its accelerations have the shape {arrays['acc'].shape}, its particles "
                             f"{self.rates.acc.shape}")
        self.rates.acc[...] = arrays["acc"]
        if "drho" in arrays and arrays["drho"].shape == self.rates.drho.shape:
            self.rates.drho[...] = arrays["drho"]
        self.rates.fresh = bool(meta["fresh"])
        for plugin, values in meta["stats"].items():
            self.stats.setdefault(plugin, {}).update(values)
        for plugin, values in meta.get("kept", {}).items():
            self.kept.setdefault(plugin, {}).update(
                {k: arrays[v["__array__"]] if isinstance(v, dict) and "__array__" in v else v
                 for k, v in values.items()})
        self.counters.update(meta["counters"])
        self._anchor = arrays.get("pair_list_positions")


def _restore_namespaces(live: dict, saved: dict) -> None:
    """``live`` (plugin name -> dict) made equal to ``saved`` without replacing the dicts a
    plugin holds, nor the lists in them."""
    for name in list(live):
        if name not in saved:
            del live[name]
    for name, values in saved.items():
        target = live.setdefault(name, {})
        for key in list(target):
            if key not in values:
                del target[key]
        for key, value in values.items():
            if isinstance(target.get(key), list) and isinstance(value, list):
                target[key][:] = copy.deepcopy(value)
            else:
                target[key] = copy.deepcopy(value)  # the snapshot stays as it was taken
