"""Many logs in one call: ``rotor diagnose`` and ``rotor analyze`` with
several LOGs or a glob pattern, in this process (--jobs 1), on two threads (--jobs 2),
across a local pool of two spawned processes (diagnose_many(pool="process")) and on a
local two-worker Dask cluster (--scheduler, and
rotor.diagnostics.bulk.diagnose_many with a client); one JSON line per file, a bad file's
error line among the others' results, the exit status, and the same numbers as one call
per file."""

from __future__ import annotations

import json
import math
import sys

import pytest
from conftest import run_cli

import rotor
from rotor.cli import app
from rotor.cli.args import cli_json_words
from rotor.cli.logs import FileOutput, for_each_log
from rotor.diagnostics.bulk import analyze_many, diagnose_many, expand_logs, is_pattern
from rotor.diagnostics.synthetic import simulated_recording
from rotor.errors import EngineError, InternalError, LogError, SolverError

N = 8
DIAGNOSE = ["--engine", "tue-single", "--columns", "time,-,encoder_v", "--json"]


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """N short simulated bench recordings (3 cycles, each its own noise, start and load) and a bad file."""
    folder = tmp_path_factory.mktemp("bulk")
    paths = [
        str(simulated_recording(folder / f"rec{i:02d}.txt", cycles=3, seed=i, imep_scale=0.8 + 0.01 * i))
        for i in range(N)
    ]
    bad = folder / "zz_bad.txt"
    bad.write_text("0.0\n")
    return folder, paths, str(bad)


@pytest.fixture(scope="module")
def separate(logs):
    """The JSON of N separate `rotor diagnose LOG --json` calls (the single-LOG form, unchanged)."""
    _, paths, _ = logs
    out = []
    for p in paths:
        rc, text, err = run_cli(None, "diagnose", p, *DIAGNOSE)
        assert rc == 0, err
        assert text.startswith("{\n")  # one indented JSON object, as before
        out.append(json.loads(text))
    return out


def _same(a, b, path="result"):
    """The same JSON, numbers to 1e-12 relative (bitwise in practice)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{path}: keys {sorted(set(a) ^ set(b))}"
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300), f"{path}: {a!r} != {b!r}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def _lines(out):
    return [json.loads(line) for line in out.splitlines()]


def _check_bulk(rows, paths, separate, bad):
    assert [r["file"] for r in rows] == [*paths, bad]
    for row, one in zip(rows, separate):
        _same({k: v for k, v in row.items() if k != "file"}, one)
    assert set(rows[-1]) == {"file", "error", "exit_status"} and rows[-1]["exit_status"] == 2
    assert "no column for 'encoder_v'" in rows[-1]["error"]


def test_one_call_in_process_gives_the_numbers_of_separate_calls(logs, separate, capsys):
    folder, paths, bad = logs
    rc, out, err = run_cli(capsys, "diagnose", str(folder / "rec*.txt"), bad, *DIAGNOSE, "--jobs", "1")
    assert rc == 2, err  # one bad input among them
    _check_bulk(_lines(out), paths, separate, bad)
    assert err.splitlines()[-1] == f"rotor: 1 of {N + 1} files failed"
    assert f"rotor: error: {bad}: " in err


def test_two_threads_give_the_same_numbers(logs, separate, capsys):
    folder, paths, bad = logs
    rc, out, err = run_cli(capsys, "diagnose", bad, str(folder / "rec*.txt"), *DIAGNOSE, "--jobs", "2", "--quiet")
    assert rc == 2, err
    rows = _lines(out)
    _check_bulk([*rows[1:], rows[0]], paths, separate, bad)  # in the order given: the bad file first


def test_a_local_process_pool_gives_the_same_numbers(logs, separate):
    _, paths, bad = logs
    got = diagnose_many("tue-single", [*paths, bad], columns="time,-,encoder_v", jobs=2, pool="process", progress=False)
    assert isinstance(got[-1], LogError) and "no column" in str(got[-1])
    for res, one in zip(got[:-1], separate):
        _same(cli_json_words(json.loads(json.dumps(res.to_json_dict()))), one)


def test_a_local_dask_cluster_gives_the_same_numbers(logs, separate, capsys):
    pytest.importorskip("distributed")
    from dask.distributed import Client, LocalCluster

    folder, paths, bad = logs
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        got = diagnose_many(
            rotor.load_engine("tue-single"), [*paths, bad], columns="time,-,encoder_v", client=client, progress=False
        )
        assert isinstance(got[-1], LogError) and "no column" in str(got[-1])
        for res, one in zip(got[:-1], separate):
            _same(cli_json_words(json.loads(json.dumps(res.to_json_dict()))), one)
        rc, out, err = run_cli(
            capsys, "diagnose", *paths[:4], *DIAGNOSE, "--scheduler", cluster.scheduler_address, "--quiet"
        )
        assert rc == 0, err
        for row, one in zip(_lines(out), separate[:4]):
            _same({k: v for k, v in row.items() if k != "file"}, one)


def test_python_in_process_matches_and_keeps_the_order(logs, separate):
    _, paths, bad = logs
    got = diagnose_many("tue-single", [paths[3], bad, paths[0]], columns="time,-,encoder_v", jobs=1, progress=False)
    assert isinstance(got[1], LogError)
    _same(json.loads(json.dumps(got[0].to_json_dict())), separate[3])
    _same(json.loads(json.dumps(got[2].to_json_dict())), separate[0])


def test_text_form_names_each_file(logs, capsys):
    _, paths, bad = logs
    rc, out, err = run_cli(
        capsys, "diagnose", paths[0], paths[1], "--engine", "tue-single", "--columns", "time,-,encoder_v", "-j", "1"
    )
    assert out.startswith(f"==> {paths[0]} <==\n") and f"\n\n==> {paths[1]} <==\n" in out, err
    assert rc in (0, 1), err  # a file's text summary may need a steady state the engine lacks (exit 1)


def test_analyze_many_files(logs, capsys):
    _, paths, _ = logs
    args = ["--wheel", "60-2", "--columns", "time,pressure_v,encoder_v", "--json"]
    one = []
    for p in paths[:3]:
        rc, out, err = run_cli(capsys, "analyze", p, *args)
        assert rc == 0, err
        one.append(json.loads(out))
    rc, out, err = run_cli(capsys, "analyze", *paths[:3], *args, "--jobs", "1")
    assert rc == 0, err
    for row, d in zip(_lines(out), one):
        _same({k: v for k, v in row.items() if k != "file"}, d)
    got = analyze_many(paths[:2], "60-2", columns="time,pressure_v,encoder_v", jobs=1, progress=False)
    # the library's notes name its arguments (wheel='60-2'), the command line's its flags (--wheel 60-2)
    _same(cli_json_words(json.loads(json.dumps(got[1].to_json_dict()))), one[1])


def test_a_pattern_that_matches_nothing_is_an_error(tmp_path, capsys):
    rc, out, err = run_cli(capsys, "diagnose", str(tmp_path / "*.csv"), "--engine", "tue-single", "--json")
    assert rc == 2 and out == "" and err.count("\n") == 1
    assert "the pattern matches no file" in err
    rc, out, err = run_cli(capsys, "analyze", str(tmp_path / "nothing-[0-9].txt"))
    assert rc == 2 and "matches no file" in err
    with pytest.raises(LogError, match="matches no file"):
        expand_logs(str(tmp_path / "*.txt"))


def test_expand_logs(tmp_path):
    for name in ("b.csv", "a.csv", "c[1].csv"):
        (tmp_path / name).write_text("0\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "d.csv").write_text("0\n")
    a, b, c = (str(tmp_path / n) for n in ("a.csv", "b.csv", "c[1].csv"))
    assert expand_logs(str(tmp_path / "*.csv")) == [a, b, c]
    assert expand_logs([c, str(tmp_path / "?.csv"), a]) == [c, a, b]  # a literal name with [ ], no repeats
    assert str(tmp_path / "sub" / "d.csv") in expand_logs(str(tmp_path / "**" / "*.csv"))
    assert not is_pattern(c) and is_pattern(str(tmp_path / "*.csv"))
    assert expand_logs(str(tmp_path / "missing.csv")) == [str(tmp_path / "missing.csv")]  # that file's error


def test_scheduler_without_dask_is_one_line(monkeypatch, tmp_path, capsys):
    paths = [str(tmp_path / "a.txt"), str(tmp_path / "b.txt")]
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    rc, out, err = run_cli(capsys, "diagnose", *paths[:2], *DIAGNOSE, "--scheduler", "tcp://127.0.0.1:1")
    assert rc == 2 and out == "" and err.count("\n") == 1
    assert "pip install 'crank-rotor[dask]'" in err


def test_options_of_one_log_refuse_several(tmp_path, capsys):
    paths = [str(tmp_path / "a.txt"), str(tmp_path / "b.txt")]
    rc, _, err = run_cli(capsys, "diagnose", *paths[:2], *DIAGNOSE, "--save-calibration", str(tmp_path / "c.json"))
    assert rc == 2 and "--save-calibration takes a single LOG" in err
    rc, _, err = run_cli(capsys, "analyze", *paths[:2], "--save-tooth-errors", str(tmp_path / "t.json"))
    assert rc == 2 and "--save-tooth-errors takes a single LOG" in err
    rc, _, err = run_cli(capsys, "diagnose", *paths[:2], *DIAGNOSE, "--jobs", "0")
    assert rc == 2 and "must be 1 or more" in err


def _failing(exc):
    def one(args, log):
        raise exc

    return one


@pytest.mark.parametrize(
    "exc,status",
    [
        (LogError("x.csv: bad row 3"), 2),
        (EngineError("rpm = -1"), 2),
        (SolverError("no steady state"), 1),
        (FileNotFoundError(2, "No such file or directory", "x.csv"), 2),
        (InternalError("a NaN"), 70),
        (TypeError("unsupported operand"), 70),
        (MemoryError(), 2),
    ],
    ids=lambda v: type(v).__name__ if isinstance(v, BaseException) else str(v),
)
def test_a_files_error_is_classified_as_the_command_line_does(exc, status, capsys, tmp_path):
    """The exit status and message of one file among several are those of rotor.cli.app.report_error."""
    import argparse

    log = str(tmp_path / "x.csv")
    assert app.report_error(exc) == status
    expected = capsys.readouterr().err.strip()
    args = argparse.Namespace(log=[log, log + "2"], json=True, quiet=True, jobs=1, scheduler=None)
    with pytest.raises(SystemExit) as e:
        for_each_log(args, _failing(exc), "testing")
    assert e.value.code == status
    out, err = capsys.readouterr()
    row = json.loads(out.splitlines()[0])
    assert row["exit_status"] == status and row["file"] == log
    first = err.splitlines()[0]
    if status == 70:  # the internal error's advice differs (no --debug for one file)
        assert first.startswith("rotor: internal error: this is a bug in rotor: ")
    elif isinstance(exc, MemoryError):  # the advice names the log, not the run's options
        assert first.startswith(f"rotor: error: {log}: the machine ran out of memory")
    else:
        assert first.replace(f"{log}: ", "", 1) == expected


def test_file_output_is_plain_data():
    assert FileOutput({"a": 1}, "").warnings == []
