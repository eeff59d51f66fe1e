"""What `rotor table` and `rotor demo` print: a table's zeros written as zeros, the cylinders
whose tables are the same named with the reason, and a demo's load step inside its run."""

from __future__ import annotations

import csv
import io

import pytest
from conftest import run_cli

from rotor.cli.demo import DEMO_CYCLES, STEP_CYCLE, load_step_line, load_step_time_s
from rotor.cli.output import csv_text
from rotor.fileio import zeros_as_zero


def test_round_off_of_a_zero_is_written_as_zero():
    rows = [[0.0, 5.7e-18, 1e-20], [10.0, 0.205, 2e-20], [20.0, -8.3e-15, -1e-20]]
    cleaned = zeros_as_zero(rows)
    assert [r[1] for r in cleaned] == [0.0, 0.205, 0.0]  # round-off against the column's 0.205
    assert [r[2] for r in cleaned] == [1e-20, 2e-20, -1e-20]  # a column of small numbers is kept
    assert zeros_as_zero([]) == []
    text = csv_text(["a", "b", "c"], rows)
    assert text.splitlines()[1] == "0,0,1e-20"


def test_the_crank_table_as_csv_writes_its_zeros_as_zeros(capsys):
    rc, out, _ = run_cli(capsys, "table", "4chn15", "--step", "90", "--format", "csv")
    assert rc == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    tdc = rows[0]
    assert tdc["angle_deg"] == "0"
    for column in ("s_m", "v_m_s", "n_N", "t_N", "m_Nm"):  # zero at TDC by the kinematics
        assert tdc[column] == "0", (column, tdc[column])
    assert "e-1" not in out


def test_cylinders_with_the_same_table_are_named_with_the_reason(capsys):
    tables = {}
    for cylinder in (1, 2, 5):
        rc, out, _ = run_cli(capsys, "table", "v8", "--cylinder", cylinder, "--step", "90")
        assert rc == 0
        body, note = out.rstrip("\n").rsplit("\n", 1)
        tables[cylinder] = body.split("\n", 1)[1]  # the table without its title line
        assert note.startswith("note: every cylinder (1–8) has this table")
        assert "crank-throw kinematics" in note and "phase on the crankshaft" in note
    assert tables[1] == tables[2] == tables[5]


def test_a_single_cylinder_table_has_no_note(capsys):
    rc, out, _ = run_cli(capsys, "table", "tue-single", "--step", "90")
    assert rc == 0 and "note:" not in out


@pytest.mark.parametrize(("rpm", "strokes"), [(1250.0, 4), (12000.0, 4), (300.0, 2), (20000.0, 2)])
def test_the_demo_steps_its_load_inside_its_run(rpm, strokes):
    cycle_s = strokes / 2 * 60.0 / rpm
    step_s = load_step_time_s(rpm, strokes)
    assert step_s == pytest.approx((STEP_CYCLE - 1) * cycle_s, rel=5e-3)
    assert 0 < step_s < 0.5 * DEMO_CYCLES * cycle_s
    line = load_step_line(1000.0, step_s, DEMO_CYCLES * cycle_s)
    assert f"at t = {step_s:g} s" in line and f"cycle {STEP_CYCLE}" in line
