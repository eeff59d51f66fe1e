"""The persistent compilation cache: untouched by `import rotor`, switched on by the `rotor`
command and by `rotor.enable_compilation_cache()`, movable, and off on request."""

import json
import os
import subprocess
import sys

CODE = """
import json, jax, rotor
before = jax.config.jax_compilation_cache_dir
used = rotor.enable_compilation_cache()
print(json.dumps({"before": before, "dir": jax.config.jax_compilation_cache_dir, "used": used}))
"""


def _env(tmp_path, env_value=None):
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "xdg"))
    env.pop("ROTOR_COMPILATION_CACHE", None)
    if env_value is not None:
        env["ROTOR_COMPILATION_CACHE"] = env_value
    return env


def _run(env_value, tmp_path):
    out = subprocess.run(
        [sys.executable, "-c", CODE], env=_env(tmp_path, env_value), capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_leaves_the_cache_alone_and_enable_switches_it_on(tmp_path):
    r = _run(None, tmp_path)
    assert r["before"] is None, "import rotor must not set JAX's compilation cache"
    assert r["dir"] == r["used"] == str(tmp_path / "xdg" / "rotor" / "jax")
    r = _run(str(tmp_path / "mine"), tmp_path)
    assert r["used"] == str(tmp_path / "mine") and (tmp_path / "mine").is_dir()
    r = _run("off", tmp_path)
    assert r["used"] is None and r["dir"] is None


def test_the_command_switches_the_cache_on(tmp_path):
    env = _env(tmp_path)
    subprocess.run(
        [sys.executable, "-m", "rotor.cli", "info", "4chn15", "--json"], env=env, check=True, capture_output=True
    )
    assert (tmp_path / "xdg" / "rotor" / "jax").is_dir()
    off = tmp_path / "off"
    env = dict(_env(off), ROTOR_COMPILATION_CACHE="off")
    subprocess.run(
        [sys.executable, "-m", "rotor.cli", "info", "4chn15", "--json"], env=env, check=True, capture_output=True
    )
    assert not (off / "xdg").exists()


def test_a_compiled_kernel_is_reused_by_the_next_process(tmp_path):
    code = (
        "import jax, rotor; rotor.enable_compilation_cache(); e = rotor.load_engine('4chn15'); "
        "jax.block_until_ready(rotor.steady_state(e, grid_deg=2.0).omega)"
    )
    env = dict(os.environ, ROTOR_COMPILATION_CACHE=str(tmp_path / "c"))
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    written = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "c").glob("*-cache")}
    assert any("_closed_steady" in n for n in written), written
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    again = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "c").glob("*-cache")}
    # every executable of the first process read back, none compiled and written again (a
    # small eager operation may join the cache when a loaded machine makes its compile
    # cross the 0.1 s threshold: new names are allowed, rewritten ones are not)
    assert {name: again[name] for name in written} == written


COUNT_PROGRAMS = """
import json, sys
import jax.monitoring
counts = {"requests": 0, "hits": 0}
def seen(event, **_):
    if event == "/jax/compilation_cache/compile_requests_use_cache":
        counts["requests"] += 1
    elif event == "/jax/compilation_cache/cache_hits":
        counts["hits"] += 1
jax.monitoring.register_event_listener(seen)
from rotor.cli.app import main
sys.argv[0] = "rotor"
code = main()  # as the command runs: every program written to the cache, however quick to compile
print(json.dumps(counts), file=sys.stderr)
sys.exit(code)
"""


def test_a_second_process_finds_every_program_of_a_command_in_the_cache(tmp_path):
    """The adaptive angle-domain run holds no host callback (diffrax's checks of its save
    points are made when it traces), so the persistent cache stores every program it
    compiles: a second process compiles nothing."""
    env = dict(os.environ, ROTOR_COMPILATION_CACHE=str(tmp_path / "c"))
    argv = [sys.executable, "-c", COUNT_PROGRAMS, "simulate", "4chn15", "--cycles", "3", "--method", "angle", "--quiet"]
    counts = []
    for _ in range(2):
        run = subprocess.run(argv, env=env, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        counts.append(json.loads(run.stderr.strip().splitlines()[-1]))
    first, second = counts
    assert first["requests"] > 0 and first["hits"] < first["requests"]
    assert second["requests"] == first["requests"]
    assert second["hits"] == second["requests"], f"programs compiled again in the second process: {second}"
