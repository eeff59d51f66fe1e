"""``rotor monitor`` as careful with its input as ``rotor analyze``: time units and time bases,
an engine or wheel that does not fit the log, verdict times, the line reader's time and
memory whatever the line ends, a followed file truncated or replaced, bounded warnings, a
run that judges nothing, Ctrl-C."""

import gc
import json
import os
import signal
import subprocess
import sys
import time
import tracemalloc

import numpy as np
import pytest
from conftest import run_cli

import rotor
from rotor import cli
from rotor.diagnostics.monitor import (
    MIN_TEETH_PER_SEGMENT,
    MisfireMonitor,
    ToothLines,
    check_wheel,
)
from rotor.errors import LogError

MISFIRES = {(7, 2), (19, 4), (20, 4)}
ENGINE = ["--engine", "4chn15", "--wheel", "60-2"]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """``rotor simulate 4chn15 --cycles 40 --misfire 7:2,19:4,20:4 --record rec.csv --wheel 60-2``."""
    folder = tmp_path_factory.mktemp("monitor_input")
    log = folder / "rec.csv"
    code = cli.main(
        ["simulate", "4chn15", "--cycles", "40", "--misfire", "7:2,19:4,20:4", "--record", str(log), "--wheel", "60-2"]
    )
    assert code == 0
    return log


def rewrite(log, path, time_text=None, header=None):
    """The log ``log`` written to ``path`` with each time as ``time_text(t)`` and its column-name
    line as ``header`` (kept where None)."""
    out = []
    for line in log.read_text().splitlines():
        if line.startswith("#"):
            out.append(line)
        elif line[:1].isdigit():
            out.append(time_text(float(line)) if time_text else line)
        else:
            out.append(header if header is not None else line)
    path.write_text("\n".join(out) + "\n")
    return path


def verdicts(out):
    """The verdict lines and the summary of ``rotor monitor --json`` (the window lines apart)."""
    rows = [json.loads(line) for line in out.splitlines() if line.strip()]
    assert "summary" in rows[-1]
    return [r for r in rows[:-1] if "window" not in r], rows[-1]["summary"]


def one_error_line(err):
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("rotor: error: ") and "Traceback" not in err, err
    return lines[0]


def times_of(log):
    return ToothLines().feed(log.read_text(), final=True)[0]


# ---------------------------------------------------------------------- time units, time base
def test_monitor_reads_millisecond_times_its_header_names(recorded, tmp_path, capsys):
    """A ``tooth_time_ms`` header: the times read in milliseconds, the same verdicts and IMEP
    as in seconds (read as seconds, every firing's IMEP was -12 bar)."""
    code, out, _ = run_cli(capsys, "monitor", recorded, *ENGINE, "--json")
    seconds = verdicts(out)[0]
    for header, factor in (("tooth_time_ms", 1e3), ("tooth_time_us", 1e6)):
        path = rewrite(recorded, tmp_path / f"{header}.csv", lambda t, f=factor: f"{t * f:.7f}", header)
        # the run's last cycle, which the recording's truth file gives, given
        code, out, err = run_cli(capsys, "monitor", path, *ENGINE, "--json", "--last-cycle", "40")
        assert code == 0 and f"column {header!r} read as tooth times in seconds" in err
        rows, _ = verdicts(out)
        assert {(r["cycle"], r["cylinder"]) for r in rows if r["misfire"]} == MISFIRES
        fired = [r["imep_bar"] for r in rows if not r["misfire"]]
        assert min(fired) > 9.5 and len(rows) == len(seconds)
        assert np.allclose([r["imep_bar"] for r in rows], [r["imep_bar"] for r in seconds], atol=0.01)


def test_monitor_refuses_millisecond_times_it_cannot_tell(recorded, tmp_path, capsys):
    """Plain values in milliseconds (a 'tooth_time_s' header or none): refused as ``rotor
    analyze`` refuses them, the unit and the way out named."""
    path = rewrite(recorded, tmp_path / "ms.csv", lambda t: f"{t * 1e3:.7f}")
    code, out, err = run_cli(capsys, "monitor", path, *ENGINE)
    line = one_error_line(err)
    assert code == 2 and out == ""
    assert "imply 1.25 rpm" in line and "milliseconds (1250 rpm if so)" in line and "'tooth_time_ms'" in line


def test_monitor_refuses_times_too_far_from_zero_to_resolve_the_teeth(recorded, tmp_path, capsys):
    """Times offset by 1e12 s (a float64 holds only 1.2e-4 s there, 14 % of the tooth period):
    refused (they gave 12 false misfires and missed the 3 real ones, without a word); offset
    by 1e9 s they resolve 2.4e-7 s and give the verdicts of the times from 0."""
    far = rewrite(recorded, tmp_path / "far.csv", lambda t: repr(t + 1e12))
    code, out, err = run_cli(capsys, "monitor", far, *ENGINE)
    line = one_error_line(err)
    assert code == 2 and out == ""
    assert "resolve 0.000122 s" in line and "far from 0" in line and "offsets from the start" in line
    near = rewrite(recorded, tmp_path / "near.csv", lambda t: repr(t + 1e9))
    code, out, err = run_cli(capsys, "monitor", near, *ENGINE, "--json")
    assert code == 0 and "warning" not in err
    rows, _ = verdicts(out)
    assert {(r["cycle"], r["cylinder"]) for r in rows if r["misfire"]} == MISFIRES


def test_monitor_reads_a_recording_of_several_columns_as_analyze_does(tmp_path, capsys):
    """A sampled signal or a logic analyser's columns is read through the stages `rotor analyze`
    uses (channels, edges, wheel), not line by line as tooth times (each row's time was read as
    an edge, and a warning printed every 119 rows): a recording too short for its wheel is
    refused in that reading's one line, a capture is judged."""
    t = np.arange(0, 0.05, 1e-5)
    analog = tmp_path / "analog.txt"
    np.savetxt(analog, np.column_stack([t, np.sin(t * 6000), np.cos(t * 100)]), delimiter="\t", fmt="%.6e")
    code, out, err = run_cli(capsys, "monitor", analog, "--cylinders", "1", "--wheel", "60-2", "--tdc-deg", "0")
    line = one_error_line(err)
    assert code == 2 and out == "" and "60-2" in line and "Traceback" not in err
    rec = tmp_path / "rec.csv"
    assert run_cli(capsys, "simulate", "4chn15", "--cycles", "12", "--record", rec, "--wheel", "60-2")[0] == 0
    times = rotor.read_log(rec)["tooth_time_s"]
    level = np.ones(2 * times.size)
    level[1::2] = 0
    rows = np.column_stack([np.sort(np.r_[times, times + 2e-4]), level])
    capture = tmp_path / "capture.csv"
    capture.write_text("Time[s], Channel 0\n" + "".join(f"{a:.7f}, {int(b)}\n" for a, b in rows))
    code, out, err = run_cli(capsys, "monitor", capture, "--engine", "4chn15", "--tdc-deg", "29.4")
    assert code == 0 and "firings judged" in out and "wheel 60-2" in err, err


# ---------------------------------------------------------------------- engine and wheel
def test_monitor_refuses_an_engine_that_does_not_fit_the_log(recorded, capsys):
    """The 4chn15's run read with the v8 preset (-5.9 bar for every firing, 6 misfires at wrong
    cylinders, without a word) or the mwm6 preset: refused before any verdict, in one line."""
    for preset in ("v8", "mwm6"):
        code, out, err = run_cli(capsys, "monitor", recorded, "--engine", preset, "--wheel", "60-2")
        line = one_error_line(err.replace("rotor: note: the 60-2 wheel found: edges placed from 0.000000 s\n", ""))
        assert code == 2 and out == ""
        assert "the engine does not fit the log" in line and "bar" in line and "cylinders and firing order" in line
    m = MisfireMonitor("60-2", tdc_deg=29.4, engine="v8", check_fit=False)  # unchecked: its IMEPs as they come
    out = m.feed(times_of(recorded)) + m.close()
    assert max(v.imep_pa for v in out) < 0


@pytest.fixture(scope="module")
def dead_cylinder(tmp_path_factory):
    """A 4chn15 run whose cylinder 2 never fires."""
    log = tmp_path_factory.mktemp("monitor_dead") / "dead.csv"
    misfires = ",".join(f"{k}:2" for k in range(1, 13))
    argv = ["simulate", "4chn15", "--cycles", "12", "--load", "constant:600", "--misfire", misfires]
    assert cli.main([*argv, "--record", str(log), "--wheel", "60-2"]) == 0
    return log


def test_an_engine_with_a_dead_cylinder_still_fits(dead_cylinder):
    """A cylinder that never fires is what the monitor is for: its engine is not refused, nor
    its verdicts flagged (its missing firing adds every order of the speed, weakly against
    the others' firings)."""
    t = times_of(dead_cylinder)
    for kw in ({"engine": "4chn15"}, {"cylinders": 4, "firing_order": [1, 3, 4, 2]}):
        m = MisfireMonitor("60-2", tdc_deg=29.4, **kw)
        out = m.feed(t) + m.close()
        assert len(out) >= 4 * 11 and not any(v.engine_doubt for v in out) and not m.result().engine_doubt


def test_a_cylinder_count_the_speed_does_not_show_flags_every_verdict(recorded, capsys):
    """The 4chn15's run monitored as a six-cylinder engine: its speed's strongest order (2, of
    the acceleration: 4) is no multiple of a six's firing frequency (3 a revolution): one
    warning, and the verdicts from the third whole cycle on flagged; as a four-cylinder, none."""
    code, out, err = run_cli(capsys, "monitor", recorded, "--cylinders", "6", "--wheel", "60-2", "--json")
    assert code == 0 and err.count("engine_fit") == 0 and err.count("strongest order is 4 a revolution") == 1
    rows, summary = verdicts(out)
    flagged = [r["engine_doubt"] for r in rows]
    assert summary["engine_doubt"] and sum(flagged) > 0.9 * len(rows)
    assert flagged == sorted(flagged)  # from the check on
    code, text, _ = run_cli(capsys, "monitor", recorded, "--cylinders", "6", "--wheel", "60-2")
    assert "engine doubtful" in text and "the engine may not fit the log" in text
    code, out, err = run_cli(capsys, "monitor", recorded, "--cylinders", "4", "--firing-order", "1,3,4,2", *ENGINE[2:])
    assert code == 0 and "strongest order" not in err and "doubtful" not in out


@pytest.mark.parametrize("wheel", ["12-10", "3-1", "4-1"])
def test_a_wheel_with_too_few_teeth_per_firing_is_refused(wheel, tmp_path, capsys):
    """A 12-10 wheel (one tooth per firing of a four-cylinder engine) missed the planted
    misfire, a 3-1 one called a false one: refused before a line is read, naming the teeth
    the monitor needs."""
    empty = tmp_path / "later.csv"
    empty.write_text("")
    code, out, err = run_cli(capsys, "monitor", empty, "--engine", "4chn15", "--wheel", wheel, "--tdc-deg", "0")
    line = one_error_line(err)
    assert code == 2 and f"at least {MIN_TEETH_PER_SEGMENT} teeth per firing" in line and f"wheel {wheel}" in line
    with pytest.raises(LogError, match="teeth per firing"):
        MisfireMonitor(wheel, tdc_deg=0.0, cylinders=4)
    assert check_wheel("60-2", engine="v8") == pytest.approx(14.5)
    assert check_wheel("36-1", cylinders=8) == pytest.approx(8.75)


# ---------------------------------------------------------------------- verdict times
def test_a_verdict_is_decided_no_earlier_than_it_is_given(recorded):
    """Fed an edge at a time, every verdict comes back with the edge that decided it: its
    ``decided_at_s`` is that edge's time (the first verdicts, which wait for every cylinder's
    baseline, carried the earlier time of their own last edge)."""
    t = times_of(recorded)
    m = MisfireMonitor("60-2", tdc_deg=29.4, engine="4chn15")
    given = []
    for x in t:
        given += [(v.decided_at_s, float(x)) for v in m.feed([x])]
    assert len(given) >= 150 and all(decided == edge for decided, edge in given)
    tail = m.close()
    assert all(v.decided_at_s <= t[-1] and v.decided_at_s >= given[-1][1] for v in tail)


# ---------------------------------------------------------------------- the line reader
def _feed_cost(text, chunk, **kw):
    """(seconds, peak bytes allocated) of reading ``text`` in chunks of ``chunk`` characters."""
    best = np.inf
    for _ in range(5):
        lines = ToothLines(**kw)
        t0 = time.perf_counter()
        for i in range(0, len(text), chunk):
            lines.feed(text[i : i + chunk])
        lines.feed("", final=True)
        best = min(best, time.perf_counter() - t0)
    gc.collect()
    tracemalloc.start()
    lines = ToothLines(**kw)
    got = [lines.feed(text[i : i + chunk])[0] for i in range(0, len(text), chunk)]
    got.append(lines.feed("", final=True)[0])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return best, peak, np.concatenate(got)


@pytest.mark.timeout(120)
def test_the_line_reader_takes_linear_time_and_memory_without_line_ends():
    """Text without a line end, 100 kB, 400 kB and 1.6 MB in 1 kB pieces: time and memory grow
    with the text, not with its square (40 MB of zeros took 22 s and 390 MB)."""
    costs = [_feed_cost("0" * (100_000 * k), 1000, max_line=4_000_000) for k in (1, 4, 16)]
    for (t1, m1, _), (tk, mk, _), k in zip(costs[:1] * 2, costs[1:], (4, 16), strict=True):
        # memory within 1.5× linear; time below half the square (quadratic work gives k², and a
        # busy machine's timing noise on the small input stays well inside this)
        assert tk / t1 < k * k / 2 and mk / m1 < 1.5 * k
    assert costs[2][2].tolist() == [0.0]


@pytest.mark.timeout(120)
def test_the_line_reader_takes_cr_only_lines_as_lines_in_linear_time_and_bounded_memory():
    """Lines ended by CR alone (a CR-only log of 3e6 rows took 22 s, then 'no tooth time'),
    by LF and by CRLF: the same times, in time linear in the rows and memory bounded by the
    chunk."""
    rows = np.round(np.cumsum(np.full(200_000, 8e-4)), 7)
    body = "\n".join(f"{x:.7f}" for x in rows) + "\n"
    for end in ("\r", "\n", "\r\n"):
        costs = []
        for k in (1, 4, 16):
            n = len(body) * k // 16
            text = body[: body.rindex("\n", 0, n) + 1].replace("\n", end)
            costs.append(_feed_cost(text, 65536))
        t_small, m_small, times_small = costs[0]
        t_large, m_large, times_large = costs[2]
        assert times_large.size == rows.size and np.array_equal(times_large, rows)
        assert t_large / t_small < 16 * 16 / 2 and m_large / m_small < 24  # time: below half of quadratic
        assert m_large < 16 * 65536 * 8


def test_a_crlf_split_between_chunks_is_one_line_end():
    lines = ToothLines()
    got = [lines.feed(part)[0] for part in ("0.1\r", "\n0.2\r", "\n", "0.3")]
    got.append(lines.feed("", final=True)[0])
    assert np.concatenate(got).tolist() == [0.1, 0.2, 0.3] and lines.line_no == 3


def test_a_line_too_long_or_a_nul_byte_is_refused_naming_the_line(tmp_path, capsys):
    """2 MB without a line end, and a zero-filled file: refused in one line naming the line,
    at once (the whole file is not read)."""
    long = tmp_path / "long.csv"
    long.write_text("0.001\n0.002\n" + "0" * 2_000_000)
    zeros = tmp_path / "zeros.bin"
    zeros.write_bytes(b"0.001\n" + bytes(1000))
    for path, words in ((long, "line 3: longer than 1,000,000 characters"), (zeros, "line 2: a NUL byte")):
        t0 = time.perf_counter()
        code, out, err = run_cli(capsys, "monitor", path, *ENGINE, "--tdc-deg", "0")
        line = one_error_line(err)
        assert code == 2 and words in line and str(path) in line and time.perf_counter() - t0 < 30


def test_a_cr_only_log_gives_the_verdicts_of_the_lf_log(recorded, tmp_path, capsys):
    cr = tmp_path / "cr.csv"
    cr.write_bytes(recorded.read_bytes().replace(b"\n", b"\r"))
    # the run's last cycle given to both (cr.csv has no truth file beside it to say it)
    code, out_lf, _ = run_cli(capsys, "monitor", recorded, *ENGINE, "--json", "--last-cycle", "40")
    code, out_cr, err = run_cli(capsys, "monitor", cr, *ENGINE, "--json", "--last-cycle", "40")
    assert code == 0 and out_cr == out_lf


# ---------------------------------------------------------------------- warnings, nothing judged
def test_warnings_of_one_kind_are_shown_a_few_times_and_counted(recorded, tmp_path, capsys):
    """500 bad lines: three warnings shown, one saying the rest are counted, and the count in
    the summary (a warning a line, before)."""
    lines = recorded.read_text().splitlines()
    first = next(i for i, s in enumerate(lines) if s[:1].isdigit())
    bad = lines[: first + 100] + ["not a time"] * 500 + lines[first + 100 :]
    path = tmp_path / "bad.csv"
    path.write_text("\n".join(bad) + "\n")
    code, out, err = run_cli(capsys, "monitor", path, *ENGINE, "--json")
    assert code == 0 and err.count("is not a time: skipped") == 3
    assert err.count("more notes 'bad_line' are counted, not shown") == 1 and len(err.splitlines()) <= 6
    rows, summary = verdicts(out)
    assert summary["lines_skipped"] == 500 and {(r["cycle"], r["cylinder"]) for r in rows if r["misfire"]} == MISFIRES


def test_a_monitor_that_judges_nothing_exits_2_with_the_reason(recorded, tmp_path, capsys):
    """A wheel never found (36-1 times read as 60-2: a warning every 29 edges and an all-NaN
    table, exit 0) and a log too short: exit 2, the reason in one line, no table."""
    wrong = tmp_path / "wrong.csv"
    theta = np.arange(0, 300 * 36) * (2 * np.pi / 36)
    t = theta[(np.arange(theta.size) % 36) < 35] / 157.0
    wrong.write_text("# tdc_after_gap_deg: 0\n" + "\n".join(f"{x:.9f}" for x in t) + "\n")
    code, out, err = run_cli(capsys, "monitor", wrong, "--cylinders", "4", "--wheel", "60-2", "--json")
    assert code == 2 and out == "" and len(err.splitlines()) <= 5
    assert "no firing judged: the 60-2 wheel was not found in" in err.splitlines()[-1]
    short = tmp_path / "short.csv"
    short.write_text("\n".join(recorded.read_text().splitlines()[:60]) + "\n")
    code, out, err = run_cli(capsys, "monitor", short, *ENGINE)
    assert code == 2 and out == "" and "no firing judged: 56 tooth edge(s), fewer than the 119" in one_error_line(err)


def test_the_summary_shows_a_dash_where_a_cylinder_has_no_verdict(recorded):
    """A stream that ends after a cycle: cylinders without a judged firing show '-' in the
    summary and null in the JSON, never NaN."""
    t = times_of(recorded)
    m = MisfireMonitor("60-2", tdc_deg=29.4, engine="4chn15")
    m.feed(t[:200])
    m.close()
    r = m.result()
    assert 0 < r.judged.sum() and 0 in r.judged.tolist()
    assert "nan" not in r.summary().lower() and " -" in r.summary()
    json.dumps(r.to_json_dict(), allow_nan=False)


# ---------------------------------------------------------------------- --follow, Ctrl-C
def _follow(path):
    return subprocess.Popen(
        [sys.executable, "-m", "rotor.cli", "monitor", str(path), *ENGINE, "--follow"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _stop(p):
    time.sleep(0.3)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    return out, err


@pytest.mark.timeout(180)
@pytest.mark.parametrize("how", ["truncated", "replaced"])
def test_follow_notices_a_file_truncated_or_replaced_and_reads_it_anew(recorded, tmp_path, how):
    """The followed file truncated (copied and emptied, as copytruncate does) or replaced (moved
    away and made anew, as a rotating logger does) while the monitor waits at its end: it says
    so in one line and reads the new contents from their start (it waited without a word)."""
    text = recorded.read_text()
    cut = text.index("\n", len(text) // 2) + 1
    grow = tmp_path / "grow.csv"
    grow.write_text(text[:cut])
    p = _follow(grow)
    try:
        assert p.stdout.readline().startswith("cycle")
        time.sleep(1.0)  # at the end of the file, waiting
        head = "".join(line + "\n" for line in text.splitlines() if not line[:1].isdigit())
        rest = head + text[cut:]
        if how == "truncated":
            grow.write_text(rest)
        else:
            os.rename(grow, tmp_path / "grow.csv.1")
            (tmp_path / "grow.csv").write_text(rest)
        seen = []
        while not seen or (seen[-1] and not seen[-1].startswith("cycle    40")):
            seen.append(p.stdout.readline())
        out, err = _stop(p)
    finally:
        if p.poll() is None:
            p.kill()
    word = "was truncated" if how == "truncated" else "was replaced by another file"
    assert err.count(word) == 1 and "Traceback" not in err and p.returncode == 130
    assert seen[-1].startswith("cycle    40") and sum("MISFIRE" in line for line in seen) >= 2


@pytest.mark.timeout(120)
def test_ctrl_c_in_a_garbage_collector_callback_exits_130_without_a_traceback(recorded, tmp_path):
    """SIGINT while a garbage collector's callback runs: Python cannot raise it there and
    printed it with a traceback; the run still ends with 130 and 'rotor: interrupted'."""
    script = tmp_path / "gc_interrupt.py"
    script.write_text(
        "import gc, os, signal, sys\n"
        "from rotor.cli.app import main\n"
        "calls = []\n"
        "def callback(phase, info):\n"
        "    if phase == 'start' and 'rotor.diagnostics.monitor' in sys.modules:\n"
        "        calls.append(1)\n"
        "        if len(calls) == 3:\n"
        "            os.kill(os.getpid(), signal.SIGINT)\n"
        "            for _ in range(1000):\n"
        "                pass\n"
        "gc.callbacks.append(callback)\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    p = subprocess.run(
        [sys.executable, str(script), "monitor", str(recorded), *ENGINE],
        capture_output=True,
        text=True,
        timeout=100,
    )
    assert p.returncode == 130 and "rotor: interrupted" in p.stderr
    assert "Traceback" not in p.stderr and "Exception ignored" not in p.stderr


@pytest.mark.timeout(120)
def test_follow_ends_on_an_interrupt_dropped_in_a_garbage_collector_callback(recorded, tmp_path):
    """Following a file at its end, an interrupt that a garbage collector's callback dropped
    still ends the wait (exit 130), without a traceback."""
    script = tmp_path / "gc_follow.py"
    script.write_text(
        "import gc, os, signal, sys, threading, time\n"
        "from rotor.cli.app import main\n"
        "fired = []\n"
        "def callback(phase, info):\n"
        "    if phase == 'start' and not fired and threading.current_thread() is threading.main_thread():\n"
        "        fired.append(1)\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        for _ in range(1000):\n"
        "            pass\n"
        "def later():\n"
        "    time.sleep(3.0)\n"
        "    gc.callbacks.append(callback)\n"
        "    gc.set_threshold(1)\n"
        "threading.Thread(target=later, daemon=True).start()\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    p = subprocess.run(
        [sys.executable, str(script), "monitor", str(recorded), *ENGINE, "--follow"],
        capture_output=True,
        text=True,
        timeout=100,
    )
    assert p.returncode == 130 and "rotor: interrupted" in p.stderr
    assert "Traceback" not in p.stderr and "Exception ignored" not in p.stderr


@pytest.mark.timeout(60)
def test_a_named_pipe_is_read_as_a_stream(recorded, tmp_path):
    """A named pipe given as the log is read as it comes (it was 'no such file')."""
    fifo = tmp_path / "teeth.pipe"
    os.mkfifo(fifo)
    proc = subprocess.Popen(
        [sys.executable, "-m", "rotor.cli", "monitor", str(fifo), "--engine", "4chn15", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    with open(fifo, "wb") as f:
        f.write(recorded.read_bytes())
    out, err = proc.communicate(timeout=50)
    assert proc.returncode == 0, err.decode()
    assert json.loads(out.decode().splitlines()[-1])["summary"]["misfire_count"] == 3
