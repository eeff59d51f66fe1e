"""A calibration file whose pressure gain or inertia fits another unit better is refused
naming that unit, as an engine file's are."""

from __future__ import annotations

import json
from importlib import resources

import pytest

from rotor.diagnostics.calibration_record import Calibration
from rotor.errors import EngineError


def _preset() -> dict:
    return json.loads((resources.files("rotor.presets") / "tue-single.calibration.json").read_text())


def test_the_preset_calibration_passes():
    Calibration.from_json_dict(_preset())


@pytest.mark.parametrize(
    "key,factor,unit",
    [("pressure_gain_pa", 1e-5, "bar"), ("inertia_kgm2", 1e4, "kg·cm²")],
)
def test_a_calibration_value_in_another_unit_is_refused_naming_it(key, factor, unit):
    d = _preset()
    d[key] = d[key] * factor
    with pytest.raises(EngineError, match=unit):
        Calibration.from_json_dict(d, where="cal.json")
