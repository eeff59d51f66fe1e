"""Logged signals: reading recordings and turning a trigger wheel into crank speed.

Holds the log readers (:mod:`.reader`), edge finding in sampled wheel signals
(:mod:`.edges`), trigger wheels, tooth location and tooth-error estimation
(:mod:`.wheel`), the wheel signal read and placed (:mod:`.track`, :mod:`.pattern`), the
recording's crank angle (:mod:`.angle`) and phase: TDC and the firing revolution
(:mod:`.phasing`), and the logged-speed analysis: per-cycle speed, δ and orders
(:mod:`.analysis`).

May import: :mod:`rotor.engine` (the engine's inertia ripple), :mod:`rotor.plotting` (to
draw its results) and the base layer. Never :mod:`rotor.dynamics` or
:mod:`rotor.diagnostics`.

Simulated analog wheel signals with their true edges, to test the readers: :mod:`.synthetic`.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
