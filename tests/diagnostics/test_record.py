"""A simulated run written as a wheel log (``rotor simulate --record``) and read back by the
tools that read bench recordings: the misfire comes back with the numbers it was given."""

import json

import numpy as np
import pytest
from conftest import run_cli

import rotor
from rotor.diagnostics.record import record_run, stated_phase


def test_simulate_record_then_diagnose_gives_the_misfire_back(tmp_path, capsys):
    log = tmp_path / "rec.csv"
    code, out, _ = run_cli(
        capsys, "simulate", "4chn15", "--cycles", "12", "--misfire", "5:3", "--record", str(log), "--wheel", "60-2"
    )
    assert code == 0 and f"wrote {log}" in out
    lines = log.read_text().splitlines()
    assert "tooth_time_s" in lines[:5] and "# tdc_after_gap_deg: 29.4" in lines
    truth = json.loads((tmp_path / "rec.truth.json").read_text())
    assert truth["misfires"] == [[5, 3]] and truth["tdc_after_gap_deg"] == pytest.approx(29.4)
    imep = np.asarray(truth["imep_pa"])
    assert imep.shape == (12, 4) and imep[4, 2] < 0.05 * np.median(imep)  # cycle 5, cylinder 3
    code, out, _ = run_cli(capsys, "analyze", str(log), "--wheel", "60-2", "--json")
    a = json.loads(out)
    assert code == 0 and len(a["cycles"]) == 12 and a["tdc_after_gap_deg"] == pytest.approx(29.4)
    assert [c["cycle"] for c in a["cycles"]] == list(range(1, 13))
    code, out, err = run_cli(capsys, "diagnose", str(log), "--engine", "4chn15", "--wheel", "60-2", "--json")
    d = json.loads(out)
    assert code == 0 and err == ""
    assert d["misfires"] == [[5, 3]] and len(d["cycles"]) == 12
    assert [c["cycle"] for c in d["cycles"]] == list(range(1, 13))
    assert d["cycles"][4]["misfire"] == [False, False, True, False]
    assert d["r2"] > 0.99


def test_python_round_trip_counts_from_one(tmp_path):
    engine = rotor.load_engine("4chn15")
    load = rotor.ConstantLoad(float(rotor.steady_state(engine).load_torque_Nm))
    pattern = rotor.combustion_pattern(6, 4, misfires=[(3, 2)])
    assert pattern[2, 1] == 0.0 and pattern.sum() == 23.0
    run = rotor.simulate(engine, cycles=6, load=load, combustion=pattern, progress=False)
    log, truth = record_run(tmp_path / "run.csv", run, wheel="36-1")
    assert truth.name == "run.truth.json" and json.loads(truth.read_text())["misfires"] == [[3, 2]]
    assert stated_phase(log) == (pytest.approx(29.4), 0)
    d = rotor.diagnose(engine, log, wheel="36-1")
    assert d.misfires() == [(3, 2)]
    assert d.to_pandas().query("misfire")[["cycle", "cylinder"]].values.tolist() == [[3, 2]]
    # both spreads, each named: the estimate's noise and the cycle-to-cycle spread
    text = d.summary()
    assert "±1σ estimate" in text and "cycle-to-cycle σ" in text
    spread = d.to_json_dict()  # the diagnosis's JSON is per cycle; the identification's carries the spread
    assert "cycles" in spread
    assert np.all(np.isfinite(d.imep_cycle_std_pa)) and d.imep_cycle_std_pa.shape == (4,)
    # one Axes, one panel (kind=); the three together still
    import matplotlib

    matplotlib.use("Agg")
    ax = d.plot(kind="imep")
    assert "misfire" in ax.get_title() and ax.get_xlabel().startswith("cycle (from 1")
    marked = [line for line in ax.get_lines() if line.get_label() == "misfire"]
    assert marked and list(marked[0].get_xdata()) == [3]  # cycle 3
    assert len(d.plot()) == 3
    with pytest.raises(ValueError, match="kind"):
        d.plot(kind="everything")


def test_record_refuses_what_it_cannot_write(tmp_path, capsys):
    code, _, err = run_cli(
        capsys, "simulate", "4chn15", "--cycles", "3", "--record", str(tmp_path / "x.csv"), "--wheel", "60-0"
    )
    assert code == 2 and err.startswith("rotor") and err.count("\n") == 1
    assert stated_phase(tmp_path / "missing.csv") is None
    for argv, needle in (
        (["--record", str(tmp_path / "no" / "x.csv")], "no folder"),  # refused before the run
        (["--record", str(tmp_path / "x.csv"), "--cycles", "1"], "--cycles 2 or more"),
    ):
        code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "3", *argv)
        assert code == 2 and needle in err and err.count("\n") == 1


@pytest.fixture(scope="module")
def short_run():
    """A 3-cycle run of 4chn15 to record."""
    engine = rotor.load_engine("4chn15")
    return rotor.simulate(engine, cycles=3, load=rotor.ConstantLoad(300.0), progress=False)


@pytest.mark.parametrize("stop", [KeyboardInterrupt, OSError], ids=["Ctrl-C", "a full disk"])
@pytest.mark.parametrize("at", [1, 2], ids=["first rename", "second rename"])
def test_the_log_and_its_truth_are_put_in_place_both_or_neither(tmp_path, monkeypatch, short_run, stop, at):
    import errno
    import os

    log, truth = tmp_path / "rec.csv", tmp_path / "rec.truth.json"
    log.write_text("old log\n")
    truth.write_text("old truth\n")
    real_replace = os.replace
    calls = []

    def stopped(src, dst):
        calls.append(dst)
        if len(calls) == at:
            raise stop() if stop is KeyboardInterrupt else OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), dst)
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", stopped)
    with pytest.raises(stop):
        record_run(log, short_run)
    monkeypatch.undo()
    assert log.read_text() == "old log\n" and truth.read_text() == "old truth\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv", "rec.truth.json"]
    record_run(log, short_run)
    lines = log.read_text().splitlines()
    assert lines[0].startswith("# a run recorded by rotor") and lines[3] == "tooth_time_s"
    assert json.loads(truth.read_text())["log"] == "rec.csv"


def test_a_truth_that_cannot_be_written_leaves_no_log(tmp_path, short_run, capsys):
    import os

    (tmp_path / "rec.truth.json").mkdir()  # a folder where the truth should go
    with pytest.raises(OSError) as info:
        record_run(tmp_path / "rec.csv", short_run)
    assert info.value.filename == str(tmp_path / "rec.truth.json")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.truth.json"]
    pipe = tmp_path / "two.truth.json"
    os.mkfifo(pipe)
    code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--record", tmp_path / "two.csv")
    assert code == 2 and err == f"rotor: error: {pipe}: is a named pipe (FIFO), not a regular file: give a file name\n"
    assert not (tmp_path / "two.csv").exists()


def test_record_never_writes_onto_a_pipe_or_a_link(tmp_path, capsys):
    import os
    import stat

    pipe, link, target = tmp_path / "pipe.csv", tmp_path / "link.csv", tmp_path / "target.csv"
    os.mkfifo(pipe)  # stands in for a device
    target.write_text("the user's\n")
    link.symlink_to(target)
    for path, words in ((pipe, "is a named pipe (FIFO)"), (link, f"is a link to {target}")):
        code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--record", path)
        assert code == 2 and err.startswith(f"rotor: error: {path}: {words}") and err.count("\n") == 1, err
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode) and link.is_symlink() and target.read_text() == "the user's\n"
    code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--record", "-")
    assert code == 2 and err.startswith("rotor: error: --record -: ") and "give a file name" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "pipe.csv", "target.csv"]


@pytest.mark.parametrize("wheel", ["36-2-1", "36-2-2-2", "36-2-1-1"])
def test_a_multi_gap_wheel_is_recorded_with_its_gaps_where_they_lie(tmp_path, capsys, wheel):
    log = tmp_path / "rec.csv"
    code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "6", "--record", str(log), "--wheel", wheel)
    assert code == 0, err
    code, out, err = run_cli(capsys, "analyze", str(log), "--json")  # the wheel found from the log alone
    assert code == 0, err
    assert json.loads(out)["wheel"]["spec"] == wheel


@pytest.mark.parametrize("wheel", ["3-1", "12-10"])
def test_a_wheel_of_few_teeth_recorded_reads_back_when_named_and_is_refused_in_words_when_not(tmp_path, capsys, wheel):
    log = tmp_path / "rec.csv"
    code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "6", "--record", str(log), "--wheel", wheel)
    assert code == 0, err
    code, out, err = run_cli(capsys, "analyze", str(log), "--wheel", wheel, "--json")
    assert code == 0 and json.loads(out)["wheel"]["spec"] == wheel, err
    code, _, err = run_cli(capsys, "analyze", str(log))
    assert code in (0, 2) and "Traceback" not in err and len(err.strip().splitlines()) <= 1


def test_diagnose_of_a_wheel_whose_errors_a_firing_run_cannot_give_names_its_own_option(tmp_path, capsys):
    log = tmp_path / "rec.csv"
    assert run_cli(capsys, "simulate", "4chn15", "--cycles", "6", "--record", str(log), "--wheel", "36-2-2-2")[0] == 0
    code, _, err = run_cli(capsys, "diagnose", str(log), "--engine", "4chn15")
    assert code == 2 and "--calibration FILE" in err and "--tooth-errors" not in err
