"""Designing and checking the crank train: flywheel sizing, bearing loads, balancing, and
the report of the whole kinematic and dynamic calculation.

:mod:`.flywheel` holds the textbook flywheel rule (:func:`~.flywheel.textbook_flywheel`,
a :class:`~.flywheel.TextbookFlywheel`), the smallest flywheel found through the steady
state (:func:`~.flywheel.design_flywheel`, a :class:`~.flywheel.FlywheelDesign` that
knows its engine and computes its own δ sweep for the plot) and the lightest disc for an
inertia (:func:`~.flywheel.lightest_disc`, a :class:`~.flywheel.DiscFlywheel`).
:mod:`.bearings` holds the loads on the crank pins, big ends, main journals and main
bearings, the wear diagrams and the running torques (:func:`~.bearings.bearing_loads`);
:mod:`.balance` the free forces and moments by order and the textbook's six conditions
(:func:`~.balance.balance`); :mod:`.report` writes the whole course-project calculation as
one HTML page with its figures and tables (:func:`~.report.report`). Every result speaks
:class:`rotor.results.Result`; the drawing is in :mod:`rotor.plotting`.

May import: :mod:`rotor.dynamics`, :mod:`rotor.engine`, :mod:`rotor.plotting` (to draw its
results) and the base layer. Never :mod:`rotor.logs`, :mod:`rotor.diagnostics` or
:mod:`rotor.cli`.
"""

from ..cache import submodules_on_demand

__getattr__ = submodules_on_demand(__name__)
