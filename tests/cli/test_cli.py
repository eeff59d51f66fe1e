"""The command line: table formats, info, plots, demo, presets; where a command may write
(standard output for ``-``, never a link, a device or a file the command reads)."""

import json
import os
import stat

import numpy as np
import pytest
from conftest import run_cli

from rotor.cli import main


def test_table_text(capsys):
    assert main(["table", "4chn15", "--step", "30"]) == 0
    out = capsys.readouterr().out
    assert "4ChN15/20.5" in out and "series kinematics" in out
    rows = [l for l in out.splitlines() if l.strip() and l.split()[0].replace(".", "").isdigit()]
    assert len(rows) == 25  # 0, 30, ..., 720


def test_table_exact_and_rpm_and_output_file(tmp_path, capsys):
    path = tmp_path / "t.csv"
    assert main(["table", "v8", "--rpm", "2000", "--kinematics", "exact", "--format", "csv", "-o", str(path)]) == 0
    lines = path.read_text().splitlines()
    assert lines[0].startswith("angle_deg,s_m,")
    assert len(lines) == 1 + 73
    assert not list(tmp_path.glob(".rotor-*"))  # no temporary file left behind


@pytest.mark.parametrize(
    "args", [["--step", "7"], ["--step", "-1"], ["--rpm", "0"], ["--cylinder", "9"], ["--format", "xml"]]
)
def test_table_bad_arguments_exit_2(args, capsys):
    with pytest.raises(SystemExit) as exc:
        rc = main(["table", "4chn15", *args])
        raise SystemExit(rc)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error" in err


def test_info_json(capsys):
    assert main(["info", "4chn15", "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["cylinders"] == 4 and s["rpm"] == 1250
    assert np.isclose(s["indicated_power_w"], s["mean_gas_torque_Nm"] * 1250 * np.pi / 30)
    assert 0.9e6 < s["imep_pa"] < 1.05e6


def test_plot_and_demo_write_pngs(tmp_path, capsys):
    out = tmp_path / "plots"
    assert main(["demo", "--plot", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "IMEP" in text and "irregularity" in text and "load step" in text
    for name in (
        "kinematics.png",
        "forces.png",
        "torque.png",
        "inertia.png",
        "steady_cycle.png",
        "steady_orders.png",
        "load_step_time.png",
        "load_step_cycle.png",
    ):
        p = out / name
        assert p.is_file() and p.stat().st_size > 10_000
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_presets_lists_names(capsys):
    assert main(["presets"]) == 0
    assert "4chn15" in capsys.readouterr().out


def test_unwritable_output_is_a_clean_error(tmp_path, capsys):
    assert main(["table", "4chn15", "-o", str(tmp_path / "missing" / "t.csv")]) == 2
    assert capsys.readouterr().err.startswith("rotor: error:")


def test_table_json_is_the_tables_json(capsys):
    from rotor.engine.file import load_engine
    from rotor.engine.table import crank_table

    rc, out, _ = run_cli(capsys, "table", "4chn15", "--step", "30", "--json")
    assert rc == 0
    assert json.loads(out) == crank_table(load_engine("4chn15"), step_deg=30.0).to_json_dict()
    rc, _, err = run_cli(capsys, "table", "4chn15", "--json", "--format", "csv")
    assert rc == 2 and "not allowed with" in err


def test_info_prints_the_results_summary(capsys):
    from rotor.engine.file import load_engine
    from rotor.engine.summary import engine_summary

    rc, out, _ = run_cli(capsys, "info", "v8", "--rpm", "2000")
    assert rc == 0 and out == engine_summary(load_engine("v8"), rpm=2000).summary()


def test_steady_json_is_the_results_json(capsys):
    from rotor.dynamics.steady import steady_state
    from rotor.engine.file import load_engine

    rc, out, _ = run_cli(capsys, "steady", "4chn15", "--json")
    assert rc == 0
    got, want = json.loads(out), steady_state(load_engine("4chn15")).to_json_dict()
    got.pop("wall_s"), want.pop("wall_s")
    assert got == want


def test_presets_json(capsys):
    rc, out, _ = run_cli(capsys, "presets", "--json")
    names = {p["name"]: p["engine"] for p in json.loads(out)["presets"]}
    assert rc == 0 and names["4chn15"] == "4ChN15/20.5 diesel" and "tue-single" in names


def test_solver_error_exits_1_and_closed_pipe_0(monkeypatch, capsys):
    import rotor.dynamics.steady
    from rotor.errors import NoSteadyStateError

    def no_answer(*a, **k):
        raise NoSteadyStateError("no periodic solution\nat all")

    monkeypatch.setattr(rotor.dynamics.steady, "steady_state", no_answer)
    rc, out, err = run_cli(capsys, "steady", "4chn15")
    assert rc == 1 and out == "" and err == "rotor: no periodic solution at all\n"

    def closed(*a, **k):
        raise BrokenPipeError

    monkeypatch.setattr(rotor.dynamics.steady, "steady_state", closed)
    assert run_cli(capsys, "steady", "4chn15")[0] == 0


@pytest.mark.parametrize(
    "argv",
    [
        ["steady", "nosuch"],
        ["simulate", "4chn15", "--misfire", "3-1"],
        ["analyze", "missing.csv", "--wheel", "60-2"],
        ["analyze", "missing.csv", "--compression-ratio", "9"],
        ["flywheel", "4chn15", "--delta", "0.01,0.02"],
        ["plot", "4chn15", "--out", "x"],
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv, capsys):
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2 and out == "" and err.count("\n") == 1 and "error:" in err


# ----------------------------------------------------------------------------- where outputs go
def test_table_output_dash_is_standard_output(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_cli(capsys, "table", "4chn15", "--step", "90", "--format", "csv", "--output", "-")
    assert rc == 0 and err == "" and out.startswith("angle_deg,s_m,") and len(out.splitlines()) == 1 + 9
    assert list(tmp_path.iterdir()) == []  # no file named "-"


@pytest.fixture
def outputs(tmp_path):
    """A log, a named pipe (standing in for a device such as /dev/null) and a link to a
    user's file (standing in for /dev/stdout), in ``tmp_path``."""
    (tmp_path / "rec.csv").write_text("0.1\n0.2\n")
    os.mkfifo(tmp_path / "pipe")
    (tmp_path / "mine.txt").write_text("the user's\n")
    (tmp_path / "link").symlink_to(tmp_path / "mine.txt")
    return tmp_path


LOG_COMMANDS = {
    "table --output": ["table", "4chn15", "--output"],
    "analyze --save-tooth-errors": ["analyze", "{log}", "--wheel", "60-2", "--save-tooth-errors"],
    "diagnose --save-calibration": ["diagnose", "{log}", "--engine", "4chn15", "--save-calibration"],
    "calibrate --output": ["calibrate", "{log}", "--engine", "4chn15", "--output"],
    "simulate --record": ["simulate", "4chn15", "--cycles", "2", "--record"],
}


def _argv(words, tmp_path, value):
    return [w.format(log=tmp_path / "rec.csv") for w in words] + [str(value)]


def _unchanged(tmp_path):
    assert stat.S_ISFIFO(os.lstat(tmp_path / "pipe").st_mode) and (tmp_path / "link").is_symlink()
    assert (tmp_path / "mine.txt").read_text() == "the user's\n" and (tmp_path / "rec.csv").read_text() == "0.1\n0.2\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "mine.txt", "pipe", "rec.csv"]


@pytest.mark.parametrize("command", list(LOG_COMMANDS))
def test_an_output_onto_a_pipe_or_a_link_is_refused_and_left_as_it_is(command, outputs, capsys):
    for name, words in (("pipe", "is a named pipe (FIFO), not a regular file"), ("link", "is a link to")):
        rc, out, err = run_cli(capsys, *_argv(LOG_COMMANDS[command], outputs, outputs / name))
        assert rc == 2 and out == "" and err.count("\n") == 1, err
        assert err.startswith(f"rotor: error: {outputs / name}: {words}"), err
    _unchanged(outputs)


@pytest.mark.parametrize(
    "argv,words",
    [
        (["analyze", "{log}", "--wheel", "60-2", "--save-tooth-errors", "-"], "--save-tooth-errors -: "),
        (["diagnose", "{log}", "--engine", "4chn15", "--save-calibration", "-"], "--save-calibration -: "),
        (["calibrate", "{log}", "--engine", "4chn15", "--output", "-"], "--output -: "),
        (["simulate", "4chn15", "--record", "-"], "--record -: "),
        (["balance", "4chn15", "--plot", "-"], "--plot -: --plot names a folder, not standard output"),
        (["report", "4chn15", "--out", "-"], "--out -: --out names a folder, not standard output"),
    ],
    ids=["--save-tooth-errors", "--save-calibration", "calibrate --output", "--record", "--plot", "--out"],
)
def test_dash_is_refused_where_it_is_not_standard_output(argv, words, outputs, capsys, monkeypatch):
    monkeypatch.chdir(outputs)
    rc, out, err = run_cli(capsys, *[w.format(log=outputs / "rec.csv") for w in argv])
    assert rc == 2 and out == "" and err.count("\n") == 1 and err.startswith(f"rotor: error: {words}"), err
    _unchanged(outputs)


@pytest.mark.parametrize(
    "argv,output,source",
    [
        (["analyze", "{rec}", "--wheel", "60-2", "--save-tooth-errors", "{rec}"], "--save-tooth-errors", "LOG"),
        (["analyze", "{rec}", "--wheel", "60-2", "--save-tooth-errors", "{hard}"], "--save-tooth-errors", "LOG"),
        (["analyze", "{rec}", "--wheel", "60-2", "--save-tooth-errors", "{dotted}"], "--save-tooth-errors", "LOG"),
        (
            ["analyze", "{rec}", "--tooth-errors", "{te}", "--save-tooth-errors", "{te}"],
            "--save-tooth-errors",
            "--tooth-errors",
        ),
        (["diagnose", "{rec}", "--engine", "4chn15", "--save-calibration", "{rec}"], "--save-calibration", "LOG"),
        (
            ["diagnose", "{rec}", "--engine", "4chn15", "--calibration", "{cal}", "--save-calibration", "{cal}"],
            "--save-calibration",
            "--calibration",
        ),
        (["calibrate", "{rec}", "--engine", "{eng}", "--output", "{eng}"], "--output", "--engine"),
        (["simulate", "{eng}", "--record", "{eng}"], "--record", "ENGINE"),
        (["table", "{eng}", "--output", "{eng}"], "--output", "ENGINE"),
    ],
    ids=[
        "the log",
        "a hard link",
        "another spelling",
        "--tooth-errors",
        "diagnose",
        "--calibration",
        "calibrate",
        "simulate",
        "table",
    ],
)
def test_an_output_that_is_a_file_the_command_reads_is_refused(argv, output, source, tmp_path, capsys):
    files = {"rec": "rec.csv", "te": "te.json", "cal": "cal.json", "eng": "engine.toml"}
    for name in files.values():
        (tmp_path / name).write_text(f"{name}\n")
    os.link(tmp_path / "rec.csv", tmp_path / "hard.csv")
    paths = {k: str(tmp_path / v) for k, v in files.items()}
    paths |= {"hard": str(tmp_path / "hard.csv"), "dotted": str(tmp_path / "." / "rec.csv")}
    rc, out, err = run_cli(capsys, *[w.format(**paths) for w in argv])
    assert rc == 2 and out == "" and err.count("\n") == 1, err
    assert err.startswith(f"rotor: error: {output} ") and f"is the same file as {source} " in err, err
    assert f"give {output} another file" in err
    assert all((tmp_path / name).read_text() == f"{name}\n" for name in files.values())
