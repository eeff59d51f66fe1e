"""The crank train in motion: the equation of motion and its solutions.

Holds the engine prepared as periodic tables over one cycle (:mod:`.crank_train`; made
once and reused: :mod:`.prepared`), the equation of motion and its integrators
(:mod:`.equation`), the periodic steady state (:mod:`.steady`) and many of them at once
(:mod:`.sweep`), transient runs (:mod:`.transient`), loads and the governor
(:mod:`.loads`), per-cycle combustion events (:mod:`.combustion`) and the speed result
ω(θ, t) with δ and orders (:mod:`.result`).

May import: :mod:`rotor.engine`, :mod:`rotor.plotting` (to draw its results) and the
base layer. Never :mod:`rotor.logs`, :mod:`rotor.diagnostics` or :mod:`rotor.design`.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
