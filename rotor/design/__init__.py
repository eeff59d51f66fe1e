"""Designing the crank train: flywheel sizing (later: bearing loads and balancing).

Holds the textbook flywheel rule and the smallest flywheel found through the steady
state (:mod:`.flywheel`).

May import: :mod:`rotor.dynamics`, :mod:`rotor.engine` and the ground floor. Never
:mod:`rotor.logs`, :mod:`rotor.diagnostics`, :mod:`rotor.plotting` or :mod:`rotor.cli`.
"""
