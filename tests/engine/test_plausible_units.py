"""Units checked at the edge (rotor.engine.plausible): an engine file whose pressures are in
bar, kPa or MPa, whose lengths are in mm or cm, whose masses are in grams or whose inertias
are in kg·cm² is refused, naming the key and the unit the value reads as; the real engines
of the presets and the values at the ends of each range pass; IMEP may be 0 or negative."""

from __future__ import annotations

import copy
import tomllib

import pytest

import rotor
from rotor.engine.file import preset_path
from rotor.engine.plausible import EDGE_RANGES, check_edge, check_pressure_table, unit_slips

V8 = tomllib.loads(preset_path("v8").read_text())
TABLE = tomllib.loads(preset_path("4chn15").read_text())


def load(base, table, **values):
    data = copy.deepcopy(base)
    data[table].update(values)
    return rotor.engine_from_dict(data)


SLIPS = [
    ("intake in bar", V8, "pressure", {"intake_pa": 0.95}, r"\[pressure\] intake_pa = 0.95 .* reads as bar \(0.95 bar"),
    ("intake in kPa", V8, "pressure", {"intake_pa": 95.0}, r"intake_pa = 95 .* reads as kPa \(95 kPa = 9.5e\+04 Pa\)"),
    ("exhaust in bar", V8, "pressure", {"exhaust_pa": 1.1}, r"exhaust_pa = 1.1 .* reads as bar"),
    ("crankcase in bar", V8, "pressure", {"crankcase_pa": 1.013}, r"crankcase_pa = 1.013 .* reads as bar"),
    ("IMEP in bar", V8, "pressure", {"imep_pa": 12.5}, r"imep_pa = 12.5 .* reads as bar \(12.5 bar = 1.25e\+06 Pa\)"),
    ("IMEP in MPa", V8, "pressure", {"imep_pa": 1.05}, r"imep_pa = 1.05 .* reads as MPa \(1.05 MPa = 1.05e\+06 Pa\)"),
    (
        "table in MPa",
        TABLE,
        "pressure",
        {"pressure_pa": [p / 1e6 for p in TABLE["pressure"]["pressure_pa"]]},
        r"\[pressure\] pressure_pa: its peak = 7.1\d* lies outside .*5 … 300 bar.* reads as MPa",
    ),
    (
        "table in bar",
        TABLE,
        "pressure",
        {"pressure_pa": [p / 1e5 for p in TABLE["pressure"]["pressure_pa"]]},
        r"pressure_pa: its peak = 71.\d* .* reads as bar",
    ),
    ("fmep in bar", V8, "friction", {"fmep_pa": 1.2}, r"\[friction\] fmep_pa = 1.2 .* reads as bar"),
    ("bore in mm", V8, "geometry", {"bore_m": 101.6}, r"bore_m = 101.6 .* reads as mm \(101.6 mm = 0.1016 m\)"),
    ("stroke in cm", V8, "geometry", {"stroke_m": 7.62}, r"stroke_m = 7.62 .* reads as cm \(7.62 cm = 0.0762 m\)"),
    (
        "rod in cm",
        V8,
        "geometry",
        {"rod_length_m": 15.0},
        r"rod_length_m = 15 .* rod/stroke ratio is 197.* reads as cm",
    ),
    (
        "piston in grams",
        V8,
        "masses",
        {"reciprocating_kg": 850.0},
        r"reciprocating_kg = 850 .* reads as g \(850 g = 0.85 kg",
    ),
    ("rod mass in grams", V8, "masses", {"rotating_kg": 400.0}, r"rotating_kg = 400 .* reads as g"),
    ("inertia in kg·cm²", V8, "crankshaft", {"inertia_kgm2": 2900.0}, r"inertia_kgm2 = 2900 .* reads as kg·cm²"),
]


@pytest.mark.parametrize("label, base, table, values, message", SLIPS, ids=[s[0] for s in SLIPS])
def test_a_value_in_another_unit_is_refused_naming_that_unit(label, base, table, values, message):
    if table == "friction":
        base = {**base, "friction": {"fmep_pa": 1e5}}
    with pytest.raises(rotor.EngineError, match=message):
        load(base, table, **values)


def test_the_same_values_in_si_units_load():
    load(V8, "pressure", intake_pa=0.95e5, imep_pa=12.5e5, exhaust_pa=1.1e5)
    load(TABLE, "pressure", pressure_pa=TABLE["pressure"]["pressure_pa"])
    load(V8, "masses", reciprocating_kg=0.85, rotating_kg=0.4)
    load({**V8, "friction": {"fmep_pa": 1.2e5}}, "friction", fmep_pa=0.0)  # no friction: 0 passes


def test_a_rod_inertia_in_kg_cm2_is_refused():
    data = copy.deepcopy(V8)
    data["masses"].update(rod_kg=0.6, rod_cg_from_big_end_m=0.04, rod_inertia_kgm2=40.0)
    with pytest.raises(rotor.EngineError, match=r"rod_inertia_kgm2 = 40 is .* reads as kg·cm²"):
        rotor.engine_from_dict(data)
    data["masses"]["rod_inertia_kgm2"] = 0.004
    rotor.engine_from_dict(data)


@pytest.mark.parametrize("imep", [0.0, -0.8e5, -1e3, 1e3, 4e6, -4e6])
def test_imep_may_be_zero_or_negative_for_a_motored_engine(imep):
    check_edge("calibration: imep_measured_pa", imep, "imep_pa")


@pytest.mark.parametrize(
    "imep, unit", [(12.5, "bar"), (-0.9, "bar"), (0.5, "bar"), (4.1e6, None), (-999.0, "kPa")], ids=str
)
def test_an_imep_under_1000_pa_or_over_40_bar_is_refused(imep, unit):
    with pytest.raises(rotor.EngineError, match=r"calibration: imep_pa = .* lies outside the plausible ±\(1000") as e:
        check_edge("calibration: imep_pa", imep, "imep_pa")
    if unit is not None:
        assert f" {unit} ({imep:g} {unit} = " in str(e.value).split("reads as")[1]
    else:
        assert "reads as" not in str(e.value)


@pytest.mark.parametrize("quantity", sorted(EDGE_RANGES))
def test_the_ends_of_each_range_pass_and_beyond_them_is_refused(quantity):
    r = EDGE_RANGES[quantity]
    check_edge("x", r.lo, quantity)
    check_edge("x", r.hi, quantity)
    for bad in (r.lo * 0.999, r.hi * 1.001, float("nan")):
        with pytest.raises(rotor.EngineError, match=r"^x = "):
            check_edge("x", bad, quantity)


def test_a_calibration_gain_in_bar_per_volt_names_bar():
    with pytest.raises(rotor.EngineError, match=r"reads as bar/unit \(51.9 bar/unit = 5.19e\+06 Pa/unit\)"):
        check_edge("cal.json: pressure_gain_pa", 51.9, "pressure_gain_pa")
    check_edge("cal.json: pressure_gain_pa", 5.19e6, "pressure_gain_pa")


def test_a_table_with_a_low_point_in_another_unit_is_refused():
    with pytest.raises(rotor.EngineError, match=r"its lowest point = 0.5 .* 0.01 … 300 bar"):
        check_pressure_table("[pressure] pressure_pa", [0.5, 1e5, 5e6])


def test_the_likelier_unit_comes_first():
    assert [u for u, _ in unit_slips(92.0, 1e-3, 2.0, "m", 0.092)] == ["mm", "cm"]
    assert [u for u, _ in unit_slips(9.2, 1e-3, 2.0, "m", 0.092)][0] == "cm"
    assert unit_slips(1e9, 1e-3, 2.0, "m", 0.092) == []


@pytest.mark.parametrize("name", rotor.preset_names())
def test_every_preset_is_within_the_ranges(name):
    rotor.load_engine(name)


def test_a_calibrated_inertia_in_kg_cm2_is_refused_beside_its_engines_bore():
    from rotor.engine.plausible import check_inertia_kgm2

    check_inertia_kgm2("cal.json: inertia_kgm2", 0.0161, bore_m=0.0677, cylinders=1)
    with pytest.raises(
        rotor.EngineError, match=r"cal.json: inertia_kgm2 = 161 .* reads as kg·cm² \(161 kg·cm² = 0.0161"
    ):
        check_inertia_kgm2("cal.json: inertia_kgm2", 161.0, bore_m=0.0677, cylinders=1)
    with pytest.raises(rotor.EngineError, match=r"cal.json: inertia_kgm2 = -1 lies outside"):
        check_inertia_kgm2("cal.json: inertia_kgm2", -1.0)
