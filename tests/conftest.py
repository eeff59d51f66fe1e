import gc
import json
import os
import signal
import time
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings

matplotlib.use("Agg")

# A suite started in the background by a non-interactive shell inherits SIGINT ignored
# (POSIX), and so would every command it starts: the tests of Ctrl-C need the default.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# JAX's persistent compilation cache in a folder of the checkout's own (build/, ignored by
# git; inherited by the CLI subprocesses the tests start), not the user's ~/.cache/rotor/jax:
# a fresh clone starts from an empty cache, as on a fresh machine, and a second run in the
# same clone reads back what the first compiled. Delete build/test-jax-cache to start cold.
if "ROTOR_COMPILATION_CACHE" not in os.environ:
    os.environ["ROTOR_COMPILATION_CACHE"] = str(Path(__file__).resolve().parents[1] / "build" / "test-jax-cache")
# The engines' tables (rotor.cache.table_folder) likewise, beside it.
if "ROTOR_TABLE_CACHE" not in os.environ:
    os.environ["ROTOR_TABLE_CACHE"] = str(Path(__file__).resolve().parents[1] / "build" / "test-tables")

# Property tests draw the same examples on every run (``derandomize``), so that `make test`
# runs what CI runs; `make fuzz` (ROTOR_FUZZ=1) draws new ones, and what it finds becomes an
# explicit example in the test.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("fuzz", derandomize=False)
settings.load_profile("fuzz" if os.environ.get("ROTOR_FUZZ", "").strip() not in ("", "0") else "deterministic")

# The suite compiles with LLVM's optimisation off (level 0; the CLI subprocesses and
# notebook kernels inherit it): most of its time is XLA compiling programs that then run
# for milliseconds: a cold run's pytest phase took 752 s at level 0 against 925 s at the
# default here, the same tree (benchmarks/README.md, "Test suite time"). Users' programs are compiled at XLA's default level, which
# tests/project/test_code_generation.py runs in a process of its own and compares with this
# one. ROTOR_SUITE_XLA_DEFAULT=1 runs the whole suite at the default level; XLA_FLAGS that
# names the option keeps the caller's.
if os.environ.get("ROTOR_SUITE_XLA_DEFAULT", "").strip() in ("", "0") and "xla_backend_optimization_level" not in (
    os.environ.get("XLA_FLAGS", "")
):
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} --xla_backend_optimization_level=0".strip()

# The kept outputs of `rotor table` and `rotor info` (rotor/cli/kept.py) are off: every CLI
# test computes what it checks; tests/cli/test_cli_latency.py switches them on in a folder of its own.
os.environ.setdefault("ROTOR_OUTPUT_CACHE", "off")


import jax  # noqa: E402

import rotor  # noqa: E402  (switches float64 on)
from rotor.programs import clear_programs  # noqa: E402

# Switched on for the tests in this process too, not only once a CLI command has run in it:
# most of the suite's time is XLA compiling rotor's kernels, and many modules (and both
# xdist workers, the CLI subprocesses and the notebook kernels of tests/project/test_notebooks.py,
# which share the folder) compile the same ones. A kernel compiled once in the session is
# read back instead of compiled again, also after _free_compiled_code below drops it.
# Every program is kept, however quickly it compiled (the `rotor` command keeps those of 0.1 s
# or more): the suite's many small ones (an operation of JAX on a concrete array of a new
# shape) are compiled once for both workers and for the next run, not again in each.
# ROTOR_COMPILATION_CACHE=off runs the suite without it.
COMPILATION_CACHE = rotor.enable_compilation_cache(min_compile_time_s=0.0)

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
SHARED_DATA = ROOT.parent / "shared" / "data"

# How many programs XLA was asked for in the test processes (CLI subprocesses and notebook
# kernels apart), how many of them the persistent cache held, and the seconds spent: each
# process writes its own count into build/test-compilations/, the summary adds them up.
COMPILATIONS = ROOT / "build" / "test-compilations"
_COMPILED = {"programs": 0, "from_cache": 0, "seconds": 0.0}
_PER_TEST: dict[str, list[float]] = {}
"""Per test file: [XLA programs compiled, seconds compiling, seconds in its tests]."""


# ROTOR_SUITE_PROFILE=1: also per test file and per function, the seconds tracing, lowering
# and compiling (build/test-compilations/<worker>.json, "functions").
_PROFILE = os.environ.get("ROTOR_SUITE_PROFILE", "").strip() not in ("", "0")
_FUNCTIONS: dict[str, list[float]] = {}
_CURRENT = {"file": ""}


def _count_program(event: str, duration_secs: float, fun_name: str = "?", **_: object) -> None:
    if event == "/jax/core/compile/backend_compile_duration":
        _COMPILED["programs"] += 1
        _COMPILED["seconds"] += duration_secs
    if _PROFILE and event.startswith("/jax/core/compile/"):
        key = f"{_CURRENT['file']}|{event.rsplit('/', 1)[-1]}|{fun_name}"
        row = _FUNCTIONS.setdefault(key, [0, 0.0])
        row[0] += 1
        row[1] += duration_secs


def _count_cache_hit(event: str, **_: object) -> None:
    if event == "/jax/compilation_cache/cache_hits":
        _COMPILED["from_cache"] += 1


jax.monitoring.register_event_duration_secs_listener(_count_program)
jax.monitoring.register_event_listener(_count_cache_hit)


def pytest_configure(config):
    if not hasattr(config, "workerinput"):  # the main process, before any worker starts
        for old in COMPILATIONS.glob("*.json"):
            old.unlink(missing_ok=True)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Adds up, per test file, the programs compiled and the time spent (setup, call and
    teardown), for the summary's table of where the suite's time goes."""
    programs, seconds, start = (
        _COMPILED["programs"] - _COMPILED["from_cache"],
        _COMPILED["seconds"],
        time.perf_counter(),
    )
    _CURRENT["file"] = item.nodeid.split("::")[0]
    yield
    row = _PER_TEST.setdefault(item.nodeid.split("::")[0], [0, 0.0, 0.0])
    row[0] += _COMPILED["programs"] - _COMPILED["from_cache"] - programs
    row[1] += _COMPILED["seconds"] - seconds
    row[2] += time.perf_counter() - start


def pytest_sessionfinish(session):
    worker = getattr(session.config, "workerinput", {}).get("workerid", "main")
    COMPILATIONS.mkdir(parents=True, exist_ok=True)
    (COMPILATIONS / f"{worker}.json").write_text(json.dumps({**_COMPILED, "files": _PER_TEST, "functions": _FUNCTIONS}))


def pytest_terminal_summary(terminalreporter):
    counts = [json.loads(f.read_text()) for f in sorted(COMPILATIONS.glob("*.json"))]
    if counts:
        programs, cached = sum(c["programs"] for c in counts), sum(c["from_cache"] for c in counts)
        seconds = sum(c["seconds"] for c in counts)
        terminalreporter.write_line(
            f"XLA programs in the test processes: {programs} ({cached} read from the persistent compilation cache, "
            f"{programs - cached} compiled), {seconds:.0f} s"
        )
        files: dict[str, list[float]] = {}
        for c in counts:
            files.update(c.get("files", {}))
        slowest = sorted(files.items(), key=lambda kv: -kv[1][2])[:15]
        if slowest:
            terminalreporter.write_line("slowest test files: seconds (of them compiling), programs compiled")
            for name, (n, compiling, total) in slowest:
                terminalreporter.write_line(f"{total:8.1f} s ({compiling:6.1f} s) {int(n):6d}  {name}")


def _memory_maps() -> tuple[int, int]:
    """(memory mappings of this process, the kernel's limit vm.max_map_count); (0, 1) where
    /proc cannot tell."""
    try:
        with open("/proc/self/maps", "rb") as f:
            used = f.read().count(b"\n")
        with open("/proc/sys/vm/max_map_count") as f:
            return used, int(f.read())
    except (OSError, ValueError):
        return 0, 1


MAPS_HIGH = 0.5
"""Share of vm.max_map_count past which the compiled executables are dropped."""


@pytest.fixture(autouse=True)
def _free_compiled_code():
    """Drop JAX's compiled executables when this process nears the kernel's limit on memory
    mappings. Every loaded CPU executable holds mappings; one process running the whole
    suite otherwise passes Linux's vm.max_map_count (65530) about 85 % of the way through
    and XLA crashes in the next compile (two test modules alone leave 24 000 mappings; after
    clear_caches, 1 100). Below half the limit the compiled code is kept for the tests after,
    which reuse it instead of tracing and compiling again."""
    yield
    used, limit = _memory_maps()
    if used > MAPS_HIGH * limit:
        jax.clear_caches()
        clear_programs()
        gc.collect()


def run_cli(capsys: pytest.CaptureFixture | None, *argv: object) -> tuple[int, str, str]:
    """``rotor argv`` in the test's own process through :func:`rotor.cli.app.main`: (exit
    status, standard output, standard error). Each argument is passed as ``str`` (paths and
    numbers may be given as they are); a usage error argparse raises as ``SystemExit`` gives
    its exit status. ``capsys`` is the test's fixture, whose buffers are read (and emptied);
    ``None`` in a fixture wider than one test, where no ``capsys`` exists: the output is then
    caught with ``contextlib.redirect_stdout``/``redirect_stderr``."""
    import contextlib
    import io

    from rotor.cli.app import main

    def call() -> int:
        try:
            return main([str(a) for a in argv])
        except SystemExit as e:  # argparse's own usage errors, --help
            return 0 if e.code is None else e.code

    if capsys is not None:
        rc = call()
        out, err = capsys.readouterr()
        return rc, out, err
    out_buf, err_buf = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out_buf), contextlib.redirect_stderr(err_buf):
        rc = call()
    return rc, out_buf.getvalue(), err_buf.getvalue()


@pytest.fixture(scope="session")
def diesel():
    return rotor.load_engine("4chn15")


def two_mass_engine(
    lam=0.267,
    R=0.1025,
    m_rec=9.72,
    m_rot=0.0,
    J=1e-6,
    cylinders=1,
    k=0.0,
    throws=None,
    firing=None,
    pressure=None,
    strokes=4,
):
    """A small engine built in Python, for closed-form checks."""
    throws = [0.0] * cylinders if throws is None else throws
    firing = list(range(1, cylinders + 1)) if firing is None else firing
    return rotor.Engine(
        name="test",
        strokes=strokes,
        cylinders=cylinders,
        geometry=rotor.Geometry(bore_m=0.15, stroke_m=2 * R, rod_length_m=R / lam, pin_offset_m=k),
        masses=rotor.Masses(reciprocating_kg=m_rec, rotating_kg=m_rot),
        crankshaft=rotor.Crankshaft(inertia_kgm2=J),
        layout=rotor.Layout(throw_angles_deg=throws, firing_order=firing),
        pressure=rotor.NoPressure() if pressure is None else pressure,
        operating=rotor.Operating(rpm=1000.0),
    )
