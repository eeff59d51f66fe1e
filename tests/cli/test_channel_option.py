"""`--channel` is `--columns` by another name: `rotor analyze FILE.mf4 --channel crank=CRANK`
reads an MDF file's channel by its name."""

from __future__ import annotations

import pytest
from conftest import run_cli


def test_an_mdf_channel_named_with_channel_reads_as_with_columns(tmp_path, capsys):
    asammdf = pytest.importorskip("asammdf")
    from rotor.logs.synthetic import bench_capture

    log = bench_capture(rpm=1500, revolutions=30)
    mdf = asammdf.MDF()
    mdf.append([asammdf.Signal(log["encoder_v"], log["time"], name="CRANK", unit="V")])
    path = tmp_path / "run.mf4"
    mdf.save(path)
    rc, by_channel, err = run_cli(capsys, "analyze", str(path), "--channel", "crank=CRANK", "--json")
    assert rc == 0, err
    rc, by_columns, _ = run_cli(capsys, "analyze", str(path), "--columns", "crank=CRANK", "--json")
    assert rc == 0 and by_channel == by_columns and '"60-2"' in by_channel
