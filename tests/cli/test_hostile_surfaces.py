"""Hostile inputs against the later surfaces of the command line and the library: absurd
finite option values, the kept-output cache, wheel specs and wheel files, digital captures,
user text in plots, interrupts, output locations and the sizes of torsion work.

Each case ends cleanly: exit 2 for bad input with one line naming the problem, 130 on
Ctrl-C, 0 only with a whole, finite result; no traceback, no partial or temporary file, none
of the user's files touched. Everything runs in-process through :func:`rotor.cli.app.main`
unless the real process is the point (signals)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, run_cli

TWO_PI = 2 * np.pi


def tooth_times(rpm: float = 3000.0, revs: int = 12, teeth: int = 60, missing: int = 2) -> np.ndarray:
    """Edge times [s] of an N−M wheel at ``rpm`` with a small half-order fluctuation."""
    w = TWO_PI * rpm / 60
    ang = 0.37 + TWO_PI * np.arange(revs)[:, None] + TWO_PI / teeth * np.arange(teeth - missing)[None, :]
    ang = ang.ravel()
    return ang / w + 0.02 * np.sin(ang / 2) / w


@pytest.fixture(scope="module")
def teeth_log(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A clean 60-2 tooth-time log."""
    path = tmp_path_factory.mktemp("surfaces") / "teeth.csv"
    np.savetxt(path, tooth_times(), fmt="%.12g")
    return str(path)


def assert_refused(rc: int, err: str, *fragments: str) -> None:
    """Exit 2 with one line on stderr holding every fragment, no traceback."""
    assert rc == 2, err
    assert "Traceback" not in err and "internal error" not in err, err
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("rotor: warning:")]
    assert len(lines) == 1, err
    for f in fragments:
        assert f in lines[0], err


# ----------------------------------------------------------------------------- absurd option values
TOOTH = ["--wheel", "60-2", "--columns", "tooth_time_s"]


@pytest.mark.parametrize("value", ["9223372036854775808", "-9223372036854775808", "1e300", "3601"])
def test_an_absurd_finite_angle_is_refused_in_one_line(
    value: str, teeth_log: str, capsys: pytest.CaptureFixture
) -> None:
    rc, _, err = run_cli(capsys, "analyze", teeth_log, *TOOTH, "--json", "--tdc-deg", value)
    assert_refused(rc, err, "--tdc-deg", "from -3600 to 3600 degrees")


def test_diagnose_refuses_an_absurd_angle_too(teeth_log: str, capsys: pytest.CaptureFixture) -> None:
    argv = ["diagnose", teeth_log, "--engine", "4chn15", *TOOTH, "--tdc-deg", "9223372036854775808"]
    rc, _, err = run_cli(capsys, *argv)
    assert_refused(rc, err, "--tdc-deg", "or 'speed'")


def test_an_absurd_cylinder_count_is_refused_in_one_line(teeth_log: str, capsys: pytest.CaptureFixture) -> None:
    rc, _, err = run_cli(capsys, "analyze", teeth_log, *TOOTH, "--cylinders", "100000000000000000000000")
    assert_refused(rc, err, "--cylinders", "at most 64 cylinders")


def test_a_plausible_angle_still_runs(teeth_log: str, capsys: pytest.CaptureFixture) -> None:
    rc, out, err = run_cli(capsys, "analyze", teeth_log, *TOOTH, "--json", "--tdc-deg", "-710")
    assert rc == 0, err
    json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))


# ----------------------------------------------------------------------------- the kept-output cache
@pytest.fixture
def kept_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An output cache of its own for the test."""
    folder = tmp_path / "kept"
    monkeypatch.setenv("ROTOR_OUTPUT_CACHE", str(folder))
    return folder


def only_entry(folder: Path) -> Path:
    """The newest entry of ``folder`` (the only one, unless rotor's source changed under a
    running test and with it the key)."""
    entries = sorted(folder.iterdir(), key=lambda p: p.stat().st_mtime_ns)
    assert entries and all(p.name.startswith("rotor-output-") for p in entries), entries
    return entries[-1]


@pytest.mark.parametrize(
    "spoil",
    [
        lambda raw: b'{"displacement_m3": NaN}',
        lambda raw: b"",
        lambda raw: raw[: len(raw) // 2],
        lambda raw: raw.replace(b"0.", b"9.", 1),
    ],
    ids=["overwritten with NaN", "empty", "cut off", "one digit changed"],
)
def test_a_spoilt_kept_output_is_computed_afresh(spoil, kept_folder: Path, capsys: pytest.CaptureFixture) -> None:
    argv = ["info", "4chn15", "--json"]
    rc, first, err = run_cli(capsys, *argv)
    assert rc == 0, err
    entry = only_entry(kept_folder)
    entry.write_bytes(spoil(entry.read_bytes()))
    rc, again, err = run_cli(capsys, *argv)
    assert rc == 0 and again == first, err
    json.loads(again, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))
    rc, third, err = run_cli(capsys, *argv)  # the entry is whole again
    assert rc == 0 and third == first, err
    assert json.loads(only_entry(kept_folder).read_bytes().partition(b"\n")[2]) == json.loads(first)


def test_pruning_keeps_the_users_own_files(kept_folder: Path, capsys: pytest.CaptureFixture, monkeypatch) -> None:
    from rotor.cli import kept

    kept_folder.mkdir()
    mine = [kept_folder / f"notes{i:03d}.txt" for i in range(300)]
    for i, p in enumerate(mine):
        p.write_text(f"the user's note {i}\n")
        os.utime(p, ns=(i * 10**9, i * 10**9))
    monkeypatch.setattr(kept, "MAX_FILES", 2)
    for rpm in ("900", "1000", "1100"):
        rc, _, err = run_cli(capsys, "info", "4chn15", "--json", "--rpm", rpm)
        assert rc == 0, err
    assert all(p.read_text() == f"the user's note {i}\n" for i, p in enumerate(mine))
    own = set(kept_folder.iterdir()) - set(mine)
    assert len(own) == 2, own  # rotor's own entries are pruned to the newest


# ----------------------------------------------------------------------------- wheel specs
SEVENTEEN_GAPS = "36" + "-2" * 17
HUGE_N = "9" * 5000 + "-2"


@pytest.mark.parametrize(
    "spec,fragment",
    [
        (SEVENTEEN_GAPS, "17 gaps need 51 positions or more"),
        ("36-20-20", "40 missing teeth in 2 gaps on 36 positions; at most 32 fit"),
        ("60-59", "59 missing teeth in 1 gap on 60 positions; at most 58 fit"),
        (HUGE_N, "a number of 5000 digits"),
        ("100001-2", "from 3 to 100000"),
    ],
    ids=["17 gaps", "two big gaps", "one gap too big", "5000 digits", "too many positions"],
)
def test_a_wheel_spec_beyond_the_real_limit_names_wheel(spec: str, fragment: str, capsys, teeth_log: str) -> None:
    from rotor import parse_wheel
    from rotor.errors import LogError

    with pytest.raises(LogError) as info:
        parse_wheel(spec)
    assert info.value.argument == "wheel" and str(info.value).startswith("wheel=")
    assert fragment in str(info.value)
    rc, _, err = run_cli(capsys, "analyze", teeth_log, "--wheel", spec, "--columns", "tooth_time_s")
    assert_refused(rc, err, "rotor: error: --wheel ", fragment)
    assert "set_int_max_str_digits" not in err and "need 0 …" not in err and len(err) < 400


@pytest.mark.parametrize("spec", [3.5, None, ["60-2"], True])
def test_a_wheel_of_the_wrong_type_names_wheel(spec) -> None:
    from rotor import parse_wheel

    with pytest.raises(TypeError, match=r"^wheel="):
        parse_wheel(spec)


def test_a_wheel_at_the_real_limit_is_taken() -> None:
    from rotor import parse_wheel

    assert parse_wheel("36" + "-1" * 12).missing == 12  # 36 − 2 × 12 = 12: just fits
    assert parse_wheel("60-58").edges_per_rev == 2


# ----------------------------------------------------------------------------- wheel files
WHEEL_36_2 = "positions = 36\nmissing = [34, 35]\n"


@pytest.mark.parametrize(
    "text,fragment",
    [
        ("positions = 36\nmissing = [true]\n", "'missing' must be a list of positions 0 … 35"),
        (
            WHEEL_36_2 + "angle_deg = [" + ", ".join(str(10.0 * i) for i in range(34)) + "]\n",
            "did you mean 'angles_deg'",
        ),
        (WHEEL_36_2 + "[extra]\nx = 1\n", "extra: unknown key"),
        ("positions = 36.0\nmissing = [35]\n", "'positions' must be a whole number"),
        ("positions = 36\nmissing = [35, 35]\n", "position 35 twice"),
        ("positions = 36\nmissing = [35]\nangles_deg = [true]\n", "'angles_deg' must be 35 numbers"),
        ("positions = " + "9" * 30 + "\n", "from 3 to 100000"),
    ],
    ids=["missing true", "misspelt angles", "unknown table", "float positions", "twice", "bool angle", "huge"],
)
def test_a_malformed_wheel_file_is_refused_by_key(text: str, fragment: str, tmp_path: Path, capsys) -> None:
    from rotor.errors import LogError
    from rotor.logs.wheel import read_wheel_file

    path = tmp_path / "w.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(LogError, match="^" + str(path).replace("\\", "\\\\")) as info:
        read_wheel_file(path)
    assert fragment in str(info.value)
    rc, _, err = run_cli(capsys, "analyze", str(tmp_path / "none.csv"), "--wheel", str(path))
    assert rc == 2 and "Traceback" not in err and "internal error" not in err, err


def test_a_wheel_file_with_a_byte_order_mark_is_read(tmp_path: Path) -> None:
    from rotor.logs.wheel import read_wheel_file

    path = tmp_path / "w.toml"
    path.write_bytes(b"\xef\xbb\xbf" + WHEEL_36_2.encode())
    w = read_wheel_file(path)
    assert (w.teeth, w.gaps) == (36, (2,))


def test_a_folder_named_like_a_wheel_file_is_named_a_folder(tmp_path: Path, teeth_log: str, capsys) -> None:
    folder = tmp_path / "x.toml"
    folder.mkdir()
    rc, _, err = run_cli(capsys, "analyze", teeth_log, "--wheel", str(folder), "--columns", "tooth_time_s")
    assert_refused(rc, err, "x.toml: is a folder, not a wheel file")


# ----------------------------------------------------------------------------- user text in plots


def with_dollars(tmp_path: Path, preset: str) -> Path:
    """``preset``'s file with a name, and (for a torsional chain) a mass name, of dollars."""
    import re

    text = (ROOT / "rotor" / "presets" / f"{preset}.toml").read_text(encoding="utf-8")
    text = re.sub(r'(?m)^name = ".*"$', 'name = "Test $x_$ engine"', text, count=1)
    text = re.sub(r'(?m)^names = \["[^"]*"', 'names = ["$damper_$"', text, count=1)
    path = tmp_path / "dollar $a_$.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_dollars_in_names_are_drawn_as_they_are(tmp_path: Path, capsys) -> None:
    engine = with_dollars(tmp_path, "mwm6")
    out = tmp_path / "out $b_$"
    rc, _, err = run_cli(capsys, "modes", str(engine), "--plot", str(out))
    assert rc == 0, err
    assert [p.name for p in out.iterdir()] == ["modes.png"] and (out / "modes.png").stat().st_size > 1000


def test_an_engine_named_with_dollars_is_drawn(tmp_path: Path) -> None:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotor import load_engine
    from rotor.engine.table import crank_table

    table = crank_table(load_engine(with_dollars(tmp_path, "4chn15")), step_deg=30.0)
    axes = table.plot()
    fig = np.ravel(axes)[0].figure
    fig.savefig(io.BytesIO(), format="png")  # mathematics is parsed while drawing
    assert "Test \\$x_\\$ engine" in np.ravel(axes)[0].get_title()
    plt.close(fig)


def test_plain_keeps_every_letter_of_a_users_text() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotor.plotting.common import plain

    fig, ax = plt.subplots()
    title = ax.set_title(plain("Test $x_$ engine, 5 $ and \\$"))
    fig.canvas.draw()
    assert title.get_text() == "Test \\$x_\\$ engine, 5 \\$ and \\\\$"
    plt.close(fig)


# ----------------------------------------------------------------------------- output locations
needs_sysfs = pytest.mark.skipif(
    not os.path.isdir("/sys/kernel"), reason="needs Linux's /sys, where no file can be made"
)


@needs_sysfs
@pytest.mark.parametrize(
    "argv,path",
    [
        (["table", "4chn15", "--format", "csv", "--output", "/sys/x.csv"], "/sys/x.csv"),
        (["balance", "4chn15", "--plot", "/sys/plots"], "/sys/plots"),
        (["report", "4chn15", "--out", "/sys/report"], "/sys/report"),
        (["report", "4chn15", "--out", "/sys/new/a/report"], "/sys/new/a/report"),
    ],
    ids=["table --output", "--plot", "report", "report in new folders"],
)
def test_an_unwritable_output_is_refused_before_the_work_naming_the_users_path(
    argv: list[str], path: str, capsys, monkeypatch
) -> None:
    import rotor.engine.table

    def no_work(*a, **k):
        raise AssertionError("the work started before the output was checked")

    monkeypatch.setattr(rotor.engine.table, "crank_table", no_work)
    monkeypatch.setattr("rotor.design.balance.balance", no_work)
    rc, _, err = run_cli(capsys, *argv)
    assert_refused(rc, err, f"rotor: error: {path}: ")
    assert ".rotor" not in err


@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_a_dangling_link_as_the_output_folder_is_refused_before_the_work(
    option: str, tmp_path: Path, capsys, monkeypatch
) -> None:
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "nowhere")
    monkeypatch.setattr("rotor.design.balance.balance", lambda *a, **k: pytest.fail("the work started"))
    argv = ["report", "4chn15", "--out", str(link)] if option == "--out" else ["balance", "4chn15", "--plot", str(link)]
    rc, _, err = run_cli(capsys, *argv)
    assert_refused(rc, err, f"{link}: is a link to {tmp_path / 'nowhere'}, which does not exist")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link"]


def test_two_reports_put_in_place_at_once_end_as_one_whole_report(tmp_path: Path) -> None:
    import threading

    from rotor.design.report import report_folder

    out = tmp_path / "new" / "report"
    both_written = threading.Barrier(2)
    errors: list[BaseException] = []

    def write(who: str) -> None:
        try:
            with report_folder(str(out)) as tmp:
                for name in ("figures", "tables"):
                    os.mkdir(os.path.join(tmp, name))
                    Path(tmp, name, f"{name}.txt").write_text(who)
                Path(tmp, "index.html").write_text(who)
                both_written.wait(timeout=10)  # both put their report in place at once
        except BaseException as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=write, args=(who,)) for who in ("first", "second")]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=30)
    assert not errors, errors
    assert sorted(p.name for p in out.iterdir()) == [".rotor-report.json", "figures", "index.html", "tables"]
    texts = {(out / "index.html").read_text(), (out / "figures" / "figures.txt").read_text()}
    texts.add((out / "tables" / "tables.txt").read_text())
    assert len(texts) == 1, texts  # one run's report, whole
    assert sorted(p.name for p in out.parent.iterdir()) == ["report"]  # no temporary folder left


# ----------------------------------------------------------------------------- interrupts
@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_an_interrupt_dropped_in_a_garbage_collector_callback_still_stops_the_run(
    tmp_path: Path, capsys, monkeypatch
) -> None:
    import gc
    import signal

    import rotor.engine.table

    fired = []

    def interrupt_once(phase: str, info: dict) -> None:
        if phase == "start" and not fired:
            fired.append(True)
            signal.raise_signal(signal.SIGINT)  # its KeyboardInterrupt is raised here, and dropped

    real = rotor.engine.table.crank_table

    def crank_table_with_a_collection(*args, **kwargs):
        gc.callbacks.append(interrupt_once)
        try:
            gc.collect()
        finally:
            gc.callbacks.remove(interrupt_once)
        return real(*args, **kwargs)

    monkeypatch.setattr(rotor.engine.table, "crank_table", crank_table_with_a_collection)
    out = tmp_path / "table.csv"
    rc, _, err = run_cli(capsys, "table", "4chn15", "--format", "csv", "--output", str(out))
    assert fired and rc == 130, err
    assert "rotor: interrupted" in err and not out.exists() and list(tmp_path.iterdir()) == []
    assert "Traceback" not in err and "Exception ignored" not in err  # dropped quietly, for every command
    from rotor.fileio import INTERRUPT, write_text_atomic

    assert not INTERRUPT  # the next call in this process is not stopped by it
    write_text_atomic(out, "x")
    assert out.read_text() == "x"


@pytest.mark.parametrize("stop", [KeyboardInterrupt, OSError])
def test_a_report_that_fails_removes_the_folders_it_made(stop, tmp_path: Path) -> None:
    from rotor.design.report import report_folder

    with pytest.raises(stop):
        with report_folder(str(tmp_path / "new" / "a" / "b" / "rep")) as tmp:
            Path(tmp, "index.html").write_text("half")
            raise stop()
    assert list(tmp_path.iterdir()) == []


def test_a_command_that_fails_removes_the_plot_folders_it_made(tmp_path: Path, capsys, monkeypatch) -> None:
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("rotor.cli.report.save_plot", interrupted)
    rc, _, err = run_cli(capsys, "balance", "4chn15", "--plot", str(tmp_path / "new" / "a" / "b"))
    assert rc == 130 and "rotor: interrupted" in err, err
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- digital captures
def capture_lines(order: tuple[int, int] = (0, 1)) -> list[str]:
    """A logic analyser's export, ", " separated: a 60-2 crank wheel on Channel 0 and a cam
    on Channel 1 at 3000 rpm, one row per transition; the columns in ``order`` of channels."""
    w = TWO_PI * 3000 / 60
    events = []
    for rev in range(12):
        for j in range(58):
            a = TWO_PI * rev + TWO_PI / 60 * j + 0.37
            events += [(a / w, 0, 1), ((a + np.pi / 60) / w, 0, 0)]
    for c in range(6):
        a = 2 * TWO_PI * c + 1.0
        events += [(a / w, 1, 1), ((a + 0.5) / w, 1, 0)]
    level = [0, 0]
    lines = ["Time[s], " + ", ".join(f"Channel {k}" for k in order), "0.000000000, 0, 0"]
    for t, channel, v in sorted(events):
        level[channel] = v
        lines.append(f"{t:.9f}, " + ", ".join(str(level[k]) for k in order))
    return lines


def test_a_nan_row_of_a_capture_is_named_by_its_line(tmp_path: Path, capsys) -> None:
    lines = capture_lines()
    lines.insert(50, "nan, nan, nan")
    path = tmp_path / "capture.csv"
    path.write_text("\n".join(lines) + "\n")
    rc, _, err = run_cli(capsys, "analyze", str(path), "--wheel", "60-2")
    assert_refused(rc, err, "capture.csv: line 51, column 'time': nan is not a finite number")
    assert "dtype" not in err


def test_capture_channels_are_mapped_by_name_wherever_their_columns_stand(tmp_path: Path, capsys) -> None:
    results = {}
    for order in ((0, 1), (1, 0)):
        path = tmp_path / f"capture{order[0]}{order[1]}.csv"
        path.write_text("\n".join(capture_lines(order)) + "\n")
        rc, out, err = run_cli(capsys, "analyze", str(path), "--wheel", "60-2", "--json")
        assert rc == 0, err
        results[order] = json.loads(out)
    assert results[(1, 0)]["cycles"] == results[(0, 1)]["cycles"]
    assert any("'Channel 0' → encoder_d" in n and "'Channel 1' → cam_d" in n for n in results[(1, 0)]["notes"])
    # the column names given win over the header's
    path = tmp_path / "capture10.csv"
    rc, out, err = run_cli(
        capsys, "analyze", str(path), "--wheel", "60-2", "--json", "--columns", "time,cam_d,encoder_d"
    )
    assert rc == 0 and json.loads(out)["cycles"] == results[(0, 1)]["cycles"], err
    rc, _, err = run_cli(capsys, "analyze", str(path), "--wheel", "60-2", "--columns", "time,encoder_d,cam_d")
    assert rc == 2 and "Traceback" not in err, err


def test_samples_cut_out_of_a_recording_are_named_without_a_warning(tmp_path: Path, capsys) -> None:
    w = 1500 / 30 * np.pi
    t = np.arange(0, 8 * TWO_PI / w, 1e-5)
    phi = w * t + 0.1
    tooth = (np.mod(phi, TWO_PI / 60) < np.pi / 60) & (np.floor(np.mod(phi, TWO_PI) / (TWO_PI / 60)) < 58)
    keep = ~((t > 0.1) & (t < 0.105))  # 5 ms of samples lost
    path = tmp_path / "bench.csv"
    np.savetxt(path, np.column_stack([t[keep], tooth[keep] * 4.0 + 0.3]), fmt="%.7g", delimiter=",")
    rc, _, err = run_cli(capsys, "analyze", str(path), "--wheel", "60-2", "--columns", "time,encoder_v")
    assert_refused(rc, err, "bench.csv: line 10002: the samples stop for 5 ms", "samples are missing")
    assert "Warning" not in err


# ----------------------------------------------------------------------------- sizes of torsion work
def long_chain(tmp_path: Path, n: int) -> Path:
    """The MWM six with a ``[torsion]`` chain of ``n`` masses (its inertia spread over the
    masses before the throws, the shafts stiffened in proportion)."""
    import re

    text = (ROOT / "rotor" / "presets" / "mwm6.toml").read_text(encoding="utf-8")
    head, _, rest = text.partition("[torsion]")
    after = re.split(r"(?m)^\[(?!torsion)", rest, maxsplit=1)
    tail = [0.03123, 0.01723, 0.03123, 0.03123, 0.01723, 0.03323, 2.07262]
    front = (0.017 + 0.009) / (n - 7)
    table = (
        f"[torsion]\ninertias_kgm2 = {[front] * (n - 7) + tail}\n"
        f"stiffnesses_Nm_per_rad = {[1.106e6 * n / 9] * (n - 1)}\n"
        f"throw_masses = {list(range(n - 6, n))}\nload_mass = {n}\n"
        f"relative_damping_Nms_per_rad = {[30.0] * (n - 1)}\n"
    )
    path = tmp_path / f"chain{n}.toml"
    path.write_text(head + table + ("\n[" + after[1] if len(after) > 1 else ""), encoding="utf-8")
    return path


def test_the_modes_of_a_long_chain_take_seconds_and_agree_with_the_exact_range(tmp_path: Path) -> None:
    import time

    import rotor
    from rotor.torsion.modes import EXACT_SPREAD_MASSES, frequency_spread

    engine = rotor.load_engine(long_chain(tmp_path, 200))
    t0 = time.perf_counter()
    modes = rotor.torsional_modes(engine)
    assert time.perf_counter() - t0 < 30  # 360 dense eigenproblems and a 400 × 400 state space took minutes
    assert np.all(modes.frequency_min_hz <= modes.natural_frequencies_hz * (1 + 1e-9))
    assert np.all(modes.frequency_max_hz >= modes.natural_frequencies_hz * (1 - 1e-9))
    assert np.all(np.isfinite(modes.damped_frequencies_hz)) and np.all(modes.damping_ratios > 0)
    # the tridiagonal problems against the dense ones at every angle, on a chain just long enough
    import jax

    from rotor.torsion.model import mass_inertias
    from rotor.torsion.modes import natural_frequencies_of

    short = rotor.load_engine(long_chain(tmp_path, EXACT_SPREAD_MASSES + 1))
    lo, hi = frequency_spread(short)
    J = mass_inertias(short, np.linspace(0, TWO_PI, 360, endpoint=False))
    exact = np.asarray(jax.vmap(natural_frequencies_of, in_axes=(0, None))(J, short.torsion.stiffnesses_Nm_per_rad))
    np.testing.assert_allclose(lo, exact.min(axis=0), rtol=1e-9)
    np.testing.assert_allclose(hi, exact.max(axis=0), rtol=1e-9)
    assert np.max(hi / lo) > 1.01  # a range to get right


@pytest.mark.parametrize("command", ["modes", "campbell"])
def test_a_chain_of_ten_thousand_masses_is_refused_naming_the_table(command: str, tmp_path: Path, capsys) -> None:
    rc, _, err = run_cli(capsys, command, str(long_chain(tmp_path, 10_000)))
    assert_refused(rc, err, "the [torsion] table's chain has 10000 masses", "about", "at most 2000 masses")


@pytest.mark.parametrize(
    "n,fragment",
    [(100, "would take about 3 minutes per speed"), (1000, "× 1000 masses of the [torsion] table needs")],
)
def test_a_forced_response_too_big_is_refused_before_the_work(n: int, fragment: str, tmp_path: Path, capsys) -> None:
    rc, _, err = run_cli(capsys, "torsion", str(long_chain(tmp_path, n)))
    assert_refused(rc, err, fragment)
    assert "--cycles" not in err and "--steps-per-cycle" not in err


def test_a_campbell_sweep_of_ten_million_speeds_is_refused_before_allocating() -> None:
    import rotor
    from rotor.errors import EngineError

    with pytest.raises(EngineError, match=r"^campbell\(rpm\): 10000000 speeds × 24 orders × 8 modes needs .* GB"):
        rotor.campbell(rotor.load_engine("mwm6"), rpm=np.linspace(600, 2600, 10**7))


def test_running_out_of_memory_names_only_the_commands_own_options(capsys, monkeypatch) -> None:
    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr("rotor.cli.torsion.cmd_torsion", exhausted)
    monkeypatch.setattr("rotor.torsion.response.torsional_response", exhausted)
    rc, _, err = run_cli(capsys, "torsion", "mwm6")
    assert_refused(rc, err, "ran out of memory: reduce the size of the run (a smaller input)")
    monkeypatch.setattr("rotor.engine.table.crank_table", exhausted)
    rc, _, err = run_cli(capsys, "table", "4chn15")
    assert_refused(rc, err, "ran out of memory: reduce the size of the run (--step, or a smaller input")


def test_a_named_pipe_given_as_a_log_is_named_as_one(tmp_path: Path, capsys) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    rc, _, err = run_cli(capsys, "analyze", str(fifo))
    assert rc == 2 and "is a named pipe, not a log file" in err and len(err.strip().splitlines()) == 1


def test_control_characters_of_a_name_reach_the_terminal_escaped(tmp_path: Path, capsys) -> None:
    name = tmp_path / "a\x1b[31mred\rname.csv"
    rc, _, err = run_cli(capsys, "analyze", str(name))
    assert rc == 2 and "\x1b" not in err and "\r" not in err and "\\x1b" in err


def test_an_error_naming_ten_thousand_columns_is_cut_to_a_line(tmp_path: Path, capsys) -> None:
    wide = tmp_path / "wide.csv"
    wide.write_text(",".join(f"c{i}" for i in range(10_000)) + "\n" + ",".join(["1"] * 10_000) + "\n")
    rc, _, err = run_cli(capsys, "analyze", str(wide), "--columns", ",".join(["bogus"] * 10_000))
    assert rc == 2 and len(err) < 1000 and "characters in all" in err


def test_a_scheduler_address_where_no_dask_scheduler_answers_is_named(tmp_path: Path, capsys) -> None:
    import socket
    import threading

    pytest.importorskip("distributed")
    server = socket.socket()
    server.bind(("127.0.0.1", 0))  # this machine only, one connection, stops by itself
    server.listen(1)
    server.settimeout(20)
    port = server.getsockname()[1]

    def answer_once() -> None:
        try:
            conn, _ = server.accept()
            conn.settimeout(5)
            conn.recv(100)
            conn.sendall(b"HTTP/1.0 200 OK\r\n\r\nnot a scheduler")
            conn.close()
        except OSError:
            pass
        finally:
            server.close()

    thread = threading.Thread(target=answer_once, daemon=True)
    thread.start()
    log = tmp_path / "teeth.csv"
    log.write_text("tooth_time_s\n" + "".join(f"{0.001 * i:.6f}\n" for i in range(200)))
    rc, _, err = run_cli(capsys, "analyze", str(log), str(log), "--scheduler", f"tcp://127.0.0.1:{port}")
    thread.join(timeout=10)
    assert rc == 2 and "is not a Dask scheduler" in err and "memory" not in err.split("(")[0]


def test_a_library_function_a_message_recommends_is_named_as_its_command(capsys) -> None:
    rc, _, err = run_cli(capsys, "steady", "4chn15", "--rpm", "5")
    assert rc != 0 and "rotor.simulate" not in err and "`rotor simulate ENGINE`" in err


def test_an_empty_engine_name_is_named_as_empty(capsys) -> None:
    import rotor
    from rotor.errors import EngineError

    with pytest.raises(EngineError, match="an empty name"):
        rotor.load_engine("")
    rc, _, err = run_cli(capsys, "info", "")
    assert rc == 2 and "an empty name" in err and "`rotor presets`" in err
