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


# ---------------------------------------------------------------------- the engines' tables
def _tables(monkeypatch, tmp_path):
    """Tables kept in a folder of the test's own, as after rotor.enable_compilation_cache()."""
    import rotor.cache as cache
    from rotor.dynamics import crank_train as ct

    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(tmp_path / "tables"))
    monkeypatch.setattr(cache, "_TABLES_ON", [True])
    ct.clear_table_cache()
    return cache, ct


def _built(monkeypatch, ct):
    """Counts the calls of the table builder."""
    calls = []
    real = ct._build
    monkeypatch.setattr(ct, "_build", lambda *a: calls.append(a) or real(*a))
    return calls


def test_an_engines_tables_are_read_back_by_the_next_process_bit_for_bit(monkeypatch, tmp_path):
    """Built and kept once; after the process forgets them (a new process), read back from the
    folder, the builder not called, every array bit for bit; the results the same."""
    import equinox as eqx
    import numpy as np

    import rotor

    cache, ct = _tables(monkeypatch, tmp_path)
    engine = rotor.load_engine("mwm6")
    calls = _built(monkeypatch, ct)
    first = rotor.crank_train(engine)
    delta = float(rotor.steady_state(engine).delta)
    assert len(calls) == 1 and len(list((tmp_path / "tables").glob("rotor-tables-*.npz"))) == 1
    ct.clear_table_cache()
    again = rotor.crank_train(engine)
    assert len(calls) == 1, "read back, not built"
    for name in ("values", "slopes", "imep_motored_pa", "imep_combustion_pa", "mean_inertia", "work"):
        np.testing.assert_array_equal(np.asarray(getattr(again, name)), np.asarray(getattr(first, name)), name)
    ct.clear_table_cache()
    assert float(rotor.steady_state(engine).delta) == delta
    # another fidelity, another engine, another crankshaft inertia: tables of their own
    rotor.crank_train(engine, "constant")
    rotor.crank_train(rotor.load_engine("4chn15"))
    heavy = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, engine.crankshaft.inertia_kgm2 * 3)
    ct.clear_table_cache()
    built = rotor.crank_train(heavy)
    ct.clear_table_cache()
    np.testing.assert_array_equal(np.asarray(rotor.crank_train(heavy).values), np.asarray(built.values))
    assert float(built.mean_inertia) > float(first.mean_inertia) + 1.9 * float(engine.crankshaft.inertia_kgm2)
    assert len(calls) == 4 and len(list((tmp_path / "tables").glob("rotor-tables-*.npz"))) == 4


def test_a_damaged_or_foreign_entry_is_built_afresh(monkeypatch, tmp_path):
    """A cut-off file, one copied under another engine's name, or one kept by another version
    of rotor's source is a miss: the tables are built again and the entry replaced."""
    import rotor

    cache, ct = _tables(monkeypatch, tmp_path)
    a, b = rotor.load_engine("4chn15"), rotor.load_engine("mwm6")
    calls = _built(monkeypatch, ct)
    rotor.crank_train(a), rotor.crank_train(b)
    (pa, pb) = sorted((tmp_path / "tables").glob("rotor-tables-*.npz"), key=lambda p: p.stat().st_mtime_ns)
    raw = pa.read_bytes()
    pa.write_bytes(raw[: len(raw) // 2])
    ct.clear_table_cache()
    rotor.crank_train(a)
    assert len(calls) == 3 and pa.read_bytes() == raw  # built again, kept whole again
    pb.write_bytes(raw)  # engine a's tables under engine b's name
    ct.clear_table_cache()
    assert rotor.crank_train(b).values.shape[1] == 3 + 6 and len(calls) == 4
    monkeypatch.setattr(cache, "_FINGERPRINT", [b"another version of rotor"])
    ct.clear_table_cache()
    rotor.crank_train(a)
    assert len(calls) == 5


def test_tables_are_kept_only_where_asked_and_no_more_than_the_cap(monkeypatch, tmp_path):
    """Off with ROTOR_TABLE_CACHE=off and before enable_compilation_cache(); at most
    TABLE_FILES entries (the newest), no other file of the folder touched; a refused engine's
    tables never kept."""
    import equinox as eqx
    import pytest

    import rotor

    cache, ct = _tables(monkeypatch, tmp_path)
    folder = tmp_path / "tables"
    folder.mkdir()
    (folder / "mine.txt").write_text("the user's own")
    monkeypatch.setattr(cache, "TABLE_FILES", 2)
    engine = rotor.load_engine("4chn15")
    for k in range(3):
        rotor.crank_train(eqx.tree_at(lambda e: e.geometry.bore_m, engine, engine.geometry.bore_m * (1 + 0.01 * k)))
    assert len(list(folder.glob("rotor-tables-*.npz"))) == 2 and (folder / "mine.txt").read_text() == "the user's own"
    bad = eqx.tree_at(lambda e: e.masses.reciprocating_kg, engine, -1e6)
    with pytest.raises(rotor.EngineError):
        rotor.crank_train(bad)
    assert len(list(folder.glob("rotor-tables-*.npz"))) == 2
    monkeypatch.setenv("ROTOR_TABLE_CACHE", "off")
    assert cache.table_folder() is None
    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(folder))
    monkeypatch.setattr(cache, "_TABLES_ON", [])
    assert cache.table_folder() is None
