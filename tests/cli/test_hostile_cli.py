"""Hostile but realistic command lines: for every command of
``rotor --help``, a table of bad numbers, bad files and bad output paths, each with the
exit status and a fragment of the one line it must print; the error contract of the
command line (internal errors, ``--debug``, Ctrl-C, out of memory); the one writer of JSON
and CSV that never writes NaN or Infinity; file errors that name the user's path; wrong
Python types at the base layer's edge (``save_json``, ``load_json``, ``json_safe``).

Everything runs in-process through :func:`rotor.cli.app.main` (one subprocess checks the
real exit status and stderr of ``python -m rotor.cli``)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, run_cli

from rotor.cli import app
from rotor.cli.output import csv_text, json_text, print_json
from rotor.errors import EngineError, InternalError, LogError, SolverError
from rotor.fileio import atomic_path, find_nonfinite, load_json, save_json, write_text_atomic
from rotor.results import json_safe

TWO_PI = 2 * np.pi


def tooth_times(rpm: float = 3000.0, revs: int = 12, teeth: int = 60, missing: int = 2) -> np.ndarray:
    """Edge times [s] of an N−M wheel at ``rpm`` with a small half-order fluctuation."""
    w = TWO_PI * rpm / 60
    ang = 0.37 + TWO_PI * np.arange(revs)[:, None] + TWO_PI / teeth * np.arange(teeth - missing)[None, :]
    ang = ang.ravel()
    return ang / w + 0.02 * np.sin(ang / 2) / w


@pytest.fixture(scope="module")
def places(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """A tooth-time log, a regular file, a folder and a missing folder to name in the cases."""
    root = tmp_path_factory.mktemp("hostile")
    log = root / "teeth.csv"
    np.savetxt(log, tooth_times(), fmt="%.12g")
    (root / "file").write_text("not a folder\n")
    (root / "dir").mkdir()
    (root / "full").mkdir()
    (root / "full" / "notes.txt").write_text("not a report\n")
    preset = (ROOT / "rotor" / "presets" / "4chn15.toml").read_text(encoding="utf-8")
    bad_web = root / "bad_web.toml"
    bad_web.write_text(preset + "\n[[counterweights]]\nweb = 9\nmass_kg = 2.0\nradius_m = 0.08\nangle_deg = 180\n")
    bad_journals = root / "bad_journals.toml"
    bad_journals.write_text(preset.replace("[crankshaft]\n", "[crankshaft]\nmain_journals = 4\n"))
    return {
        "log": str(log),
        "file": str(root / "file"),
        "dir": str(root / "dir"),
        "full": str(root / "full"),
        "missing": str(root / "missing"),
        "bad_web": str(bad_web),
        "bad_journals": str(bad_journals),
    }


def assert_contract(rc: int, out: str, err: str, argv: list[str]) -> None:
    """The promises of every run: a known exit status, no traceback, no internal error,
    one line on stderr when it fails, and JSON without NaN when it prints JSON."""
    assert rc in (0, 1, 2), f"rotor {' '.join(argv)}: exit {rc}\n{err}"
    assert "Traceback" not in err and "internal error" not in err, err
    if rc != 0:
        lines = [line for line in err.splitlines() if line.strip() and not line.startswith("rotor: warning:")]
        assert len(lines) == 1, f"rotor {' '.join(argv)}: {len(lines)} lines on stderr:\n{err}"
    elif "--json" in argv:
        json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in the JSON of rotor {' '.join(argv)}"))


TOOTH = ["--wheel", "60-2", "--columns", "tooth_time_s"]

# (argv with {log}, {file}, {dir}, {missing} filled in, exit status, fragment of stderr)
CASES = [
    # the parser itself
    ([], 2, "required: COMMAND"),
    (["nosuchcommand"], 2, "invalid choice"),
    (["presets", "--bogus"], 2, "unrecognized arguments"),
    # table
    (["table", "4chn15", "--step", "0"], 2, "must be a positive number"),
    (["table", "4chn15", "--step", "nan"], 2, "must be a positive number"),
    (["table", "4chn15", "--step", "-inf"], 2, "must be a positive number"),
    (["table", "4chn15", "--step", "1e-7"], 2, "use a larger step"),
    (["table", "4chn15", "--step", "1e300"], 2, "up to 720 degrees"),
    (["table", "4chn15", "--rpm", "1e300"], 2, "rpm = 1e+300"),
    (["table", "4chn15", "--cylinder", "0"], 2, "cylinder = 0"),
    (["table", "4chn15", "--cylinder", "99"], 2, "cylinder"),
    (["table", "4chn15", "--cylinder", "-99999999999999999999"], 2, "cylinder"),
    (["table", "4chn15", "--output", "{dir}"], 2, "{dir}: is a folder"),
    (["table", "4chn15", "--output", "{dir}/"], 2, "{dir}/: is a folder"),
    (["table", "4chn15", "--output", "{file}/t.csv"], 2, "{file}/t.csv: {file} is a file, not a folder"),
    (["table", "4chn15", "--output", "{missing}/t.csv"], 2, "{missing}/t.csv: no folder"),
    (["table", "4chn15", "--format", "csv", "--json"], 2, "not allowed with"),
    # info
    (["info", "{file}"], 2, "{file}: not a valid TOML file"),
    (["info", "{dir}"], 2, "{dir}: is a directory"),
    (["info", "{missing}.toml"], 2, "{missing}.toml"),
    (["info", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    (["info", "4chn15", "--rpm", "-5"], 2, "must be a positive number"),
    (["info", "4chn15", "--rpm", "1e300", "--json"], 2, "rpm = 1e+300"),
    # plot
    (["plot", "4chn15", "--plot", "{file}"], 2, "{file}: is a file, not a folder"),
    (["plot", "4chn15", "--plot", "{file}/sub"], 2, "{file}/sub: {file} is a file, not a folder"),
    (["plot", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    # presets
    (["presets", "extra"], 2, "unrecognized arguments"),
    # wheels
    (["wheels", "nosuchwheel"], 2, "not in the catalogue"),
    (["wheels", "36-2", "extra"], 2, "unrecognized arguments"),
    (["wheels", "\x1b[31m"], 2, "not in the catalogue"),
    # steady
    (["steady", "4chn15", "--load", "abc"], 2, "--load 'abc'"),
    (["steady", "4chn15", "--load", "constant:nan"], 2, "--load 'constant:nan'"),
    (["steady", "4chn15", "--load", "propeller:inf,1000"], 2, "--load 'propeller:inf,1000'"),
    (["steady", "4chn15", "--fidelity", "bogus"], 2, "invalid choice"),
    (["steady", "{file}"], 2, "not a valid TOML file"),
    (["steady", "4chn15", "--rpm", "9223372036854775808"], 2, "between 0.1 and 100000 rpm"),
    (["steady", "4chn15", "--load", "constant:1e300"], 1, "fuel scale gives no finite speed"),
    # simulate
    (["simulate", "4chn15", "--cycles", "0"], 2, "must be 1 or more"),
    (["simulate", "4chn15", "--cycles", "1.5"], 2, "is not a whole number"),
    (["simulate", "4chn15", "--cycles", "1000000000000"], 2, "memory"),
    (["simulate", "4chn15", "--cycles", "9" * 5000], 2, "is not a whole number"),
    (["simulate", "4chn15", "--rtol", "1e300", "--cycles", "1"], 2, "rtol = 1e+300"),
    (["simulate", "4chn15", "--rpm", "-1"], 2, "must be zero or positive"),
    (["simulate", "4chn15", "--misfire", "99:1"], 2, "cycle 99 is not in the run"),
    (["simulate", "4chn15", "--misfire", "3:9"], 2, "cylinder 9 does not exist"),
    (["simulate", "4chn15", "--misfire", "x"], 2, "CYCLE:CYLINDER"),
    (["simulate", "4chn15", "--governor", "0"], 2, "must be a positive number"),
    # analyze
    (["analyze", "{log}", *TOOTH, "--max-order", "1e-9"], 2, "keeps no order"),
    (["analyze", "{log}", *TOOTH, "--points-per-cycle", "100000000"], 2, "memory"),
    (["analyze", "{log}", *TOOTH, "--tdc-deg", "nan"], 2, "a finite angle from -3600 to 3600 degrees"),
    (["analyze", "{log}", *TOOTH, "--tdc-deg", "inf"], 2, "a finite angle from -3600 to 3600 degrees"),
    (["analyze", "{log}", "--wheel", "0-0", "--columns", "tooth_time_s"], 2, "0 teeth"),
    (["analyze", "{log}", *TOOTH, "--compression-ratio", "16"], 2, "go together"),
    (["analyze", "{log}", *TOOTH, "--engine-orders", "x"], 2, "--engine-orders 'x'"),
    (["analyze", "{log}", *TOOTH, "--tooth-errors", "{file}"], 2, "{file}: not a tooth-error file"),
    (["analyze", "{log}", *TOOTH, "--tooth-errors", "{dir}"], 2, "{dir}: is a folder"),
    (["analyze", "{log}", *TOOTH, "--save-tooth-errors", "{dir}"], 2, "{dir}: is a folder: give a file name"),
    (
        ["analyze", "{log}", *TOOTH, "--save-tooth-errors", "{file}/x.json"],
        2,
        "{file}/x.json: {file} is a file, not a folder",
    ),
    (["analyze", "{log}", *TOOTH, "--plot", "{file}"], 2, "{file}: is a file, not a folder"),
    (["analyze", "{file}", "--wheel", "60-2"], 2, "{file}: line 1"),
    (["analyze", "{dir}", "--wheel", "60-2"], 2, "{dir}: is a folder"),
    (["analyze", "{missing}.csv", "--wheel", "60-2"], 2, "{missing}.csv: No such file"),
    # several LOGs or a pattern: the run's own errors are one line before any file is read
    (["analyze", "{dir}/*.csv", "--wheel", "60-2"], 2, "{dir}/*.csv: the pattern matches no file"),
    (["analyze", "{log}", "{log}", *TOOTH, "--save-tooth-errors", "{file}"], 2, "takes a single LOG"),
    (["analyze", "{log}", "{log}", *TOOTH, "--jobs", "0"], 2, "must be 1 or more"),
    (["analyze", "{log}", "{log}", *TOOTH, "--jobs", "two"], 2, "is not a whole number"),
    # diagnose
    (["diagnose", "{log}", "--engine", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    (["diagnose", "{log}", "{log}", "--engine", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    (["diagnose", "{dir}/[0-9]*.txt", "--engine", "4chn15"], 2, "the pattern matches no file"),
    (["diagnose", "{log}", "{log}", "--engine", "4chn15", "--save-calibration", "{dir}/c.json"], 2, "a single LOG"),
    (["diagnose", "{log}", "--engine", "4chn15", *TOOTH, "--calibration", "{file}"], 2, "not a calibration file"),
    (["diagnose", "{log}", "--engine", "4chn15", *TOOTH, "--calibration", "{dir}"], 2, "{dir}: is a folder"),
    (
        ["diagnose", "{log}", "--engine", "4chn15", *TOOTH, "--save-calibration", "{file}/c.json"],
        2,
        "{file}/c.json: {file} is a file, not a folder",
    ),
    (["diagnose", "{log}", "--engine", "4chn15", *TOOTH, "--threshold", "-1"], 2, "must be a positive number"),
    (["diagnose", "{log}", "--engine", "4chn15", *TOOTH], 2, "TDC is not known"),
    # calibrate
    (["calibrate", "{log}", "--engine", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    (["calibrate", "{log}", "--engine", "tue-single", *TOOTH], 2, "no pressure channel"),
    (["calibrate", "{log}", "--engine", "tue-single", *TOOTH, "--pressure-gain", "abc"], 2, "'abc': a positive gain"),
    (["calibrate", "{log}", "--engine", "tue-single", *TOOTH, "--pressure-gain", "-5"], 2, "'-5': a positive gain"),
    (["calibrate", "{log}", "--engine", "tue-single", *TOOTH, "--intake-pa", "-1"], 2, "must be a positive number"),
    (
        ["calibrate", "{log}", "--engine", "tue-single", *TOOTH, "--output", "{file}/c.json"],
        2,
        "{file}/c.json: {file} is a file, not a folder",
    ),
    # monitor
    (["monitor", "{log}", "--engine", "4chn15", "--wheel", "60-2"], 2, "--tdc-deg: where cylinder 1's TDC lies"),
    (["monitor", "{missing}/x.csv", "--engine", "4chn15", "--wheel", "60-2"], 2, "{missing}/x.csv: No such file"),
    (["monitor", "{dir}", "--engine", "4chn15", "--wheel", "60-2"], 2, "{dir}: Is a directory"),
    (["monitor", "{log}", "--wheel", "60-2"], 2, "--engine ENGINE or --cylinders N"),
    (["monitor", "{log}", "--wheel", "60", "--cylinders", "4", "--tdc-deg", "0"], 2, "a wheel with a gap"),
    (["monitor", "{log}", "--wheel", "60-2", "--cylinders", "0"], 2, "cylinders from 1 to 64"),
    (["monitor", "{file}", "--wheel", "60-2", "--cylinders", "4", "--tdc-deg", "0"], 2, "no tooth time in the input"),
    (
        ["monitor", "{log}", "--wheel", "60-2", "--cylinders", "4", "--firing-order", "1,2,2,4", "--tdc-deg", "0"],
        2,
        "each cylinder 1 … 4 once",
    ),
    (
        ["monitor", "{log}", "--engine", "4chn15", "--wheel", "60-2", "--threshold", "-1"],
        2,
        "must be a positive number",
    ),
    # flywheel
    (["flywheel", "4chn15", "--delta", "0"], 2, "must be a positive number"),
    (["flywheel", "4chn15", "--delta", "nan"], 2, "must be a positive number"),
    (["flywheel", "4chn15", "--delta", "0.01,0.02"], 2, "gives 2 values for 1 speeds"),
    (["flywheel", "4chn15", "--delta", "0.01", "--rpm", "0.001"], 2, "rpm = 0.001"),
    (["flywheel", "4chn15", "--delta", "0.01", "--shaft-inertia", "-1"], 2, "must be zero or positive"),
    (["flywheel", "4chn15", "--delta", "1e-300"], 2, "delta = 1e-300: a target below 1e-05"),
    # loads
    (["loads", "4chn15", "--rpm", "-5"], 2, "must be a positive number"),
    (["loads", "4chn15", "--rpm", "1e300"], 2, "= 1e+300: must be a positive, finite speed"),
    (["loads", "4chn15", "--step", "7"], 2, "must divide the 720° cycle"),
    (["loads", "4chn15", "--step", "0"], 2, "must be a positive number"),
    (["loads", "4chn15", "--step", "1e-9"], 2, "use a larger step"),
    (["loads", "{bad_web}"], 2, "web 9 does not exist"),
    (["loads", "{bad_journals}"], 2, "main_journals = 4"),
    (["loads", "4chn15", "--plot", "{file}"], 2, "{file}: is a file, not a folder"),
    (["loads", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    # balance
    (["balance", "4chn15", "--orders", "0"], 2, "must be 1 or more"),
    (["balance", "4chn15", "--orders", "1.5"], 2, "is not a whole number"),
    (["balance", "4chn15", "--orders", "1000"], 2, "orders) = 1000"),
    (["balance", "4chn15", "--rpm", "-5"], 2, "must be a positive number"),
    (["balance", "{bad_web}"], 2, "web 9 does not exist"),
    (["balance", "4chn15", "--plot", "{file}"], 2, "{file}: is a file, not a folder"),
    # modes, campbell, torsion (an engine needs a [torsion] table)
    (["modes", "4chn15"], 2, "has no [torsion] table; add one to its file"),
    (["modes", "mwm6", "--rpm", "-5"], 2, "must be a positive number"),
    (["modes", "mwm6", "--plot", "{file}"], 2, "{file}: is a file, not a folder"),
    (["campbell", "4chn15"], 2, "has no [torsion] table; add one to its file"),
    (["campbell", "mwm6", "--rpm-range", "2400:600"], 2, "expected 0 < A < B"),
    (["campbell", "mwm6", "--rpm-range", "600"], 2, "expected two speeds in rpm as A:B"),
    (["campbell", "mwm6", "--rpm-range", "0:1e300"], 2, "expected 0 < A < B"),
    (["campbell", "mwm6", "--rpm-range", "600:1e9"], 2, "upper end = 1000000000.0: must be a positive"),
    (["torsion", "4chn15", "--rpm", "1250"], 2, "has no [torsion] table; add one to its file"),
    (["torsion", "mwm6", "--rpm", "nan"], 2, "must be a positive number"),
    (["torsion", "mwm6", "--rpm", "1e300"], 2, "= 1e+300: must be a positive, finite speed"),
    (["torsion", "{file}"], 2, "not a valid TOML file"),
    # report
    (["report", "4chn15"], 2, "the following arguments are required: --out"),
    (["report", "4chn15", "--out", "{file}"], 2, "{file}: is a file, not a folder for the report"),
    (["report", "4chn15", "--out", "{file}/sub"], 2, "{file}/sub: {file} is a file, not a folder"),
    (["report", "4chn15", "--out", "{full}"], 2, "{full}: holds other files (notes.txt)"),
    (["report", "4chn15", "--out", "{missing}/r", "--step", "7"], 2, "must divide the 720° cycle"),
    (["report", "4chn15", "--out", "{missing}/r", "--rpm", "-5"], 2, "must be a positive number"),
    (["report", "4chn15", "--out", "{missing}/r", "--delta", "0"], 2, "must be a positive number"),
    (["report", "4chn15", "--out", "{missing}/r", "--delta", "1e-300"], 2, "delta = 1e-300"),
    (["report", "4chn15", "--out", "{missing}/r", "--orders", "0"], 2, "must be 1 or more"),
    (["report", "{bad_web}", "--out", "{missing}/r"], 2, "web 9 does not exist"),
    # demo
    (["demo", "--engine", "nosuchpreset"], 2, "neither an engine file nor a preset"),
    (["demo", "--bogus"], 2, "unrecognized arguments"),
]


def _fill(text: str, places: dict[str, str]) -> str:
    for k, v in places.items():
        text = text.replace("{" + k + "}", v)
    return text


@pytest.mark.parametrize("argv,code,fragment", CASES, ids=lambda v: " ".join(v)[:60] if isinstance(v, list) else None)
def test_hostile_case_is_one_line_with_its_exit_status(
    argv: list[str], code: int, fragment: str, places: dict[str, str], capsys: pytest.CaptureFixture
) -> None:
    argv = [_fill(a, places) for a in argv]
    rc, out, err = run_cli(capsys, *argv)
    assert_contract(rc, out, err, argv)
    assert rc == code, f"rotor {' '.join(argv)}: exit {rc}, expected {code}\n{err}"
    assert _fill(fragment, places) in err, err
    assert ".rotor-" not in err, f"the temporary file is named instead of the user's path: {err}"


def test_every_command_has_hostile_cases() -> None:
    """The table covers every command ``rotor --help`` lists."""
    parser = app.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    commands = set(sub.choices)
    argvs = [c.values[0] if hasattr(c, "values") else c[0] for c in CASES]
    covered = {argv[0] for argv in argvs if argv}
    assert commands <= covered, f"commands without hostile cases: {sorted(commands - covered)}"


# ----------------------------------------------------------------------------- the error contract
def _raising(exc: BaseException):
    def command(args: object) -> None:
        raise exc

    return command


def _concretization_error() -> BaseException:
    import jax
    import jax.numpy as jnp

    try:
        jax.jit(lambda n: jnp.zeros(int(n)))(3)
    except Exception as e:  # noqa: BLE001 - the error JAX raises, whatever its class
        return e
    raise AssertionError("JAX did not refuse")


def _numpy_value_error() -> BaseException:
    try:
        np.min(np.array([]))
    except ValueError as e:
        return e
    raise AssertionError("numpy did not refuse")


CONTRACT = [
    (TypeError("unsupported operand"), 70, "rotor: internal error: this is a bug in rotor: TypeError: unsupported"),
    (KeyError("x"), 70, "internal error: this is a bug in rotor: KeyError"),
    (RuntimeError("XlaRuntimeError: out of range"), 70, "internal error"),
    (InternalError('the result\'s "mean_rpm" is NaN'), 70, 'InternalError: the result\'s "mean_rpm" is NaN'),
    (KeyboardInterrupt(), 130, "rotor: interrupted"),
    (MemoryError(), 2, "ran out of memory"),
    (RuntimeError("RESOURCE_EXHAUSTED: Out of memory allocating 22500000000 bytes."), 2, "ran out of memory"),
    (SolverError("no steady state"), 1, "rotor: no steady state"),
    (EngineError("bore_m = 1e300: too big"), 2, "rotor: error: bore_m"),
    (LogError("x.csv: bad\nsecond line"), 2, "rotor: error: x.csv: bad second line"),
    (ValueError("cylinder 9 does not exist"), 2, "rotor: error: cylinder 9"),
    (FileNotFoundError(2, "No such file or directory", "my.toml"), 2, "rotor: error: my.toml: No such file"),
]


@pytest.mark.parametrize(
    "exc,code,fragment", CONTRACT, ids=lambda v: type(v).__name__ if isinstance(v, BaseException) else None
)
def test_every_exception_is_one_line_with_its_exit_status(
    exc: BaseException, code: int, fragment: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    from rotor.cli import engine as cli_engine

    monkeypatch.setattr(cli_engine, "cmd_presets", _raising(exc))
    rc, out, err = run_cli(capsys, "presets")
    assert rc == code and fragment in err, (rc, err)
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    if code == 70:
        assert "(run again with --debug for the traceback; please report it)" in err
    rc, out, err = run_cli(capsys, "--debug", "presets")  # the traceback, then the same line
    assert rc == code and fragment in err
    if code not in (0,):
        assert "Traceback (most recent call last)" in err
        assert err.strip().splitlines()[-1].startswith("rotor: ")


@pytest.mark.parametrize("make", [_concretization_error, _numpy_value_error])
def test_foreign_errors_are_internal_errors(
    make, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    """A JAX error (ConcretizationTypeError) or a ValueError raised inside numpy is a check
    rotor missed: an internal error, one short line, never numpy's words as an input error."""
    from rotor.cli import engine as cli_engine

    exc = make()
    monkeypatch.setattr(cli_engine, "cmd_presets", _raising(exc))
    rc, out, err = run_cli(capsys, "presets")
    assert rc == 70, err
    assert err.startswith(f"rotor: internal error: this is a bug in rotor: {type(exc).__name__}: ")
    assert len(err.strip().splitlines()) == 1 and len(err) < 700, err


def test_closed_pipe_exits_0_silently(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
    from rotor.cli import engine as cli_engine

    monkeypatch.setattr(cli_engine, "cmd_presets", _raising(BrokenPipeError(32, "Broken pipe")))
    assert run_cli(capsys, "presets")[::2] == (0, "")


def test_exit_statuses_are_documented() -> None:
    assert "70" in app.EPILOG and "130" in app.EPILOG and "--debug" in app.EPILOG
    assert "70" in (app.__doc__ or "") and "130" in (app.__doc__ or "")


def test_the_real_command_exits_2_with_one_line(tmp_path: Path) -> None:
    """One subprocess: the exit status and stderr the shell sees."""
    r = subprocess.run(
        [sys.executable, "-m", "rotor.cli", "table", "4chn15", "-o", str(tmp_path / "no" / "t.csv")],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip() == f"rotor: error: {tmp_path / 'no' / 't.csv'}: no folder {tmp_path / 'no'} (make it first)"


# ----------------------------------------------------------------------------- one writer of JSON and CSV
def test_json_writer_names_the_key_path_of_a_nan() -> None:
    with pytest.raises(InternalError, match=r'the result\'s "mean_rpm" is NaN'):
        json_text({"mean_rpm": math.nan})
    with pytest.raises(InternalError, match=r'the result\'s "cycles"\[1\]\["max_rpm"\] is Infinity'):
        json_text({"cycles": [{"max_rpm": 1.0}, {"max_rpm": math.inf}]})
    with pytest.raises(InternalError, match=r'"x" is -Infinity'):
        json_text({"x": np.float64(-np.inf)})
    assert json.loads(json_text({"x": None, "y": [1, 2.5]})) == {"x": None, "y": [1, 2.5]}


def test_a_nan_in_a_result_is_an_internal_error_at_the_command_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    from rotor.cli import engine as cli_engine

    monkeypatch.setattr(cli_engine, "cmd_presets", lambda args: print_json({"mean_rpm": math.nan}))
    rc, out, err = run_cli(capsys, "presets")
    assert rc == 70 and out == ""
    assert 'the result\'s "mean_rpm" is NaN' in err and "Out of range float" not in err


def test_csv_writer_refuses_non_finite_values_naming_column_and_row() -> None:
    assert csv_text(["a_m", "b_N"], [(1.0, -0.0), (2.5, 3)]) == "a_m,b_N\n1,0\n2.5,3\n"
    with pytest.raises(InternalError, match=r'the crank table\'s "b_N" in row 2 is NaN'):
        csv_text(["a_m", "b_N"], [(1.0, 2.0), (2.0, math.nan)], what="the crank table")
    with pytest.raises(InternalError, match=r'"a_m" in row 1 is -Infinity'):
        csv_text(["a_m"], [(-math.inf,)])


def test_table_csv_goes_through_the_writer(capsys: pytest.CaptureFixture) -> None:
    from rotor.engine.file import load_engine
    from rotor.engine.table import crank_table

    rc, out, err = run_cli(capsys, "table", "4chn15", "--format", "csv", "--step", "30")
    assert rc == 0 and out == crank_table(load_engine("4chn15"), step_deg=30.0).to_csv()


def test_json_safe_keeps_nan_as_null_but_never_hides_an_infinity() -> None:
    assert json_safe({"a": np.nan, "b": [np.float32(1.5), np.int64(2)], "c": np.array([1.0, np.nan])}) == {
        "a": None,
        "b": [1.5, 2],
        "c": [1.0, None],
    }
    with pytest.raises(InternalError, match=r'"cycles"\[2\] is Infinity'):
        json_safe({"cycles": np.array([1.0, 2.0, np.inf])})
    with pytest.raises(InternalError, match=r'"x" is -Infinity'):
        json_safe({"x": -math.inf})
    with pytest.raises(TypeError, match=r'"s" is a set'):
        json_safe({"s": {1, 2}})
    with pytest.raises(TypeError, match="complex"):
        json_safe({"z": 1j})


def test_find_nonfinite() -> None:
    assert find_nonfinite({"a": [1, 2.0, {"b": None}]}) is None
    assert find_nonfinite({"a": [1, {"b": np.float32("nan")}]}) == (["a", 1, "b"], "NaN")


# ----------------------------------------------------------------------------- files and their paths
def test_file_errors_name_the_users_path(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("x")
    (tmp_path / "dir").mkdir()
    cases = {
        str(tmp_path / "dir"): "is a folder",
        str(tmp_path / "dir") + os.sep: "is a folder",
        str(tmp_path / "file" / "x.json"): "is a file, not a folder",
        str(tmp_path / "missing" / "x.json"): "no folder",
    }
    for path, words in cases.items():
        with pytest.raises(OSError) as info:
            write_text_atomic(path, "text")
        assert info.value.filename == path and words in str(info.value.strerror), info.value
        with pytest.raises(EngineError, match=words) as e:
            save_json(path, {"a": 1}, what="the calibration", error=EngineError)
        assert str(e.value).startswith(path + ": cannot write the calibration")
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".rotor-")]


def test_a_failed_write_names_the_path_not_the_temporary(tmp_path: Path) -> None:
    target = tmp_path / "out.json"
    with pytest.raises(OSError) as info:
        with atomic_path(target) as tmp:
            raise PermissionError(13, "Permission denied", tmp)
    assert info.value.filename == str(target)
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".rotor-")]


def test_save_figure_names_the_users_path(tmp_path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotor.plotting.common import save_figure

    (tmp_path / "fig.png").mkdir()
    with pytest.raises(IsADirectoryError) as info:
        save_figure(plt.subplots()[1], tmp_path / "fig.png")
    assert info.value.filename == str(tmp_path / "fig.png")
    with pytest.raises(ValueError, match=r"fig\.xyz: cannot save a plot as \.xyz"):
        save_figure(plt.subplots()[1], tmp_path / "fig.xyz")
    save_figure(plt.subplots()[1], tmp_path / "ok.png")
    assert (tmp_path / "ok.png").stat().st_size > 0


def test_save_json_refuses_nan_naming_the_key(tmp_path: Path) -> None:
    with pytest.raises(LogError, match=r'x\.json: cannot write the tooth errors: its "errors"\[1\] is NaN'):
        save_json(tmp_path / "x.json", {"errors": [0.0, math.nan]}, what="the tooth errors", error=LogError)
    assert not (tmp_path / "x.json").exists()


def test_load_json_reads_a_bom_and_refuses_binary(tmp_path: Path) -> None:
    p = tmp_path / "bom.json"
    p.write_bytes(b"\xef\xbb\xbf" + b'{"a": 1}')
    assert load_json(p, what="a calibration file") == {"a": 1}
    p.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(EngineError, match="bom.json: not a calibration file"):
        load_json(p, what="a calibration file", error=EngineError)
    with pytest.raises(IsADirectoryError):
        load_json(tmp_path, what="a calibration file")


@pytest.mark.parametrize(
    "call,argument",
    [
        (lambda: save_json(3, {}, what="x"), "path"),
        (lambda: save_json(b"x.json", {}, what="x"), "path"),
        (lambda: save_json("x.json", [1], what="x"), "data"),
        (lambda: save_json("x.json", {}, what=3), "what"),
        (lambda: save_json("x.json", {}, what="x", error="OSError"), "error"),
        (lambda: load_json(None, what="x"), "path"),
        (lambda: load_json("x.json", what=None), "what"),
        (lambda: write_text_atomic("x.txt", b"bytes"), "text"),
        (lambda: json_safe({"f": print}), '"f"'),
    ],
)
def test_wrong_python_types_name_the_argument(call, argument: str) -> None:
    with pytest.raises(TypeError, match=argument):
        call()
