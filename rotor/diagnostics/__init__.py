"""From measured speed back to the cylinders: torque, IMEP and misfires.

Holds inverse dynamics (:mod:`.inverse`), model-based identification of each firing's
combustion scale (:mod:`.identification`), the misfire index (:mod:`.misfire`),
calibration against a pressure channel and the diagnose workflow
(:mod:`.calibration`), TDC from the crank speed alone and a calibration checked against
the recording (:mod:`.phase`), and simulated bench recordings (:mod:`.synthetic`).

May import: :mod:`rotor.dynamics`, :mod:`rotor.logs`, :mod:`rotor.engine`,
:mod:`rotor.plotting` (to draw its results) and the ground floor. Never
:mod:`rotor.design` or :mod:`rotor.cli`.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
