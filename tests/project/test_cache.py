"""The persistent compilation cache: untouched by `import rotor`, switched on by the `rotor`
command and by `rotor.enable_compilation_cache()`, movable, and off on request."""

import json
import os
import subprocess
import sys

import conftest
import jax
import pytest

import rotor

sys.path.insert(0, str(conftest.ROOT / "benchmarks"))
from cache_hits import twice  # noqa: E402

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
    # JAX's cache itself: no kept programs (tests/project/test_programs.py), which bypass it
    env = dict(os.environ, ROTOR_COMPILATION_CACHE=str(tmp_path / "c"), ROTOR_PROGRAM_CACHE="off")
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    written = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "c").glob("*-cache")}
    assert any("_closed_steady" in n for n in written), written
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    again = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "c").glob("*-cache")}
    # every executable of the first process read back, none compiled and written again (a
    # small eager operation may join the cache when a loaded machine makes its compile
    # cross the 0.1 s threshold: new names are allowed, rewritten ones are not)
    assert {name: again[name] for name in written} == written


def test_a_second_process_finds_every_program_of_a_command_in_the_cache():
    """The adaptive angle-domain run holds no host callback (diffrax's checks of its save
    points are made when it traces), so the persistent cache stores every program it
    compiles: a second process compiles nothing. Both build the engine's tables (none kept
    on disk), so that both run the same programs whatever the suite kept before
    (``benchmarks/cache_hits.py`` runs every command so)."""
    first, second = twice(["simulate", "4chn15", "--cycles", "3", "--method", "angle", "--quiet"])
    assert first["requests"] > 0 and first["hits"] < first["requests"]
    assert second["requests"] == first["requests"]
    assert second["hits"] == second["requests"], f"programs compiled again in the second process: {second}"


# ---------------------------------------------------------------------- the engines' tables
TABLES_CHILD = """
import json, sys, jax, numpy as np, equinox as eqx, rotor
rotor.enable_compilation_cache()
traced = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, seconds, fun_name="?", **_: traced.append(fun_name) if event.endswith("jaxpr_trace_duration") else None
)
engine = rotor.load_engine("mwm6")
if sys.argv[1] == "heavy":
    engine = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, engine.crankshaft.inertia_kgm2 * 3)
train = rotor.crank_train(engine)
print(json.dumps({"built": "_build" in traced, "values": np.asarray(train.values).tobytes().hex()[:4096],
                  "mean_inertia": float(train.mean_inertia), "delta": float(rotor.steady_state(engine).delta)}))
"""


def _tables_child(tmp_path, variant="plain"):
    env = dict(os.environ, ROTOR_TABLE_CACHE=str(tmp_path / "tables"))
    out = subprocess.run(
        [sys.executable, "-c", TABLES_CHILD, variant], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_an_engines_tables_are_read_back_by_the_next_process_bit_for_bit(tmp_path):
    """The first process builds and keeps them; the next reads them back (the table builder not
    traced), bit for bit, and solves the same; another crankshaft inertia reads the same
    entry, its I(θ) shifted by the difference."""
    import pytest

    import rotor

    first = _tables_child(tmp_path)
    assert first["built"] and len(list((tmp_path / "tables").glob("rotor-tables-*.npz"))) == 1
    again = _tables_child(tmp_path)
    assert not again["built"] and again == {**first, "built": False}
    heavy = _tables_child(tmp_path, "heavy")  # three times the crankshaft inertia
    crankshaft = float(rotor.load_engine("mwm6").crankshaft.inertia_kgm2)
    assert not heavy["built"]
    assert heavy["mean_inertia"] == pytest.approx(first["mean_inertia"] + 2 * crankshaft, rel=1e-12)
    assert len(list((tmp_path / "tables").glob("rotor-tables-*.npz"))) == 1


def _entries(folder):
    return sorted(folder.glob("rotor-tables-*.npz"), key=lambda p: p.stat().st_mtime_ns)


def test_a_damaged_or_foreign_entry_is_built_afresh(monkeypatch, tmp_path):
    """A cut-off file, or one copied under another engine's name, is a miss: the tables are
    built again (the same as built without the folder) and the entry replaced whole."""
    import numpy as np

    import rotor
    from rotor.dynamics import crank_train as ct

    monkeypatch.setenv("ROTOR_TABLE_CACHE", "off")
    ct.clear_table_cache()
    a, b = rotor.load_engine("4chn15"), rotor.load_engine("mwm6")
    want = {e.name: np.asarray(rotor.crank_train(e).values) for e in (a, b)}
    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(tmp_path / "tables"))
    rotor.enable_compilation_cache()  # on in the suite already: the tables are kept
    for e in (a, b):
        ct.clear_table_cache()
        rotor.crank_train(e)
    pa, pb = _entries(tmp_path / "tables")
    raw = pa.read_bytes()
    pa.write_bytes(raw[: len(raw) // 2])
    ct.clear_table_cache()
    np.testing.assert_array_equal(np.asarray(rotor.crank_train(a).values), want[a.name])
    assert pa.read_bytes() == raw  # kept whole again
    pb.write_bytes(raw)  # engine a's tables under engine b's name
    ct.clear_table_cache()
    np.testing.assert_array_equal(np.asarray(rotor.crank_train(b).values), want[b.name])
    assert pb.read_bytes() != raw


def test_tables_are_kept_only_where_asked_and_no_more_than_the_cap(monkeypatch, tmp_path):
    """At most TABLE_FILES entries (the newest), no other file of the folder touched; off with
    ROTOR_TABLE_CACHE=off, and in a process that has not switched the compilation cache on."""
    import equinox as eqx

    import rotor
    import rotor.cache as cache

    folder = tmp_path / "tables"
    folder.mkdir()
    (folder / "mine.txt").write_text("the user's own")
    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(folder))
    monkeypatch.setattr(cache, "TABLE_FILES", 2)
    rotor.enable_compilation_cache()
    engine = rotor.load_engine("4chn15")
    for k in range(3):
        rotor.crank_train(eqx.tree_at(lambda e: e.geometry.bore_m, engine, engine.geometry.bore_m * (1 + 0.01 * k)))
    assert len(_entries(folder)) == 2 and (folder / "mine.txt").read_text() == "the user's own"
    monkeypatch.setenv("ROTOR_TABLE_CACHE", "off")
    assert cache.table_folder() is None
    code = "import json, rotor.cache as c; print(json.dumps(str(c.table_folder())))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == "None"


def _kept_then_respoilt(monkeypatch, tmp_path, spoil):
    """δ of an engine with its tables built (no folder), then kept in a folder and read
    back there after ``spoil`` changed the entry's arrays (name → array, the stored key and
    check left as they were): (δ built, δ read back after the change, whether the entry is
    whole again: as first written)."""
    import numpy as np

    from rotor.dynamics import crank_train as ct

    monkeypatch.setenv("ROTOR_TABLE_CACHE", "off")
    ct.clear_table_cache()
    want = float(rotor.steady_state(rotor.load_engine("4chn15")).delta)
    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(tmp_path / "tables"))
    rotor.enable_compilation_cache()  # on in the suite already: the tables are kept
    ct.clear_table_cache()
    rotor.crank_train(rotor.load_engine("4chn15"))
    (entry,) = _entries(tmp_path / "tables")
    raw = entry.read_bytes()
    with np.load(entry) as z:
        fields = {name: z[name] for name in z.files}
    spoil(fields)
    with open(entry, "wb") as f:
        np.savez(f, **fields)
    ct.clear_table_cache()
    got = float(rotor.steady_state(rotor.load_engine("4chn15")).delta)
    return want, got, entry.read_bytes() == raw


def test_a_changed_tables_entry_is_built_afresh_and_gives_the_same_delta(monkeypatch, tmp_path):
    """An entry whose numbers were changed (its stored key left as it was) is not used: the
    tables are built again, δ is as built, and the entry is kept whole again."""

    def spoil(fields):
        fields["work"] *= 3.0  # the torques' work over the cycle: δ about four times as large

    want, got, whole = _kept_then_respoilt(monkeypatch, tmp_path, spoil)
    assert got == want and whole


def test_a_tables_entry_holding_nan_is_built_afresh_not_blamed_on_the_engine(monkeypatch, tmp_path):
    import numpy as np

    def spoil(fields):
        fields["values"][100, 0] = np.nan  # I(θ) at one angle

    want, got, whole = _kept_then_respoilt(monkeypatch, tmp_path, spoil)
    assert got == want and whole


def test_tables_holding_nan_are_not_kept(monkeypatch, tmp_path):
    import numpy as np

    from rotor import cache

    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(tmp_path / "tables"))
    rotor.enable_compilation_cache()
    cache.keep_tables("k", {"a": np.array([1.0, np.nan])})
    assert _entries(tmp_path / "tables") == []
    cache.keep_tables("k", {"a": np.array([1.0, 2.0])})
    np.testing.assert_array_equal(cache.kept_tables("k")["a"], [1.0, 2.0])


def test_tables_are_neither_read_nor_written_in_a_folder_others_can_write(monkeypatch, tmp_path, capfd):
    import numpy as np

    from rotor import cache

    mine, shared = tmp_path / "mine", tmp_path / "shared"
    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(mine))
    rotor.enable_compilation_cache()
    cache.keep_tables("k", {"a": np.arange(3.0)})
    (entry,) = _entries(mine)
    shared.mkdir()
    (shared / entry.name).write_bytes(entry.read_bytes())  # a whole, valid entry
    shared.chmod(0o777)
    monkeypatch.setenv("ROTOR_TABLE_CACHE", str(shared))
    capfd.readouterr()
    assert cache.kept_tables("k") is None
    cache.keep_tables("other", {"a": np.arange(4.0)})
    assert cache.kept_tables("k") is None
    assert [p.name for p in shared.iterdir()] == [entry.name]
    (line,) = capfd.readouterr().err.splitlines()
    assert str(shared) in line and "chmod go-w" in line and "ROTOR_TABLE_CACHE" in line


def test_jaxs_cache_is_not_switched_on_in_a_folder_others_can_write(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o775)
    out = subprocess.run(
        [sys.executable, "-c", CODE], env=_env(tmp_path, str(shared)), capture_output=True, text=True, check=True
    )
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["used"] is None and r["dir"] is None
    (line,) = out.stderr.strip().splitlines()
    assert line.startswith("rotor: warning: ") and str(shared) in line and "chmod go-w" in line
    assert list(shared.iterdir()) == []
    r = _run(str(tmp_path / "mine"), tmp_path)  # a folder rotor makes is the user's own
    assert r["used"] == str(tmp_path / "mine") and (tmp_path / "mine").stat().st_mode & 0o077 == 0


def test_kept_outputs_are_neither_read_nor_written_in_a_folder_of_another_user(monkeypatch, tmp_path, capfd):
    from rotor.cli import kept

    folder = tmp_path / "outputs"
    monkeypatch.setenv("ROTOR_OUTPUT_CACHE", str(folder))
    key = kept.output_key("info", "4chn15", {})
    kept.keep_output(key, "the output")
    assert kept.kept_output(key) == "the output"
    entry = kept.entry_path(key)
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / entry.name).write_bytes(entry.read_bytes())  # a whole, valid entry
    capfd.readouterr()
    monkeypatch.setenv("ROTOR_OUTPUT_CACHE", str(theirs))
    monkeypatch.setattr(os, "getuid", lambda: os.stat(tmp_path).st_uid + 4242)  # the folder: another user's
    assert kept.entry_path(key) is None and kept.output_key("info", "4chn15", {}) is None
    assert kept.kept_output(key) is None
    kept.keep_output(kept.output_key("info", "4chn15", {"rpm": 900}), "another output")
    assert [p.name for p in theirs.iterdir()] == [entry.name]
    (line,) = capfd.readouterr().err.splitlines()
    assert "owned by another user" in line and "ROTOR_OUTPUT_CACHE" in line


# ---------------------------------------------------------------------- XLA's CPU emitters
EMITTERS_CHILD = (
    "import os, sys, importlib; importlib.import_module(sys.argv[1]); print(os.environ.get('XLA_FLAGS', ''))"
)


def _xla_flags_after_import(xla_flags, module="rotor"):
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    if xla_flags is not None:
        env["XLA_FLAGS"] = xla_flags
    out = subprocess.run(
        [sys.executable, "-c", EMITTERS_CHILD, module], env=env, capture_output=True, text=True, check=True
    )
    return out.stdout.strip()


def test_rotor_chooses_xla_elemental_emitters_unless_the_user_chose():
    """Importing rotor (or the module where rotor imports JAX) adds the elemental-emitter
    option to ``$XLA_FLAGS``, keeps the user's other options, and leaves the option alone
    where the user set it."""
    from rotor.cache import XLA_CPU_FLAG

    assert _xla_flags_after_import(None) == XLA_CPU_FLAG
    assert _xla_flags_after_import(None, "rotor.jaxconfig") == XLA_CPU_FLAG
    assert _xla_flags_after_import("--xla_dump_to=/tmp/x").split() == ["--xla_dump_to=/tmp/x", XLA_CPU_FLAG]
    assert _xla_flags_after_import("--xla_cpu_use_fusion_emitters=true") == "--xla_cpu_use_fusion_emitters=true"


# ---------------------------------------------------------------------- no host callback in a program
_SEEN = {"on": False, "requests": 0, "hits": 0}


def _seen(event, **_):
    if _SEEN["on"]:
        if event == "/jax/compilation_cache/compile_requests_use_cache":
            _SEEN["requests"] += 1
        elif event == "/jax/compilation_cache/cache_hits":
            _SEEN["hits"] += 1


jax.monitoring.register_event_listener(_seen)


def _textbook_flywheel():
    rotor.textbook_flywheel(rotor.load_engine("4chn15"), 0.01, 1250)


def _inertia_for_delta():
    rotor.inertia_for_delta(rotor.load_engine("4chn15"), 0.01, 1250)


def _sweep_with_speed_dependent_friction():
    fr = rotor.Friction(fmep_pa=40e3, fmep_per_speed_pa_s_per_m=2000.0)
    rotor.steady_sweep(
        rotor.prepare(rotor.load_engine("4chn15"), grid_deg=2.0), rpm=[900.0, 1400.0], friction=fr, progress=False
    )


@pytest.mark.parametrize("call", [_textbook_flywheel, _inertia_for_delta, _sweep_with_speed_dependent_friction])
def test_a_public_functions_programs_are_all_stored_in_the_cache(call, monkeypatch):
    """Every program a public function compiles is stored by the persistent cache: run a
    second time with every compiled program dropped from the process, it reads each one
    back. A program holding a host callback (an ``eqx.error_if`` check left in the trace)
    is never stored, and would be compiled again in every process."""
    if conftest.COMPILATION_CACHE is None:
        pytest.skip("the suite runs without the compilation cache (ROTOR_COMPILATION_CACHE=off)")
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")  # JAX's cache itself, not rotor's kept programs
    call()
    jax.clear_caches()
    _SEEN.update(on=True, requests=0, hits=0)
    try:
        call()
    finally:
        _SEEN["on"] = False
    assert _SEEN["requests"] > 0
    assert _SEEN["hits"] == _SEEN["requests"], f"{_SEEN['requests'] - _SEEN['hits']} programs compiled again"
