"""What keeps the command line fast: ``import rotor`` and the commands that compute nothing
with JAX (``--help``, ``COMMAND --help``, ``presets``) import none of the heavy packages
(JAX's import alone takes about a second), and the lazy top level still offers every
public name. These check imported modules, not wall time: ``benchmarks/cli_latency.py``
measures the speed."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

import rotor
from rotor.cli.app import build_parser

HEAVY = ("jax", "jaxlib", "equinox", "diffrax", "optimistix", "lineax", "matplotlib", "scipy", "pandas")

CHILD = r"""
import json, sys
from rotor.cli.app import main
try:
    status = main(sys.argv[1:])
except SystemExit as e:  # --help
    status = e.code
heavy = sorted(m for m in sys.modules if m.split(".")[0] in HEAVY)
print(json.dumps({"status": status, "heavy": heavy}))
"""


def _commands() -> list[str]:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return list(sub.choices)


def _heavy_after(*argv: str) -> dict:
    code = f"HEAVY = {HEAVY!r}\n{CHILD}"
    out = subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=ROOT, timeout=120, check=False
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_rotor_imports_no_heavy_package():
    code = "import json, sys, rotor; print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in %r)))"
    out = subprocess.run([sys.executable, "-c", code % (HEAVY,)], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


@pytest.mark.parametrize("argv", [["--help"], ["presets"], ["presets", "--json"], ["--version"]], ids=" ".join)
def test_a_light_command_imports_no_heavy_package(argv):
    r = _heavy_after(*argv)
    assert r["status"] in (0, None), r
    assert r["heavy"] == [], f"rotor {' '.join(argv)} imported {r['heavy']}"


HELPS_CHILD = r"""
import contextlib, io, json, sys
from rotor.cli.app import main
rows = {}
for command in sys.argv[1:]:
    before = {m for m in sys.modules if m.split(".")[0] in HEAVY}
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            status = main([command, "--help"])
    except SystemExit as e:
        status = e.code
    rows[command] = {"status": status, "heavy": sorted({m for m in sys.modules if m.split(".")[0] in HEAVY} - before)}
print(json.dumps(rows))
"""


@pytest.fixture(scope="module")
def helps() -> dict:
    """``rotor COMMAND --help`` of every command, one after the other in one child process:
    the heavy modules each one imported (those an earlier one imported already are not
    counted again: that one's test fails)."""
    code = f"HEAVY = {HEAVY!r}\n{HELPS_CHILD}"
    out = subprocess.run(
        [sys.executable, "-c", code, *_commands()], capture_output=True, text=True, cwd=ROOT, timeout=120, check=False
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("command", _commands())
def test_a_commands_help_imports_no_heavy_package(command, helps):
    r = helps[command]
    assert r["status"] == 0, r
    assert r["heavy"] == [], f"rotor {command} --help imported {r['heavy']}"


def test_the_checks_see_a_heavy_import():
    """The check above can fail: a command that computes does import JAX."""
    r = _heavy_after("info", "4chn15", "--json")
    assert r["status"] == 0 and "jax" in r["heavy"] and "equinox" in r["heavy"]


def test_analysing_a_log_imports_no_jax(tmp_path):
    """A log's analysis is NumPy (and scipy's splines): ``rotor analyze`` of tooth times and of
    a sampled wheel signal with its pressure imports neither JAX nor equinox (their import is
    most of a warm command's time); with an engine file it does."""
    rng = np.random.default_rng(3)
    w = 2 * np.pi * 1500 / 60
    ang = 0.37 + 2 * np.pi * np.arange(16)[:, None] + 2 * np.pi / 60 * np.arange(58)[None, :]
    teeth = tmp_path / "teeth.csv"
    np.savetxt(teeth, (ang.ravel() + 0.02 * np.sin(ang.ravel() / 2)) / w, fmt="%.12g")
    t = np.arange(0.0, 0.5, 1e-5)
    phi = w * t + 0.3
    square = (np.mod(phi / (2 * np.pi / 60), 1.0) < 0.5) & (np.mod(np.floor(phi / (2 * np.pi / 60)), 60) < 58)
    pressure = 1.0 + np.exp(-(((np.mod(phi, 4 * np.pi) - 2 * np.pi) / 0.5) ** 2)) + 0.001 * rng.standard_normal(t.size)
    sampled = tmp_path / "wheel.csv"
    np.savetxt(
        sampled,
        np.c_[t, pressure, square * 5.0],
        delimiter=",",
        header="time,pressure_v,encoder_v",
        comments="",
        fmt="%.8g",
    )
    for argv in (
        ["analyze", str(teeth), "--wheel", "60-2", "--json"],
        ["analyze", str(sampled), "--wheel", "60-2", "--columns", "time,pressure_v,encoder_v", "--json"],
    ):
        r = _heavy_after(*argv)
        assert r["status"] in (0, None), r
        assert not {"jax", "equinox"} & {m.split(".")[0] for m in r["heavy"]}, f"rotor {' '.join(argv)}: {r['heavy']}"
    r = _heavy_after("analyze", str(teeth), "--wheel", "60-2", "--engine", "4chn15", "--tdc-deg", "0", "--json")
    assert r["status"] in (0, None) and "jax" in r["heavy"]  # the check can fail


TRACING_CHILD = r"""
import json, sys
import jax
traced = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, secs, **kw: traced.append(kw.get("fun_name")) if event.endswith("jaxpr_trace_duration") else None
)
from rotor.cli.app import main
status = main(sys.argv[1:])
print(json.dumps({"status": status, "traced": traced}))
"""


@pytest.mark.parametrize("argv", [["steady", "4chn15"], ["loads", "4chn15"], ["modes", "mwm6"]], ids=" ".join)
def test_a_warm_command_traces_nothing(argv):
    """A second call of a command (its programs kept by the first, its tables kept) traces no
    JAX function: neither a kernel nor an operation on a concrete array, each of which
    would trace and lower a program of its own in every process."""
    runs = []
    for _ in range(2):
        out = subprocess.run(
            [sys.executable, "-c", TRACING_CHILD, *argv], capture_output=True, text=True, cwd=ROOT, timeout=300
        )
        assert out.returncode == 0, out.stderr[-2000:]
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    assert runs[1]["status"] in (0, None)
    assert runs[1]["traced"] == [], f"rotor {' '.join(argv)} traced {runs[1]['traced']} on a warm call"


def test_a_steady_state_imports_no_adaptive_solver():
    """A steady state, ``closed`` and ``grid`` need no diffrax (the adaptive methods' solver,
    0.7 s to import): the modules of ``rotor steady`` leave it out, and so does the adaptive
    integrators' module, which imports it where a solve is traced (a process that runs a
    kept program never does: tests/project/test_programs.py)."""
    code = (
        "import json, sys, importlib\n"
        "for name in sys.argv[1:]:\n"
        "    importlib.import_module(name)\n"
        "if 'rotor.dynamics.adaptive' in sys.argv:\n"
        "    import rotor\n"
        "    rotor.simulate(rotor.load_engine('4chn15'), cycles=1, method='angle', rtol=1e-5)\n"
        "print(json.dumps('diffrax' in sys.modules))"
    )

    def diffrax_after(*modules):
        env = dict(os.environ, ROTOR_PROGRAM_CACHE="off")
        out = subprocess.run(
            [sys.executable, "-c", code, *modules], capture_output=True, text=True, check=True, env=env
        )
        return json.loads(out.stdout.strip().splitlines()[-1])

    assert not diffrax_after("rotor.cli.run", "rotor.dynamics.steady", "rotor.dynamics.sweep")
    assert diffrax_after("rotor.dynamics.adaptive")  # traced: imported


def test_presets_lists_the_engines_load_engine_builds():
    from rotor.cli.engine import preset_listing

    assert preset_listing() == {name: rotor.load_engine(name).name for name in rotor.preset_names()}


def test_float64_is_on_once_rotor_computes_however_jax_is_imported():
    """A module of rotor that computes switches float64 on, whether JAX was imported before
    rotor, after it, or through it."""
    for code in (
        "import rotor, jax.numpy as jnp; rotor.Engine; print(jnp.zeros(1).dtype)",
        "import jax.numpy as jnp, rotor; rotor.steady_state; print(jnp.zeros(1).dtype)",
        "import rotor.engine.model; from jax import numpy as jnp; print(jnp.zeros(1).dtype)",
        "import rotor.cycles, jax.numpy as jnp; print(jnp.zeros(1).dtype)",
    ):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        assert out.stdout.strip() == "float64", code


def test_the_cache_waits_for_jax(tmp_path):
    """``enable_compilation_cache`` before JAX is imported does not import it, and the cache
    is set once rotor imports JAX; with JAX imported already it is set at once."""
    env = {"ROTOR_COMPILATION_CACHE": str(tmp_path / "c"), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    report = (
        "print(json.dumps([used, before, jax.config.jax_compilation_cache_dir, "
        "jax.config.jax_persistent_cache_min_compile_time_secs]))"
    )
    for code in (
        "import json, sys, rotor; used = rotor.enable_compilation_cache(); before = 'jax' in sys.modules; "
        "rotor.Engine; import jax; " + report,
        "import json, sys, jax, rotor; before = False; used = rotor.enable_compilation_cache(); " + report,
    ):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
        used, before, folder, threshold = json.loads(out.stdout)
        assert used == folder == str(tmp_path / "c") and not before and threshold == 0.1, code


def _run_kept(tmp_path, *argv):
    code = f"HEAVY = {HEAVY!r}\n" + CHILD.replace("print(json.dumps(", "sys.stdout.flush(); print('\\n' + json.dumps(")
    env = dict(os.environ, ROTOR_OUTPUT_CACHE=str(tmp_path / "outputs"))
    out = subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=ROOT, env=env, timeout=300
    )
    assert out.returncode == 0, out.stderr[-2000:]
    text, _, tail = out.stdout.rpartition("\n\n")
    return text, json.loads(tail)


@pytest.mark.parametrize("argv", [["table", "4chn15", "--format", "csv"], ["info", "4chn15", "--json"]], ids=" ".join)
def test_a_repeated_table_or_info_reads_its_kept_output_without_jax(tmp_path, argv):
    first, r1 = _run_kept(tmp_path, *argv)
    assert r1["status"] in (0, None) and "jax" in r1["heavy"]
    again, r2 = _run_kept(tmp_path, *argv)
    assert r2["status"] in (0, None) and r2["heavy"] == [], r2
    assert again == first and len(first) > 200


def test_a_changed_engine_file_or_option_is_computed_afresh(tmp_path):
    """The kept output is keyed on the engine file's bytes and the options: a changed
    speed in the file, or another --rpm, computes again (and prints other figures)."""
    engine = tmp_path / "e.toml"
    engine.write_text((ROOT / "rotor" / "presets" / "4chn15.toml").read_text(encoding="utf-8"), encoding="utf-8")
    first, _ = _run_kept(tmp_path, "info", str(engine), "--json")
    assert json.loads(first)["rpm"] == 1250
    text, count = re.subn(r"(?m)^rpm = 1250$", "rpm = 1350", engine.read_text(encoding="utf-8"))
    assert count == 1
    engine.write_text(text, encoding="utf-8")
    changed, r = _run_kept(tmp_path, "info", str(engine), "--json")
    assert "jax" in r["heavy"] and json.loads(changed)["rpm"] == 1350
    other, r = _run_kept(tmp_path, "info", str(engine), "--json", "--rpm", "900")
    assert "jax" in r["heavy"] and json.loads(other)["rpm"] == 900


def test_the_rotor_command_exits_without_the_interpreters_teardown(tmp_path):
    """The ``rotor`` command (:func:`rotor.cli.command`) ends the process once the exit
    handlers have run, with its status and its whole output, without the teardown (an
    object's finaliser at teardown does not run). Where an exit handler was registered
    before it (it would be skipped), and where ``main`` is called from Python, the process
    ends as usual."""
    child = (
        "import atexit, sys\n"
        "import rotor.cli.app as app\n"
        "class Finalised:\n"
        "    def __del__(self):\n"
        "        print('torn down', flush=True)\n"
        "kept = Finalised()\n"
        "how = sys.argv.pop(1)\n"
        "sys.argv = ['rotor', *sys.argv[1:]]\n"
        "def later(argv=None, real=app.main):\n"
        "    atexit.register(lambda: print('exit handler ran', flush=True))\n"
        "    return real(argv)\n"
        "if how == 'handler first':\n"
        "    atexit.register(lambda: print('early handler ran', flush=True))\n"
        "app.main = later\n"
        "sys.exit(app.main() if how == 'main' else app.command())\n"
    )
    cases = (
        ("command", ["presets"], 0),
        ("command", ["steady", "no-such-engine"], 2),
        ("handler first", ["presets"], 0),
        ("main", ["presets"], 0),
    )
    for how, argv, status in cases:
        out = subprocess.run([sys.executable, "-c", child, how, *argv], capture_output=True, text=True, timeout=120)
        assert out.returncode == status, (how, out.stderr)
        assert "exit handler ran" in out.stdout, how
        assert ("torn down" in out.stdout) == (how != "command"), (how, out.stdout)
        assert ("early handler ran" in out.stdout) == (how == "handler first"), how
        if status == 0:
            assert "4chn15" in out.stdout
        else:
            assert "rotor: error: no-such-engine" in out.stderr


def test_the_command_notes_its_programs_and_reads_them_ahead_next_time(tmp_path):
    """A command that computes notes the kept programs it used (one file per command line,
    naming programs that exist); its next run, which reads them ahead, prints the same; a
    command that needs no JAX notes nothing."""
    env = dict(
        os.environ,
        ROTOR_COMPILATION_CACHE=str(tmp_path / "jax"),
        ROTOR_TABLE_CACHE=str(tmp_path / "tables"),
        ROTOR_OUTPUT_CACHE="off",
    )

    def rotor_command(*argv):
        out = subprocess.run([sys.executable, "-m", "rotor.cli", *argv], env=env, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        return out.stdout

    folder = tmp_path / "jax" / "rotor-programs"
    first = rotor_command("steady", "4chn15")
    (noted,) = folder.glob("recent-*.txt")
    names = noted.read_text().split()
    assert names and all((folder / name).is_file() for name in names)
    again = rotor_command("steady", "4chn15")
    assert again.split("wall time")[0] == first.split("wall time")[0] and len(first) > 500
    rotor_command("presets")
    assert list(folder.glob("recent-*.txt")) == [noted]
