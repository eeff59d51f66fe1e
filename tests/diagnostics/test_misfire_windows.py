"""Misfire rates over windows of revolutions and their OBD codes (:mod:`rotor.diagnostics.misfire_rate`),
through the monitor and ``rotor monitor``: a random misfire rate on one cylinder flags its
code, spread over all P0300; a recording shorter than a window is judged over what it has;
the verdicts say the rules that decide them."""

import json

import pytest
from conftest import run_cli

from rotor import cli
from rotor.cli.run import random_misfires
from rotor.diagnostics.misfire_rate import (
    CatalystTable,
    MisfireThresholds,
    WindowCounter,
    WindowKind,
    misfire_code,
)
from rotor.diagnostics.monitor import MisfireMonitor, ToothLines
from rotor.errors import EngineError


def lines_of(out):
    rows = [json.loads(line) for line in out.splitlines() if line.strip()]
    assert "summary" in rows[-1]
    windows = [r["window"] for r in rows if "window" in r]
    verdicts = [r for r in rows[:-1] if "window" not in r]
    return verdicts, windows, rows[-1]["summary"]


# ---------------------------------------------------------------------- the code rule
def test_one_cylinder_gives_its_code_two_or_more_give_p0300():
    assert misfire_code([0, 0, 12, 0]) == ("P0303", (3,))
    assert misfire_code([1, 0, 30, 0]) == ("P0303", (3,))  # 1 of 31 is under a tenth: not misfiring
    assert misfire_code([4, 0, 30, 0]) == ("P0300", (1, 3))  # 4 of 34 is more
    assert misfire_code([3, 3, 3, 3]) == ("P0300", (1, 2, 3, 4))
    assert misfire_code([0] * 12 + [5]) == ("P0300", (13,))  # no code of its own past cylinder 12
    assert misfire_code([0] * 11 + [5]) == ("P0312", (12,))
    assert misfire_code([0, 0, 0, 0]) == (None, ())
    assert misfire_code([1, 0, 30, 0], min_share=0.02) == ("P0300", (1, 3))


def test_the_catalyst_table_is_read_between_its_nodes_and_held_beyond():
    table = CatalystTable(rpm=(1000.0, 3000.0), load=(0.0, 1.0), rate_pct=((20.0, 10.0), (10.0, 4.0)))
    assert table.rate_at(2000.0, 0.5) == pytest.approx(0.5 * (15.0 + 7.0))
    assert table.rate_at(500.0, 2.0) == 10.0 and table.rate_at(9000.0, -1.0) == 10.0
    assert table.rate_at(3000.0, None) == 4.0  # the load not known: the lowest rate at that speed
    for bad in (
        {"rpm": (1000.0,), "load": (0.0, 1.0), "rate_pct": ((20.0,),)},
        {"rpm": (3000.0, 1000.0), "load": (0.0,), "rate_pct": ((20.0,), (10.0,))},
        {"rpm": (1000.0,), "load": (0.0,), "rate_pct": ((0.0,),)},
    ):
        with pytest.raises(EngineError, match="catalyst table"):
            CatalystTable(**bad)
    with pytest.raises(EngineError, match="whole number of revolutions"):
        MisfireThresholds(emission_revolutions=0)


def test_windows_count_the_last_revolutions_and_a_short_stream_is_judged_over_what_it_has():
    th = MisfireThresholds(catalyst_revolutions=10, emission_revolutions=50, step_revolutions=10, emission_pct=4.0)
    wc = WindowCounter(4, 4, th)  # two firings a revolution: windows of 20 and 100 firings
    got = []
    order = (1, 3, 4, 2)
    for i in range(60):  # 30 revolutions: cylinder 3 misfires at every fourth of its firings
        k, c = 1 + i // 4, order[i % 4]
        got += wc.add(k, c, c == 3 and k % 4 == 0, 0.1 * k, float("nan"))
    got += wc.close()
    cat = [w for w in got if w.kind is WindowKind.CATALYST]
    emi = [w for w in got if w.kind is WindowKind.EMISSION]
    assert [w.firings for w in cat] == [20, 20, 20] and not any(w.partial for w in cat)
    assert [w.first for w in cat] == [(1, 1), (6, 1), (11, 1)]
    assert sum(w.misfires for w in cat) == 3 and cat[0].per_cylinder == (0, 0, 1, 0)
    assert cat[0].rate_pct == 5.0 and cat[0].mean_rpm == pytest.approx(60 * 2 * 4 / 0.4)
    # the emission window never filled: judged once over the 30 revolutions there are
    (e,) = emi
    assert e.partial and e.revolutions == 30 and e.window_revolutions == 50 and "shorter than the window" in e.line()
    assert e.rate_pct == pytest.approx(100 * 3 / 60) and e.exceeded and e.code == "P0303"


def test_random_misfires_fall_at_the_rate_on_the_cylinder_named_and_are_drawn_again_alike():
    one = random_misfires(5000, 4, 2.0, cylinder=3, seed=4)
    assert {c for _, c in one} == {3} and len(one) / (5000 * 4) == pytest.approx(0.02, rel=0.1)
    assert one == random_misfires(5000, 4, 2.0, cylinder=3, seed=4) != random_misfires(5000, 4, 2.0, 3, seed=5)
    spread = random_misfires(5000, 4, 2.0, seed=4)
    assert {c for _, c in spread} == {1, 2, 3, 4} and len(spread) / 20000 == pytest.approx(0.02, rel=0.1)
    with pytest.raises(EngineError, match="at most 25 %"):
        random_misfires(10, 4, 30.0, cylinder=1)


# ---------------------------------------------------------------------- the command line
WINDOWS = ("--catalyst-revolutions", "100", "--emission-revolutions", "200", "--window-step", "100")


@pytest.fixture(scope="module")
def rate_runs(tmp_path_factory):
    """Two recorded runs of 200 cycles (400 revolutions) with 3 % random misfires: on cylinder 3
    alone and spread over the four (the command of the docs, 600 cycles and 1000-revolution
    windows, on a third of the revolutions with windows a fifth as long)."""
    folder = tmp_path_factory.mktemp("rates")
    out = {}
    for name, extra in (("one", ["--misfire-cylinder", "3"]), ("spread", [])):
        log = folder / f"{name}.csv"
        argv = ["simulate", "4chn15", "--cycles", "200", "--misfire-rate", "3", *extra, "--record", str(log)]
        assert cli.main([*argv, "--wheel", "60-2", "--quiet"]) == 0
        out[name] = (log, json.loads(log.with_name(f"{name}.truth.json").read_text()))
    return out


@pytest.mark.parametrize(("name", "code"), [("one", "P0303"), ("spread", "P0300")])
def test_a_random_misfire_rate_flags_the_emission_windows_with_its_code(rate_runs, capsys, name, code):
    log, truth = rate_runs[name]
    rc, out, err = run_cli(capsys, "monitor", str(log), "--engine", "4chn15", "--wheel", "60-2", "--json", *WINDOWS)
    assert rc == 0, err
    verdicts, windows, summary = lines_of(out)
    planted = {tuple(p) for p in truth["misfires"]}
    assert len(planted) >= 0.02 * 800
    flagged = {(v["cycle"], v["cylinder"]) for v in verdicts if v["misfire"]}
    # the misfires found, but for one whose copy is the recording's lead-in (its own baseline)
    assert len(flagged ^ planted) <= 1 and max(v["cycle"] for v in verdicts) == 200
    emission = [w for w in windows if w["kind"] == "emission"]
    assert len(emission) == 3 and all(w["window_revolutions"] == 200 and not w["partial"] for w in emission)
    assert all(w["exceeded"] and w["code"] == code and w["rate_pct"] > 1.0 for w in emission)
    # the catalyst windows (a table's rate of 10 % and more) are not exceeded: no other code anywhere
    assert {w["code"] for w in windows if w["code"]} == {code}
    assert all(not w["exceeded"] for w in windows if w["kind"] == "catalyst")
    assert summary["windows"]["windows_exceeded_count"] == {"catalyst": 0, "emission": 3}
    assert {w["code"] for w in summary["windows"]["windows_exceeded"]} == {code}


def test_the_thresholds_are_options_and_bad_ones_are_refused(rate_runs, capsys, tmp_path):
    log, _ = rate_runs["one"]
    table = tmp_path / "cat.json"
    table.write_text(json.dumps({"rpm": [1000, 3000], "load": [0, 1], "rate_pct": [[2, 2], [2, 2]]}))
    argv = ["monitor", str(log), "--engine", "4chn15", "--wheel", "60-2", "--json", *WINDOWS]
    rc, out, err = run_cli(capsys, *argv, "--catalyst-table", str(table), "--emission-rate", "50")
    assert rc == 0, err
    _, windows, _ = lines_of(out)
    assert all(w["threshold_pct"] == 2.0 and w["exceeded"] for w in windows if w["kind"] == "catalyst")
    assert not any(w["exceeded"] for w in windows if w["kind"] == "emission")
    for bad in (
        {"rpm": [1000], "load": [0, 1], "rate_pct": [[2]]},
        {"rpm": ["fast"], "load": [0], "rate_pct": [[2]]},
        {"rpm": [1000], "load": [0], "rate_pct": [[None]]},
        [1, 2],
    ):
        table.write_text(json.dumps(bad))
        rc, out, err = run_cli(capsys, *argv, "--catalyst-table", str(table))
        assert rc == 2 and out == "" and "catalyst table" in err and str(table) in err and len(err.splitlines()) == 1


def test_a_recording_shorter_than_the_windows_is_judged_over_what_it_has(tmp_path, capsys):
    log = tmp_path / "rec.csv"
    argv = ["simulate", "4chn15", "--cycles", "40", "--misfire", "7:2,19:4,20:4", "--record", str(log)]
    assert cli.main([*argv, "--wheel", "60-2", "--quiet"]) == 0
    capsys.readouterr()
    rc, out, _ = run_cli(capsys, "monitor", str(log), "--engine", "4chn15", "--wheel", "60-2", "--json")
    verdicts, windows, summary = lines_of(out)
    assert rc == 0 and len(windows) == 2 and all(w["partial"] and w["revolutions"] == 80 for w in windows)
    assert all(w["misfires"] == 3 and w["firings"] == 160 for w in windows)
    # the run's 40 cycles judged, and no firing after them (the log's lead-out)
    assert max(v["cycle"] for v in verdicts) == 40 and len(verdicts) == 160
    assert summary["last_cycle"] == 40 and summary["after_last_cycle"] == 1
    rc, text, _ = run_cli(capsys, "monitor", str(log), "--engine", "4chn15", "--wheel", "60-2")
    assert "80 of 200 revolutions: the recording is shorter than the window, judged over what it has" in text
    assert "1 firing(s) after the log's last cycle (40) not judged" in text
    # each note kind on a line of its own, in words
    assert "\n    found (the wheel's gap found: edges placed from there) ×1; the last: the 60-2 wheel found" in text
    assert "unless a neighbouring firing's index is more than twice as low" in text


def test_a_loss_below_the_threshold_not_called_says_which_neighbour_claims_it(tmp_path):
    """Cylinder 1's TDC taken 120° late: a misfire's loss falls partly into the segment of the
    firing after it; that firing's index is below −8 but not called, and the verdict says why."""
    log = tmp_path / "rec.csv"
    argv = ["simulate", "4chn15", "--cycles", "40", "--misfire", "7:2,19:4,20:4", "--record", str(log)]
    assert cli.main([*argv, "--wheel", "60-2", "--quiet"]) == 0
    t, _ = ToothLines().feed(log.read_text(), final=True)
    m = MisfireMonitor("60-2", tdc_deg=149.4, cylinders=4, firing_order=[1, 3, 4, 2], last_cycle=40)
    out = m.feed(t) + m.close()
    below = [(i, v) for i, v in enumerate(out) if v.index < -m.threshold]
    claimed = [(i, v) for i, v in below if not v.misfire]
    assert claimed and all(v.misfire == (v.claimed_by is None) for _, v in below)
    for i, v in claimed:
        neighbour = out[i - 1] if v.claimed_by == "previous" else out[i + 1]
        assert v.neighbour_index == neighbour.index < 2 * v.index and neighbour.misfire
        assert f"the {v.claimed_by} firing lost more than twice as much" in v.line()
        assert v.to_json_dict()["claimed_by_neighbour"] == v.claimed_by
    assert all(v.claimed_by is None and "twice" not in v.line() for v in out if v.index >= -m.threshold)
