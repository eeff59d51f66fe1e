"""Engine files: the presets, the mirror of file and object, and every kind of bad input
(a ValueError naming the key in Python; exit code 2 and one line in the CLI)."""

import re
import subprocess
import sys
import tomllib

import jax.numpy as jnp
import numpy as np
import pytest

import rotor
from rotor.cli import main
from rotor.engine.file import preset_path

BASE = tomllib.loads(preset_path("4chn15").read_text())


def _variant(tmp_path, mutate):
    import copy

    data = copy.deepcopy(BASE)
    mutate(data)
    return data


def _dump(data):
    """A minimal TOML writer for the test variants (numbers, strings, lists, tables)."""

    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)

    def table_list(v):
        return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)

    lines = [f"{k} = {val(v)}" for k, v in data.items() if not isinstance(v, dict) and not table_list(v)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"[{k}]")
            lines += [f"{kk} = {val(vv)}" for kk, vv in v.items()]
        elif table_list(v):
            for item in v:
                lines.append(f"[[{k}]]")
                lines += [f"{kk} = {val(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("name", rotor.preset_names())
def test_presets_load_and_are_sane(name):
    e = rotor.load_engine(name)
    th = jnp.linspace(0, e.cycle_rad, 721)
    assert np.all(np.isfinite(rotor.gas_torque(e, th)))
    assert float(rotor.imep_pa(e)) > 0
    # firing is spread over the cycle: no two cylinders fire at the same angle
    fa = np.sort(np.mod(np.rad2deg(np.asarray(e.firing_angles_rad)), 360 * e.strokes / 2))
    assert len(np.unique(np.round(fa, 6))) == e.cylinders


def test_required_presets_exist():
    assert {"4chn15", "tue-single", "mwm6", "v8"} <= set(rotor.preset_names())


def test_object_mirrors_the_file(diesel):
    assert float(diesel.crankshaft.inertia_kgm2) == BASE["crankshaft"]["inertia_kgm2"]
    assert float(diesel.geometry.bore_m) == BASE["geometry"]["bore_m"]
    assert list(diesel.layout.firing_order) == BASE["layout"]["firing_order"]
    assert np.allclose(diesel.pressure.pressure_pa, BASE["pressure"]["pressure_pa"])
    assert diesel.geometry.crank_radius_m == pytest.approx(0.1025)
    assert diesel.geometry.rod_ratio == pytest.approx(0.267, abs=1e-4)
    assert diesel.geometry.piston_area_m2 == pytest.approx(0.0176, rel=1e-3)


def test_firing_angles_follow_the_order(diesel):
    # 1-3-4-2 on a flat-plane four: firing TDCs 180 deg apart in that order
    fa = np.rad2deg(np.asarray(diesel.firing_angles_rad))
    order = [1, 3, 4, 2]
    steps = np.diff([fa[c - 1] for c in order])
    assert np.allclose(steps, 180.0)
    v8 = rotor.load_engine("v8")
    fa = np.rad2deg(np.asarray(v8.firing_angles_rad))
    steps = np.diff([fa[c - 1] for c in v8.layout.firing_order])
    assert np.allclose(steps, 90.0)


def test_float32_and_int_inputs_become_float64():
    g = rotor.Geometry(bore_m=np.float32(0.1), stroke_m=1, rod_length_m=np.float32(2.3))
    assert g.bore_m.dtype == jnp.float64 and g.stroke_m.dtype == jnp.float64
    assert float(g.bore_m) == float(np.float32(0.1))  # converted, not re-rounded


BAD = [
    ("rod not longer than crank", lambda d: d["geometry"].update(rod_length_m=0.1), "rod_length_m"),
    ("rod equal to crank", lambda d: d["geometry"].update(rod_length_m=0.1025), "rod_length_m"),
    ("zero bore", lambda d: d["geometry"].update(bore_m=0.0), "bore_m"),
    ("negative stroke", lambda d: d["geometry"].update(stroke_m=-0.2), "stroke_m"),
    ("negative mass", lambda d: d["masses"].update(reciprocating_kg=-1.0), "reciprocating_kg"),
    ("zero mass", lambda d: d["masses"].update(reciprocating_kg=0.0), "reciprocating_kg"),
    ("zero inertia", lambda d: d["crankshaft"].update(inertia_kgm2=0.0), "inertia_kgm2"),
    ("not a permutation", lambda d: d["layout"].update(firing_order=[1, 3, 3, 2]), "firing_order"),
    ("wrong length", lambda d: d["layout"].update(firing_order=[1, 3, 2]), "firing_order"),
    ("impossible order", lambda d: d["layout"].update(firing_order=[1, 4, 2, 3]), "firing_order"),
    ("throws wrong length", lambda d: d["layout"].update(throw_angles_deg=[0, 180, 180]), "throw_angles_deg"),
    (
        "table not covering",
        lambda d: d["pressure"].update(
            angle_deg=d["pressure"]["angle_deg"][19:54], pressure_pa=d["pressure"]["pressure_pa"][19:54]
        ),
        "does not cover",
    ),
    ("angles not increasing", lambda d: d["pressure"]["angle_deg"].__setitem__(5, 60), "angles must increase"),
    ("lengths differ", lambda d: d["pressure"]["pressure_pa"].pop(), "same length"),
    ("unknown key", lambda d: d["geometry"].update(bore=0.15), r"bore: unknown key \(did you mean 'bore_m'\?\)"),
    ("unknown table", lambda d: d.update(geometri={"x": 1}), "geometri"),
    ("wrong type", lambda d: d["geometry"].update(bore_m="0.15"), r"bore_m .*expected a number"),
    ("bool as number", lambda d: d["masses"].update(rotating_kg=True), "rotating_kg"),
    ("wrong list item", lambda d: d["layout"]["throw_angles_deg"].__setitem__(2, "x"), "item 3"),
    ("missing key", lambda d: d["geometry"].pop("stroke_m"), "stroke_m is missing"),
    ("missing table", lambda d: d.pop("crankshaft"), r"\[crankshaft\] is missing"),
    ("bad strokes", lambda d: d.update(strokes=3), "strokes"),
    ("bad kind", lambda d: d["pressure"].update(kind="tabel"), "did you mean 'table'"),
    ("nan", lambda d: d["operating"].update(rpm=float("nan")), "rpm"),
    ("half a full rod", lambda d: d["masses"].update(rod_kg=3.0), "rod_cg_from_big_end_m"),
    ("negative friction", lambda d: d.update(friction={"fmep_pa": -1.0}), "fmep_pa"),
    ("friction typo", lambda d: d.update(friction={"fmep": 1.0}), "did you mean 'fmep_pa'"),
    (
        "720 point that differs",
        lambda d: (d["pressure"]["angle_deg"].append(720), d["pressure"]["pressure_pa"].append(140000.0)),
        "720",
    ),
]


@pytest.mark.parametrize("label,mutate,pattern", BAD, ids=[b[0] for b in BAD])
def test_bad_input_is_a_value_error_naming_the_key(tmp_path, label, mutate, pattern):
    data = _variant(tmp_path, mutate)
    path = tmp_path / "bad.toml"
    path.write_text(_dump(data))
    with pytest.raises(ValueError, match=pattern):
        rotor.load_engine(path)


@pytest.mark.parametrize("label,mutate,pattern", BAD[::5], ids=[b[0] for b in BAD[::5]])
def test_bad_input_in_the_cli_exits_2_with_one_line(tmp_path, capsys, label, mutate, pattern):
    path = tmp_path / "bad.toml"
    path.write_text(_dump(_variant(tmp_path, mutate)))
    assert main(["table", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("rotor: error: ")
    assert re.search(pattern, err)
    assert "Traceback" not in err


def test_closing_point_equal_to_the_first_is_accepted(tmp_path):
    data = _variant(
        tmp_path,
        lambda d: (
            d["pressure"]["angle_deg"].append(720),
            d["pressure"]["pressure_pa"].append(d["pressure"]["pressure_pa"][0]),
        ),
    )
    path = tmp_path / "ok.toml"
    path.write_text(_dump(data))
    e = rotor.load_engine(path)
    assert e.pressure.angle_deg.shape[0] == 72


def test_not_toml_and_missing_files(tmp_path, capsys):
    path = tmp_path / "engine.toml"
    path.write_text("name = [unclosed\n")
    with pytest.raises(ValueError, match="not a valid TOML file"):
        rotor.load_engine(path)
    with pytest.raises(ValueError, match="neither an engine file nor a preset"):
        rotor.load_engine(tmp_path / "nothing.toml")
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(ValueError, match="not a TOML file"):
        rotor.load_engine(binary)


def test_console_script_exit_code_and_message(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("name = 'x'\n")
    exe = [sys.executable, "-m", "rotor.cli"]
    r = subprocess.run(exe + ["table", str(path)], capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "strokes is missing" in r.stderr


@pytest.mark.parametrize(
    "text",
    [
        "name = " + "[" * 5000 + "]" * 5000 + "\n",  # nested arrays, past what tomllib reads
        "name = " + "{a = " * 3000 + "1" + "}" * 3000 + "\n",  # nested inline tables
    ],
    ids=["arrays", "inline tables"],
)
def test_a_deeply_nested_file_is_refused_naming_it(tmp_path, capsys, text):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    with pytest.raises(rotor.EngineError, match=re.escape(str(path)) + ".*nested too deeply") as info:
        rotor.load_engine(path)
    assert "\n" not in str(info.value)
    assert main(["table", str(path)]) == 2  # an input error, not an internal one (70)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nested too deeply" in err


def test_nesting_that_tomllib_reads_is_refused_by_the_engine_reader(tmp_path):
    """Arrays nested a few hundred deep parse, and are refused by the engine's own check,
    naming the key (no RecursionError printing them)."""
    path = tmp_path / "deep.toml"
    path.write_text(
        preset_path("4chn15").read_text().replace("[layout]", "[layout]\nnames = " + "[" * 300 + "]" * 300, 1)
    )
    with pytest.raises(rotor.EngineError, match=r"deep\.toml: layout\.names: nested more than 16 levels") as info:
        rotor.load_engine(path)
    assert len(str(info.value)) < 300
    data = {**BASE, "geometry": {**BASE["geometry"], "bore_m": [[[[[[[[[[[[[[[[[[[[0.15]]]]]]]]]]]]]]]]]]]]}}
    with pytest.raises(rotor.EngineError, match=r"geometry\.bore_m: nested more than"):
        rotor.engine_from_dict(data)
