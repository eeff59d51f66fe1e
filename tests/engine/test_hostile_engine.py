"""Hostile engines, tables and flywheels: what is computed
is validated, not only what is read; no NaN or infinity reaches JSON or CSV; sizes are
checked before anything is allocated; a flywheel is never negative; a byte-order mark,
a file that is not UTF-8, an empty file or a directory gets one line naming the path;
wrong Python types get a TypeError naming the argument."""

import json
import math
import re
import tomllib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rotor
from rotor.cli import main
from rotor.dynamics.crank_train import check_finite_tables, check_inertia, train_from_engine
from rotor.engine import plausible
from rotor.engine.file import preset_path
from rotor.engine.plausible import PLAUSIBLE, finite_derived

TEXT = preset_path("4chn15").read_text(encoding="utf-8")


def _with(text: str, table: str, key: str, value: str) -> str:
    """The 4chn15 file with ``[table] key`` set to ``value`` (TOML text)."""
    out, here = [], ""
    for line in text.splitlines():
        m = re.match(r"\[(\w+)\]", line)
        if m:
            here = m.group(1)
        if here == table and re.match(rf"{key}\s*=", line):
            line = f"{key} = {value}"
        out.append(line)
    return "\n".join(out) + "\n"


def _file(tmp_path, text: str, name: str = "engine.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _one_line(e: BaseException) -> str:
    msg = str(e)
    assert "\n" not in msg and msg, msg
    return msg


def _tree_at(engine, where, value):
    return eqx.tree_at(where, engine, value)


# ----------------------------------------------------------------------------- item 1: absurd but finite inputs
ABSURD = [
    ("geometry", "bore_m", "1e300"),
    ("geometry", "stroke_m", "1e300"),
    ("geometry", "rod_length_m", "1e300"),
    ("masses", "reciprocating_kg", "1e300"),
    ("masses", "rotating_kg", "1e300"),
    ("crankshaft", "inertia_kgm2", "1e300"),
    ("crankshaft", "inertia_kgm2", "1e-300"),
    ("operating", "rpm", "1e300"),
    ("pressure", "crankcase_pa", "1e300"),
]


@pytest.mark.parametrize("table, key, value", ABSURD)
def test_absurd_finite_inputs_are_refused_naming_the_input(tmp_path, table, key, value):
    path = _file(tmp_path, _with(TEXT, table, key, value))
    with pytest.raises(rotor.EngineError) as e:
        rotor.load_engine(path)
    msg = _one_line(e.value)
    assert str(path) in msg and f"[{table}] {key}" in msg and "plausible" in msg


def test_a_pressure_table_entry_of_1e300_is_named(tmp_path):
    path = _file(tmp_path, TEXT.replace("7134000", "1e300"))
    with pytest.raises(rotor.EngineError, match=r"\[pressure\] pressure_pa: 1e\+300 lies outside"):
        rotor.load_engine(path)


@pytest.mark.parametrize(
    "key, value", [("compression_ratio", "1.0000001"), ("imep_pa", "1e300"), ("form_factor", "1e6")]
)
def test_absurd_wiebe_inputs(tmp_path, key, value):
    text = preset_path("tue-single").read_text(encoding="utf-8")
    path = _file(tmp_path, _with(text, "pressure", key, value))
    with pytest.raises(rotor.EngineError, match=rf"\[pressure\] {key}"):
        rotor.load_engine(path)


def test_cli_info_and_table_refuse_the_1e300_bore_in_one_line(tmp_path, capsys):
    path = _file(tmp_path, _with(TEXT, "geometry", "bore_m", "1e300"))
    for argv in (["info", str(path), "--json"], ["table", str(path), "--format", "csv"], ["steady", str(path)]):
        assert main(argv) == 2
        out, err = capsys.readouterr()
        assert out == "" and err.count("\n") == 1 and "[geometry] bore_m = 1e+300" in err
        assert "kinetic energy" not in err


def test_real_engines_from_a_model_engine_to_a_ship_diesel_fit_the_ranges():
    """The ranges are not so tight that a 5 cm³ model engine or the largest ship diesel fails."""

    def engine(bore, stroke, rod, m_rec, J, rpm, pressure):
        return rotor.Engine(
            name="x",
            strokes=2,
            cylinders=1,
            geometry=rotor.Geometry(bore_m=bore, stroke_m=stroke, rod_length_m=rod),
            masses=rotor.Masses(reciprocating_kg=m_rec, rotating_kg=0.5 * m_rec),
            crankshaft=rotor.Crankshaft(inertia_kgm2=J),
            layout=rotor.Layout(throw_angles_deg=[0.0], firing_order=[1]),
            pressure=pressure,
            operating=rotor.Operating(rpm=rpm),
        )

    table = rotor.PressureTable(angle_deg=[0.0, 90.0, 180.0, 270.0], pressure_pa=[6e6, 1e6, 1.2e5, 1e6])
    model = engine(0.0186, 0.018, 0.035, 0.004, 2e-7, 25000.0, table)  # a 5 cm³ glow engine
    ship = engine(0.98, 3.15, 3.6, 2.5e4, 3e5, 80.0, table)  # a two-stroke of the Wärtsilä RT-flex96C class
    for e in (model, ship):
        s = rotor.engine_summary(e)
        assert json.loads(json.dumps(s.to_json_dict(), allow_nan=False)) == s.to_json_dict()
        assert all(v is not None for v in s.to_json_dict().values())
    for name in rotor.preset_names():
        rotor.load_engine(name).check()


def test_derived_quantities_name_the_input_that_overflowed():
    with pytest.raises(rotor.EngineError) as e:
        with np.errstate(over="ignore"):
            area = np.pi * np.float64(1e300) ** 2 / 4
        finite_derived("the piston area", area, "m²", "[geometry] bore_m = 1e+300")
    msg = _one_line(e.value)
    assert msg.startswith("[geometry] bore_m = 1e+300: the piston area overflows (inf m²)")
    with pytest.raises(rotor.EngineError, match="vanishes"):
        finite_derived("the clearance volume", 0.0, "m³", "[pressure] compression_ratio = 1e300")
    finite_derived("x", 1.0, "m", "y")  # fine
    with pytest.raises(rotor.EngineError, match="is not a number"):
        finite_derived("the displacement", jnp.ones(3) * jnp.nan, "m³", "[geometry] stroke_m = 1")


def test_tables_of_the_crank_train_are_checked(diesel):
    values = np.ones((16, 3 + diesel.cylinders))
    slopes = np.zeros_like(values)
    check_finite_tables(values, slopes, diesel)
    check_inertia(1.0, 1.0, diesel)
    bad = values.copy()
    bad[3, 2] = np.inf
    with pytest.raises(rotor.EngineError, match="motored gas torque is inf N·m at 135°.*\\[pressure\\]"):
        check_finite_tables(bad, slopes, diesel)
    with pytest.raises(rotor.EngineError, match="slope.*not a finite"):
        check_finite_tables(values, bad, diesel)
    with pytest.raises(rotor.EngineError, match="reduced inertia I\\(θ\\) falls to -1"):
        check_inertia(-1.0, 1.0, diesel)
    # a sweep over the crankshaft inertia: every item must keep I(θ) positive
    with pytest.raises(rotor.EngineError, match="falls to -0.5"):
        check_inertia(np.array([0.2, -0.5, 1.0]), np.array([1.0, 0.3, 2.0]), diesel)


# ----------------------------------------------------------------------------- item 2: eqx.tree_at
SMUGGLED = [
    (lambda e: e.crankshaft.inertia_kgm2, 0.0, r"\[crankshaft\] inertia_kgm2 = 0: must be positive"),
    (lambda e: e.masses.reciprocating_kg, -1.0, r"\[masses\] reciprocating_kg = -1: must be positive"),
    (lambda e: e.geometry.bore_m, jnp.nan, r"\[geometry\] bore_m = nan: must be finite"),
    (lambda e: e.geometry.bore_m, 1e300, r"\[geometry\] bore_m = 1e\+300 lies outside"),
    (lambda e: e.geometry.rod_length_m, 0.05, r"\[geometry\] rod_length_m = 0.05: the rod must be longer"),
]


@pytest.mark.parametrize("where, value, match", SMUGGLED)
def test_solvers_check_fields_that_tree_at_smuggled_in(diesel, where, value, match):
    bad = _tree_at(diesel, where, value)
    for solve in (
        lambda: rotor.steady_state(bad),
        lambda: rotor.simulate(bad, cycles=1),
        lambda: rotor.crank_train(bad),
        lambda: train_from_engine(bad, "variable", 720),
        lambda: rotor.engine_summary(bad),
        lambda: rotor.crank_table(bad),
        lambda: bad.check(),
    ):
        with pytest.raises(rotor.EngineError, match=match) as e:
            solve()
        _one_line(e.value)


def test_a_string_smuggled_in_is_a_type_error(diesel):
    bad = _tree_at(diesel, lambda e: e.geometry.bore_m, "0.15")
    with pytest.raises(TypeError, match=r"\[geometry\] bore_m = '0.15': expected a number"):
        rotor.steady_state(bad)


def test_traced_fields_pass_the_checks(diesel):
    def mean_inertia(J):
        e = _tree_at(diesel, lambda e: e.crankshaft.inertia_kgm2, J)
        e.check()
        return train_from_engine(e, "variable", 720).mean_inertia

    got = float(jax.jit(mean_inertia)(jnp.asarray(10.2)))
    assert got == pytest.approx(float(rotor.mean_reduced_inertia(diesel)), rel=1e-9)
    # a traced zero is not checked (it cannot be); jax.grad through the check works
    assert float(jax.grad(mean_inertia)(jnp.asarray(10.2))) == pytest.approx(1.0, rel=1e-9)


# ----------------------------------------------------------------------------- item 3: sizes
def test_a_tiny_table_step_is_refused_before_allocating(diesel, capsys):
    for step in (1e-7, 1e-300):
        with pytest.raises(rotor.EngineError, match=r"needs .* of memory, over the .* GB.*larger step") as e:
            rotor.crank_table(diesel, step_deg=step)
        _one_line(e.value)
    assert main(["table", "4chn15", "--step", "1e-7"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "--step" in err


def test_the_memory_limit_is_the_one_check_size_reads(diesel, monkeypatch):
    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "0.01")
    with pytest.raises(rotor.EngineError, match="over the 0.01 GB"):
        rotor.crank_table(diesel, step_deg=0.001)
    with pytest.raises(rotor.EngineError, match="points per degree"):
        rotor.engine_curves(diesel, points_per_deg=1000)
    with pytest.raises(rotor.EngineError, match="larger grid_deg"):
        rotor.crank_train(diesel, grid_deg=1e-4)
    assert len(rotor.crank_table(diesel, step_deg=10.0)) == 73  # small tables still fit


def test_other_counts_are_bounded(diesel):
    with pytest.raises(rotor.EngineError, match="grid_deg"):
        rotor.crank_train(diesel, grid_deg=1e-300)
    with pytest.raises(TypeError, match="points_per_deg"):
        rotor.engine_curves(diesel, points_per_deg=0.5)


# ----------------------------------------------------------------------------- item 4: a flywheel is never negative
def test_a_shaft_that_is_enough_needs_no_flywheel(diesel):
    d = rotor.design_flywheel(diesel, 0.01, shaft_inertia_kgm2=1e6)
    assert d.flywheel_kgm2 == 0.0 and d.flywheel_needed is False and d.disc is None
    assert d.delta_shaft_alone is not None and 0 < d.delta_shaft_alone < 0.01
    out = d.to_json_dict()
    assert json.loads(json.dumps(out, allow_nan=False)) == out
    assert out["flywheel_kgm2"] == 0.0 and out["flywheel_needed"] is False and "no flywheel needed" in out["note"]
    assert "no flywheel needed" in d.summary() and "-" not in f"{d.flywheel_kgm2}"
    # with a disc asked for, still no disc and no negative dimension
    d2 = rotor.design_flywheel(diesel, 0.01, shaft_inertia_kgm2=1e6, max_outer_diameter_m=0.5)
    assert d2.disc is None and d2.flywheel_kgm2 == 0.0
    with pytest.raises(rotor.EngineError, match="shaft_inertia_kgm2 = 1e\\+300"):
        rotor.design_flywheel(diesel, 0.01, shaft_inertia_kgm2=1e300)


def test_a_negative_textbook_inertia_is_null_with_a_note():
    tb = rotor.TextbookFlywheel(
        rpm=3000.0,
        delta=0.2,
        excess_work_J=10.0,
        total_inertia_kgm2=0.001,
        crankshaft_inertia_kgm2=-0.02,
        flywheel_kgm2=0.00085,
        mean_diameter_m=0.2,
        mass_kg=0.085,
    )
    out = tb.to_json_dict()
    assert out["crankshaft_inertia_kgm2"] is None and "not applicable" in out["note"]
    assert all(v is None or not isinstance(v, float) or v >= 0 for v in out.values())


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(density_kg_m3=1e-300), "density_kg_m3"),
        (dict(max_rim_speed_m_s=1e300), "more than any flywheel"),
        (dict(max_outer_diameter_m=1e300, max_rim_speed_m_s=None), "more than any flywheel"),
        (dict(peak_rpm=1e300, max_outer_diameter_m=0.5), "peak_rpm"),
    ],
)
def test_absurd_disc_limits(kwargs, match):
    args = dict(peak_rpm=1250.0, max_outer_diameter_m=None, max_rim_speed_m_s=50.0)
    args.update(kwargs)
    with pytest.raises(rotor.EngineError, match=match) as e:
        rotor.lightest_disc(1.0, **args)
    _one_line(e.value)


# ----------------------------------------------------------------------------- item 5: files
def test_a_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + TEXT.encode("utf-8"))
    assert rotor.load_engine(path).name == rotor.load_engine("4chn15").name


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda p: p.write_bytes(TEXT.replace("diesel", "di\xe9sel").encode("latin-1")), "not UTF-8 text"),
        (lambda p: p.write_bytes(b""), "the file is empty"),
        (lambda p: p.write_bytes(b"  \n\n"), "the file is empty"),
        (lambda p: p.mkdir(), "is a directory"),
        (lambda p: p.write_bytes(b"name = 1\x00"), "NUL|not a valid TOML"),
    ],
)
def test_bad_files_name_the_users_path(tmp_path, capsys, make, match):
    path = tmp_path / "engine.toml"
    make(path)
    with pytest.raises(rotor.EngineError, match=match) as e:
        rotor.load_engine(path)
    assert _one_line(e.value).startswith(str(path))
    assert main(["info", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and str(path) in err


def test_a_directory_without_suffix_is_named(tmp_path):
    with pytest.raises(rotor.EngineError, match="is a directory"):
        rotor.load_engine(tmp_path)


# ----------------------------------------------------------------------------- item 6: Python types
def test_wrong_python_types_name_the_argument(diesel):
    cases = [
        (lambda: rotor.Geometry(bore_m="0.1", stroke_m=0.2, rod_length_m=0.4), r"\[geometry\] bore_m"),
        (lambda: rotor.Geometry(bore_m=None, stroke_m=0.2, rod_length_m=0.4), r"\[geometry\] bore_m"),
        (lambda: rotor.Layout(throw_angles_deg=["0"], firing_order=[1]), r"\[layout\] throw_angles_deg"),
        (lambda: diesel.replace(geometry="x"), r"Engine\(geometry = \.\.\.\): expected a rotor.Geometry"),
        (lambda: diesel.replace(name=4), r"Engine\(name = 4\)"),
        (lambda: rotor.load_engine(42), r"load_engine\(path_or_name\)"),
        (lambda: rotor.load_engine(None), r"load_engine\(path_or_name\)"),
        (lambda: rotor.engine_summary(engine="4chn15"), r"engine_summary\(engine\).*rotor.load_engine"),
        (lambda: rotor.engine_summary(diesel, rpm="1000"), r"rpm: expected a number"),
        (lambda: rotor.crank_table("4chn15"), r"crank_table\(engine\)"),
        (lambda: rotor.crank_table(diesel, step_deg="10"), r"step_deg: expected a number \[deg\]"),
        (lambda: rotor.crank_table(diesel, cylinder=1.0), r"cylinder: expected a whole number"),
        (lambda: rotor.engine_curves(None), r"engine_curves\(engine\)"),
        (lambda: rotor.reduced_inertia("4chn15", 0.0), r"reduced_inertia\(engine\)"),
        (lambda: rotor.gas_torque("4chn15", 0.0), r"gas_torque\(engine\)"),
        (lambda: rotor.crank_train("4chn15"), r"crank_train\(engine\)"),
        (lambda: rotor.design_flywheel("4chn15", 0.01), r"design_flywheel\(engine\)"),
        (lambda: rotor.design_flywheel(diesel, delta="0.01"), r"delta: expected a number"),
        (lambda: rotor.design_flywheel(diesel, 0.01, shaft_inertia_kgm2="1"), r"shaft_inertia_kgm2"),
        (lambda: rotor.design_flywheel(diesel, 0.01, points="1250"), r"points: expected"),
        (lambda: rotor.textbook_flywheel(diesel, [0.01]), r"delta: expected a number"),
        (lambda: rotor.lightest_disc("1", peak_rpm=1250, max_outer_diameter_m=0.5), r"inertia_kgm2"),
        (lambda: rotor.lightest_disc(1.0, peak_rpm=1250, max_outer_diameter_m="0.5"), r"max_outer_diameter_m"),
    ]
    for call, match in cases:
        with pytest.raises(TypeError, match=match) as e:
            call()
        _one_line(e.value)


def test_numpy_and_jax_scalars_are_numbers(diesel):
    t = rotor.crank_table(diesel, rpm=np.float32(1250.0), step_deg=np.int64(30), cylinder=np.int64(2))
    assert t.rpm == 1250.0 and len(t) == 25
    assert rotor.engine_summary(diesel, rpm=jnp.asarray(1250.0)).rpm == 1250.0


# ----------------------------------------------------------------------------- item 7: no NaN in JSON or CSV
@pytest.mark.parametrize("name", ["4chn15", "v8"])
def test_info_table_json_and_csv_are_finite(capsys, name):
    assert main(["info", name, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert all(v is not None for v in info.values())
    assert main(["table", name, "--format", "csv", "--step", "30"]) == 0
    csv = capsys.readouterr().out
    assert not re.search(r"nan|inf", csv, re.IGNORECASE)


def test_a_number_that_should_exist_and_does_not_is_an_error(diesel, monkeypatch):
    import jax

    import rotor.engine.summary as summary

    monkeypatch.setattr(summary, "imep_pa", lambda engine: jnp.nan)
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")  # a kept program is found by rotor's source, not by a patch
    jax.clear_caches()  # engine_summary is one compiled call: compile it again with the NaN
    try:
        with pytest.raises(rotor.EngineError, match="imep_pa is nan, not a finite number") as e:
            rotor.engine_summary(diesel)
        _one_line(e.value)
    finally:
        monkeypatch.undo()
        jax.clear_caches()  # and never let a later test reuse the NaN version


def test_plausible_ranges_are_documented():
    doc = plausible.__doc__
    for table, key in PLAUSIBLE:
        assert f"[{table}]" in doc and key.split("_")[0] in doc, key
    assert all(lo < hi and math.isfinite(hi) for lo, hi, _, _ in PLAUSIBLE.values())
    assert tomllib.loads(TEXT)["geometry"]["bore_m"] > PLAUSIBLE[("geometry", "bore_m")][0]


def test_the_crank_tables_csv_refuses_a_nan_like_the_cli():
    """The API's to_csv() goes through the one CSV writer (rotor.fileio.csv_text)."""
    import dataclasses

    import numpy as np

    from rotor.errors import InternalError

    table = rotor.crank_table(rotor.load_engine("4chn15"), step_deg=90)
    assert table.to_csv().splitlines()[0].startswith("angle_deg,s_m")
    columns = dict(table.columns)
    columns["s_m"] = np.where(np.arange(len(table)) == 2, np.nan, np.asarray(columns["s_m"]))
    with pytest.raises(InternalError, match=r'the crank table\'s "s_m" in row 3 is NaN'):
        dataclasses.replace(table, columns=columns).to_csv()
