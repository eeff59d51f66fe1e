"""`rotor diagnose` reads the logic-analyser captures of the shared data as `rotor analyze`
does (the same wheel, edges and channel), with an engine file written from each capture's
README (its cylinders; the geometry and masses estimates of an engine of that size, TDC not
stated: 90° after the gap). What this checks is the reading and that a verdict comes back,
not the IMEP: no capture states its TDC or its engine's numbers (skipped without the data)."""

from __future__ import annotations

import pytest
from conftest import SHARED_DATA

import rotor
from rotor.diagnostics.diagnosis import DiagnosisVerdict

TRIGGERS = SHARED_DATA / "ecu-triggers"

ENGINE = """
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
SIX = dict(
    cylinders=6,
    throws="[0, 0, 120, 120, 240, 240]\nbank_angles_deg = [0, 60, 0, 60, 0, 60]",
    order="[1, 2, 3, 4, 5, 6]",
)

# capture, its README's engine: (name, bore, stroke [m]) and layout (a V6 of 60° banks for the
# six-cylinder ones)
CAPTURES = [
    ("4b11-running.csv", ("4B11 2.0 l inline four", 0.086, 0.086), FOUR),
    ("3000gt.csv", ("6G72 3.0 l V6", 0.0911, 0.076), SIX),
    ("4g63-cranking.csv", ("4G63 2.0 l inline four", 0.085, 0.088), FOUR),
    ("6g75-without-spark-crank.csv", ("6G75 3.8 l V6", 0.095, 0.090), SIX),
    (
        "chrysler-phaser.csv",
        ("Chrysler 5.7 l V8", 0.0992, 0.0909),
        dict(
            cylinders=8,
            throws="[0, 270, 90, 180, 0, 270, 90, 180]\nbank_angles_deg = [-45, -45, -45, -45, 45, 45, 45, 45]",
            order="[1, 5, 4, 8, 6, 3, 7, 2]",  # the v8 preset's cross-plane crank
        ),
    ),
]


@pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")
@pytest.mark.parametrize("name,engine,layout", CAPTURES, ids=[c[0] for c in CAPTURES])
def test_diagnose_reads_a_capture_as_analyze_does(name, engine, layout, tmp_path):
    title, bore, stroke = engine
    path = tmp_path / "engine.toml"
    path.write_text(ENGINE.format(name=title, bore=bore, stroke=stroke, rod=1.65 * stroke, **layout))
    d = rotor.diagnose(rotor.load_engine(path), TRIGGERS / name, tdc_deg=90.0)
    assert d.analysis.reading_record == rotor.analyze_log(TRIGGERS / name).reading_record
    assert d.analysis.cycles >= 3
    assert isinstance(d.verdict, DiagnosisVerdict) and d.summary()
