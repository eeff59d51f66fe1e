"""Designing the crank train: flywheel sizing (later: bearing loads and balancing).

:mod:`.flywheel` holds the textbook flywheel rule (:func:`~.flywheel.textbook_flywheel`,
a :class:`~.flywheel.TextbookFlywheel`), the smallest flywheel found through the steady
state (:func:`~.flywheel.design_flywheel`, a :class:`~.flywheel.FlywheelDesign` that
knows its engine and computes its own δ sweep for the plot) and the lightest disc for an
inertia (:func:`~.flywheel.lightest_disc`, a :class:`~.flywheel.DiscFlywheel`). Every
result speaks :class:`rotor.results.Result`; the drawing is in :mod:`rotor.plotting.design`.

May import: :mod:`rotor.dynamics`, :mod:`rotor.engine`, :mod:`rotor.plotting` (to draw its
results) and the ground floor. Never :mod:`rotor.logs`, :mod:`rotor.diagnostics` or
:mod:`rotor.cli`.
"""
