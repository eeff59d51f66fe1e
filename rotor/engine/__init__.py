"""The engine: its description and file, and everything computed from its geometry alone.

Holds the engine model (:mod:`.model`) and its TOML file (:mod:`.file`), piston and rod
kinematics (:mod:`.kinematics`, :mod:`.articulated`, :mod:`.mechanism`), the reduced
inertia I(θ) (:mod:`.inertia`), cylinder pressure sources (:mod:`.pressure`), forces and
torques at a given speed (:mod:`.forces`), friction (:mod:`.friction`), the textbook
one-cylinder table (:mod:`.table`), the one-screen engine summary (:mod:`.summary`) and
the crankshaft as a beam on its main journals (:mod:`.shaft`: where its throws, webs and
journals lie; the bearing loads and the balancing built on it are in :mod:`rotor.design`).
:mod:`.plausible` holds what an engine's numbers may be: their Python types at the API
edge and the plausible range of every input (a bore of 1e300 m is finite, not an engine).

May import: the base layer (:mod:`rotor.units`, :mod:`rotor.errors`,
:mod:`rotor.checks`, :mod:`rotor.fileio`, :mod:`rotor.results`) and :mod:`rotor.plotting`
(its results draw themselves there). Nothing here integrates an equation of motion.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
