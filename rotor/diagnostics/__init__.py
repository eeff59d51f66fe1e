"""From measured speed back to the cylinders: torque, IMEP and misfires.

Holds inverse dynamics (:mod:`.inverse`), model-based identification of each firing's
combustion scale (:mod:`.identification`), the misfire index (:mod:`.misfire`),
calibration against a pressure channel (:mod:`.calibration`; the record it keeps,
:mod:`.calibration_record`; the pressure channel's work and IMEP, :mod:`.pressure_work`;
its gain from motored cycles, :mod:`.pegging`), the diagnose workflow
(:mod:`.diagnosis`, with the charge scaling of :mod:`.charge`), TDC from the crank speed
alone and a calibration checked against the recording (:mod:`.phase`), and simulated
bench recordings (:mod:`.synthetic`).

May import: :mod:`rotor.dynamics`, :mod:`rotor.logs`, :mod:`rotor.engine`,
:mod:`rotor.plotting` (to draw its results) and the base layer. Never
:mod:`rotor.design` or :mod:`rotor.cli`.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
