"""`rotor diagnose` reads the logic-analyser captures of the shared data as `rotor analyze`
does (the same wheel, edges and channel), with an engine file written from each capture's
README (`capture_engines`; TDC not stated: 90° after the gap). What this checks is the reading and that a verdict comes back,
not the IMEP: no capture states its TDC or its engine's numbers (skipped without the data)."""

from __future__ import annotations

import pytest
from capture_engines import EIGHT, FOUR, SIX, engine_toml
from conftest import SHARED_DATA

import rotor
from rotor.diagnostics.diagnosis import DiagnosisVerdict

TRIGGERS = SHARED_DATA / "ecu-triggers"

# capture, its README's engine: (name, bore, stroke [m]) and layout (a V6 of 60° banks for the
# six-cylinder ones)
CAPTURES = [
    ("4b11-running.csv", ("4B11 2.0 l inline four", 0.086, 0.086), FOUR),
    ("3000gt.csv", ("6G72 3.0 l V6", 0.0911, 0.076), SIX),
    ("4g63-cranking.csv", ("4G63 2.0 l inline four", 0.085, 0.088), FOUR),
    ("6g75-without-spark-crank.csv", ("6G75 3.8 l V6", 0.095, 0.090), SIX),
    ("chrysler-phaser.csv", ("Chrysler 5.7 l V8", 0.0992, 0.0909), EIGHT),
]


@pytest.mark.skipif(not TRIGGERS.is_dir(), reason=f"shared data not found at {TRIGGERS}")
@pytest.mark.parametrize("name,engine,layout", CAPTURES, ids=[c[0] for c in CAPTURES])
def test_diagnose_reads_a_capture_as_analyze_does(name, engine, layout, tmp_path):
    title, bore, stroke = engine
    path = tmp_path / "engine.toml"
    path.write_text(engine_toml(title, bore, stroke, layout))
    d = rotor.diagnose(rotor.load_engine(path), TRIGGERS / name, tdc_deg=90.0)
    assert d.analysis.reading_record == rotor.analyze_log(TRIGGERS / name).reading_record
    assert d.analysis.cycles >= 3
    assert isinstance(d.verdict, DiagnosisVerdict) and d.summary()
