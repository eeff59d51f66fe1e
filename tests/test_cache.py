"""The persistent compilation cache: on by default, movable, and off on request."""

import json
import os
import subprocess
import sys

CODE = """
import json, jax, rotor
print(json.dumps({"dir": jax.config.jax_compilation_cache_dir}))
"""


def _run(env_value, tmp_path):
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "xdg"))
    env.pop("ROTOR_COMPILATION_CACHE", None)
    if env_value is not None:
        env["ROTOR_COMPILATION_CACHE"] = env_value
    out = subprocess.run([sys.executable, "-c", CODE], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])["dir"]


def test_cache_default_path_env_path_and_off(tmp_path):
    assert _run(None, tmp_path) == str(tmp_path / "xdg" / "rotor" / "jax")
    assert _run(str(tmp_path / "mine"), tmp_path) == str(tmp_path / "mine")
    assert (tmp_path / "mine").is_dir()
    assert _run("off", tmp_path) is None


def test_a_compiled_kernel_is_reused_by_the_next_process(tmp_path):
    code = (
        "import jax, rotor; e = rotor.load_engine('4chn15'); "
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
