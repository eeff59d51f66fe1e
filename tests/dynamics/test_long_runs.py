"""Long transient runs: chunks, bounded memory (``keep_cycles``), size refusals, Ctrl-C.

The long-run memory and time figures are in
``benchmarks/long_run.py``; here the runs are short enough for the test suite.
"""

from __future__ import annotations

import json
import os
import pty
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import ROOT, run_cli
from kernel_traces import kernel_traces

import rotor
from rotor.cli import main as cli_main
from rotor.dynamics.transient import chunk_cycles


@pytest.fixture(scope="module")
def diesel():
    return rotor.load_engine("4chn15")


def _scales(a, out=None):
    """The largest magnitude of each key's numbers anywhere in a JSON dict."""
    out = {} if out is None else out
    items = a.items() if isinstance(a, dict) else enumerate(a) if isinstance(a, list) else []
    for k, v in items:
        if isinstance(v, float):
            out[k] = max(out.get(k, 0.0), abs(v))
        elif isinstance(v, (dict, list)):
            _scales(v, out)
    return out


def _numbers_equal(a, b, path="", scales=None):
    """Every number of two JSON dicts equal to 1e-12 relative, or to 1e-12 of the largest of
    its kind (an order's amplitude near zero); wall time and kept count apart."""
    scales = _scales(a) if scales is None else scales
    bad = []
    if isinstance(a, dict):
        assert set(a) == set(b), path
        for k in a:
            if k in ("wall_s", "kept_cycles"):
                continue
            if isinstance(a[k], float) and isinstance(b[k], float):
                if not np.isclose(a[k], b[k], rtol=1e-12, atol=1e-12 * scales[k]):
                    bad.append((f"{path}.{k}", a[k], b[k]))
            else:
                bad += _numbers_equal(a[k], b[k], f"{path}.{k}", scales)
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (u, v) in enumerate(zip(a, b)):
            bad += _numbers_equal(u, v, f"{path}[{i}]", scales)
    elif a != b:
        bad.append((path, a, b))
    return bad


# ----------------------------------------------------------------------------- the same numbers
@pytest.mark.parametrize(
    "method, cycles, load, keep",
    [
        ("grid", 130, rotor.PropellerLoad(1100.0, 1250.0), 2),  # three chunks, the last padded
        ("closed", 1100, rotor.PropellerLoad(1100.0, 1250.0), 2),
        ("angle", 25, rotor.PropellerLoad(1100.0, 1250.0), 3),
        ("grid", 60, rotor.ConstantLoad(1250.0), 2),  # runs down and stalls: the time domain follows
    ],
)
def test_keeping_the_last_cycles_gives_the_numbers_of_every_sample(diesel, method, cycles, load, keep):
    kw = dict(rpm=1200.0, cycles=cycles, load=load, method=method)
    every = rotor.simulate(diesel, **kw)
    last = rotor.simulate(diesel, **kw, keep_cycles=keep)
    assert every.first_kept_cycle_index == 0 and every.cycle_summary is None
    assert last.first_kept_cycle_index == every.uniform_cycles - keep and last.kept_cycles == keep
    a, b = every.to_json_dict(), last.to_json_dict()
    assert _numbers_equal(a, b) == []
    assert b["kept_cycles"] == keep and a["kept_cycles"] == every.uniform_cycles
    assert "delta_max" in b and "delta_max_cycle" in b
    np.testing.assert_allclose(last.delta_per_cycle, every.delta_per_cycle, rtol=1e-12)
    np.testing.assert_allclose(last.cycle_mean_omega, every.cycle_mean_omega, rtol=1e-12)
    for cycle in (-1, every.uniform_cycles - keep + 1):  # the last, the first kept (counted from 1)
        o1, o2 = every.orders(cycle), last.orders(cycle)
        np.testing.assert_allclose(o2.speed_amplitude_rad_s, o1.speed_amplitude_rad_s, rtol=1e-9, atol=1e-12)
    assert f"the last {keep} cycles of {every.uniform_cycles}" in last.summary()
    if method == "grid" and isinstance(load, rotor.ConstantLoad):
        assert every.stalled and last.stalled and last.method == "grid+time"


def test_start_from_rest_keeps_its_samples_the_same_way(diesel):
    kw = dict(rpm=0.0, cycles=2, load=rotor.ConstantLoad(-2000.0))
    every, last = rotor.simulate(diesel, **kw), rotor.simulate(diesel, **kw, keep_cycles=1)
    assert last.method == "time" and last.first_kept_cycle_index == 1
    assert _numbers_equal(every.to_json_dict(), last.to_json_dict()) == []


# ----------------------------------------------------------------------------- chunks
def test_a_run_of_many_chunks_compiles_its_kernel_once(diesel):
    load = rotor.PropellerLoad(1100.0, 1250.0)
    size = chunk_cycles("grid", 10**6, 1440)
    assert 10 <= size <= 200  # well under a second a chunk (benchmarks/long_run.py)
    counts = []
    for cycles in (3 * size + 7, 2 * size + 1):  # four chunks, the last padded; three
        before = kernel_traces()
        rotor.simulate(diesel, rpm=1200.0, cycles=cycles, load=load, method="grid")
        counts.append(kernel_traces() - before)
    assert counts[0] <= 2  # the kernel (unless an earlier run compiled it) and the samples
    assert counts[1] <= 1  # the same kernel for every run of many chunks; only the samples' shape is new


def test_a_long_run_holds_only_the_kept_samples(diesel):
    load = rotor.PropellerLoad(1100.0, 1250.0)
    res = rotor.simulate(diesel, rpm=1200.0, cycles=2000, load=load, method="closed", keep_cycles=5)
    P = res.points_per_cycle
    assert res.uniform_cycles == 2000 and res.first_kept_cycle_index == 1995
    assert res.omega.shape == (5 * P + 1,) and res.t.shape == (5 * P + 1,)  # and the end sample
    assert res.delta_per_cycle.shape == (2000,) and res.cycle_mean_omega.shape == (2000,)
    assert res.cycle_summary is not None and res.cycle_summary.max_omega.shape == (2000,)
    frame = res.to_pandas()
    assert frame["cycle"].min() == 1996 and frame["cycle"].iloc[-2] == 2000  # counted from 1
    assert res.orders(1997).order.size > 0 and res.orders("mean").order.size > 0  # cycles 1996 … 2000 kept
    with pytest.raises(ValueError, match="only the samples of the last 5 cycles"):
        res.orders(3)
    import matplotlib

    matplotlib.use("Agg")
    assert "the last 5 cycles of 2000" in res.plot(kind="time").get_title()


# ----------------------------------------------------------------------------- sizes and types
def test_sizes_are_refused_before_allocating(diesel, monkeypatch):
    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "1")
    load = rotor.ConstantLoad(1000.0)
    with pytest.raises(rotor.EngineError, match=r"cycles = 1000000 with every sample kept.*keep_cycles="):
        rotor.simulate(diesel, cycles=10**6, load=load)
    with pytest.raises(rotor.EngineError, match=r"cycles = 1000000000000 .*per-cycle"):
        rotor.simulate(diesel, cycles=10**12, load=load, keep_cycles=10)
    with pytest.raises(rotor.EngineError, match=r"steps_per_cycle = 720000000 .*fewer steps"):
        rotor.simulate(diesel, cycles=2, load=load, method="grid", steps_per_cycle=720_000_000)
    with pytest.raises(rotor.EngineError, match=r"grid_deg = 1e-07"):
        rotor.simulate(diesel, cycles=2, load=load, grid_deg=1e-7, step_deg=1e-7)


def test_cycles_takes_a_whole_number(diesel):
    load = rotor.ConstantLoad(1000.0)
    assert rotor.simulate(diesel, cycles=np.int64(3), load=load).uniform_cycles == 3
    for bad in (3.0, True, "3"):
        with pytest.raises(TypeError, match=r"cycles = .*whole number"):
            rotor.simulate(diesel, cycles=bad, load=load)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"keep_cycles = "):
        rotor.simulate(diesel, cycles=3, load=load, keep_cycles=2.5)  # type: ignore[arg-type]
    with pytest.raises(rotor.EngineError, match=r"keep_cycles = 0"):
        rotor.simulate(diesel, cycles=3, load=load, keep_cycles=0)


def test_cli_keeps_the_last_cycles_and_refuses_in_one_line(capsys, monkeypatch):
    cli_main(["simulate", "4chn15", "--cycles", "120", "--keep-cycles", "3", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert out["cycles"] == 120 and out["kept_cycles"] == 3 and out["delta_max_cycle"] >= 1
    monkeypatch.setenv("ROTOR_MEMORY_LIMIT_GB", "1")
    for argv in (["--cycles", "1000000000000"], ["--steps-per-cycle", "720000000", "--method", "grid"]):
        code, _, err = run_cli(capsys, "simulate", "4chn15", *argv)
        assert code == 2
        err = err.strip()
        assert len(err.splitlines()) == 1 and "GB" in err and "Traceback" not in err


# ----------------------------------------------------------------------------- Ctrl-C
def _read_until(fd: int, marker: bytes, timeout_s: float) -> bytes:
    """What the pseudo-terminal ``fd`` shows until ``marker`` appears (or ``timeout_s``
    passes, or the other side closes)."""
    seen, end = b"", time.monotonic() + timeout_s
    while marker not in seen and time.monotonic() < end:
        ready, _, _ = select.select([fd], [], [], 0.2)
        if ready:
            try:
                chunk = os.read(fd, 4096)
            except OSError:  # the child closed its terminal
                break
            if not chunk:
                break
            seen += chunk
    return seen


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process and a pseudo-terminal")
def test_ctrl_c_stops_a_long_run_within_two_seconds():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    argv = [sys.executable, "-m", "rotor.cli", "simulate", "4chn15", "--method", "grid", "--cycles", "20000"]
    # stderr on a pseudo-terminal, so that the run draws its progress bar: the bar appears
    # once the run is in its chunks (imports, the balancing load's steady state and the
    # compiling are over; Ctrl-C in the middle of XLA compiling is heard only when it
    # returns), however long that took on a loaded machine. The time counts from the signal.
    leader, follower = pty.openpty()
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=follower, env=env, cwd=ROOT)
    os.close(follower)
    try:
        shown = _read_until(leader, b"simulating [", timeout_s=240.0)
        assert proc.poll() is None and b"simulating [" in shown, shown.decode(errors="replace")
        sent = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=10)
        took = time.perf_counter() - sent
        text = (shown + _read_until(leader, b"\x00", timeout_s=1.0)).decode(errors="replace")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(leader)
    assert "Traceback" not in text, text
    assert proc.returncode == 130, text
    assert "interrupted" in text, text
    assert took < 2.0, f"exited {took:.2f} s after Ctrl-C"
