"""Torsional vibration: the crankshaft as a chain of masses on torsional springs.

Holds the multi-mass chain and its matrices, built from numbers, from shaft geometry or
from an engine's ``[torsion]`` table (:mod:`.model`); the free vibration by the
eigenproblem and by Holzer's transfer-matrix method (:mod:`.modes`); the Campbell
diagram with the engine orders and critical speeds (:mod:`.campbell`); the chain driven
by its engine's mechanisms and gas torques (:mod:`.driven`), its forced response at an
operating point and over speed by harmonic balance (:mod:`.response`) and its transients
in time (:mod:`.transient`).

May import: :mod:`rotor.dynamics`, :mod:`rotor.engine`, :mod:`rotor.plotting` (its
results draw themselves there) and the base layer. Never :mod:`rotor.logs`,
:mod:`rotor.diagnostics`, :mod:`rotor.design` or :mod:`rotor.cli`.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
