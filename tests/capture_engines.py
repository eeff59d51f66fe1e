"""Engine files for the logic-analyser captures of the shared data, written from their README
(the cylinders, the layout and the displacement); the rod, masses, inertia and cycle are the
estimates of an engine of that size (no capture states them). Used by the tests that diagnose
and monitor the captures."""

from __future__ import annotations

MECHANISM = """
name = "{name}"
strokes = 4
cylinders = {cylinders}

[geometry]
bore_m = {bore}
stroke_m = {stroke}
rod_length_m = {rod}

[masses]
reciprocating_kg = 0.6
rotating_kg = 0.4

[crankshaft]
inertia_kgm2 = 0.2

[layout]
throw_angles_deg = {throws}
firing_order = {order}

[operating]
rpm = 800
"""

CYCLE = """
[pressure]
kind = "wiebe"
compression_ratio = 10.0
intake_pa = 90000
exhaust_pa = 105000
imep_pa = 3.0e5
start_deg = 350.0
duration_deg = 60.0
form_factor = 2.0
compression_exponent = 1.33
expansion_exponent = 1.28
exhaust_open_deg = 500.0
blowdown_deg = 60.0
overlap_deg = 30.0
crankcase_pa = 101325
"""

FOUR = dict(cylinders=4, throws="[0, 180, 180, 0]", order="[1, 3, 4, 2]")
SIX = dict(  # a V6 of 60° banks
    cylinders=6,
    throws="[0, 0, 120, 120, 240, 240]\nbank_angles_deg = [0, 60, 0, 60, 0, 60]",
    order="[1, 2, 3, 4, 5, 6]",
)
EIGHT = dict(  # the v8 preset's cross-plane crank
    cylinders=8,
    throws="[0, 270, 90, 180, 0, 270, 90, 180]\nbank_angles_deg = [-45, -45, -45, -45, 45, 45, 45, 45]",
    order="[1, 5, 4, 8, 6, 3, 7, 2]",
)


def engine_toml(name: str, bore_m: float, stroke_m: float, layout: dict, *, cycle: bool = True) -> str:
    """The engine file's text: ``name``, ``bore_m`` and ``stroke_m`` [m], a ``layout`` above,
    the rod 1.65 strokes long; ``cycle``: with the Wiebe cycle (without it the model has no
    combustion torque)."""
    text = MECHANISM.format(name=name, bore=bore_m, stroke=stroke_m, rod=1.65 * stroke_m, **layout)
    return text + (CYCLE if cycle else "")
