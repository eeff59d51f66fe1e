"""Kept programs (rotor.programs): a kernel compiled in one process is loaded by the next,
which then neither traces it nor imports its solver's package; the results are the same to
the last bit; a damaged file is a miss; a transformation of the caller's still traces."""

import functools
import json
import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rotor import programs

# a child process: run a steady state and a short adaptive run, report the kernels JAX traced,
# whether diffrax and optimistix were imported, and the results
CHILD = """
import json, sys
import jax
traced = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, secs, **kw: traced.append(kw.get("fun_name")) if event.endswith("jaxpr_trace_duration") else None
)
import numpy as np, rotor
rotor.enable_compilation_cache()
engine = rotor.load_engine("4chn15")
steady = rotor.steady_state(engine, rpm=1500)
run = rotor.simulate(engine, rpm=1500, cycles=2, method="angle", rtol=1e-6)
print(json.dumps({
    "traced": sorted(set(t for t in traced if t)),
    "imported": [m for m in ("diffrax", "optimistix") if m in sys.modules],
    "steady": np.asarray(steady.omega).tolist(),
    "run": np.asarray(run.omega).tolist(),
}))
"""


def _child(tmp_path, programs_env: str) -> dict:
    env = dict(
        os.environ,
        ROTOR_COMPILATION_CACHE=str(tmp_path / "jax"),
        ROTOR_TABLE_CACHE=str(tmp_path / "tables"),
        ROTOR_PROGRAM_CACHE=programs_env,
    )
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_second_process_loads_the_kernels_and_agrees_to_the_bit(tmp_path):
    # traced and compiled as jit does, into JAX's cache
    without = _child(tmp_path, "off")
    assert "angle_run" in without["traced"] and "diffrax" in without["imported"]
    # JAX's cache full: what is kept must still load whole (an executable that JAX read back
    # from its cache cannot be serialized again), and give the same bits
    folder = tmp_path / "programs"
    first = _child(tmp_path, str(folder))
    kept = sorted(folder.glob("rotor-program-*.bin"))
    assert kept and all(p.stat().st_size > 0 for p in kept)
    assert {"_closed_steady", "angle_run"} <= set(first["traced"])
    assert first["steady"] == without["steady"] and first["run"] == without["run"]
    second = _child(tmp_path, str(folder))
    assert "_closed_steady" not in second["traced"] and "angle_run" not in second["traced"]
    assert second["imported"] == [], "a process that runs kept programs needs neither diffrax nor optimistix"
    assert second["steady"] == without["steady"] and second["run"] == without["run"]


@pytest.fixture
def kept_here(tmp_path, monkeypatch):
    """Programs kept in a folder of this test's, forgotten in this process before and after."""
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", str(tmp_path / "programs"))
    programs.clear_programs()
    yield tmp_path / "programs"
    programs.clear_programs()


@programs.kept_program(static_argnames=("power",))
@jax.jit
def _cubic(x, scale, power=3):
    return scale * x**power


def test_a_damaged_program_is_a_miss_and_is_written_again(kept_here):
    x = np.linspace(0.0, 1.0, 5)
    expected = 2.0 * x**3
    np.testing.assert_array_equal(_cubic(x, 2.0), expected)
    (path,) = kept_here.glob("rotor-program-*.bin")
    path.write_bytes(b"not a program")
    programs.clear_programs()
    np.testing.assert_array_equal(_cubic(x, 2.0), expected)
    assert path.stat().st_size > len(b"not a program")


def test_arguments_of_a_new_structure_or_static_value_get_programs_of_their_own(kept_here):
    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    np.testing.assert_array_equal(_cubic(x, 3.0), 3.0 * x**3)  # a new value of a traced number: the same program
    assert len(list(kept_here.glob("*.bin"))) == 1
    np.testing.assert_array_equal(_cubic(x[:3], 2.0), 2.0 * x[:3] ** 3)  # a new shape
    np.testing.assert_array_equal(_cubic(x, 2.0, power=2), 2.0 * x**2)  # a new static value
    assert len(list(kept_here.glob("*.bin"))) == 3


@programs.kept_program(static_argnames=("times",))
@functools.partial(jax.jit, static_argnames=("times",))
def _doubled(x, times):
    for _ in range(times):  # a loop in Python: ``times`` must be static to trace at all
        x = 2.0 * x
    return x


def test_an_argument_named_static_is_static_given_by_position_or_by_name(kept_here):
    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_doubled(x, 3), 8.0 * x)
    assert len(list(kept_here.glob("*.bin"))) == 1  # kept: traced with ``times`` a constant
    np.testing.assert_array_equal(_doubled(x, times=2), 4.0 * x)
    np.testing.assert_array_equal(_doubled(x, 2), 4.0 * x)
    assert len(list(kept_here.glob("*.bin"))) == 3
    assert all(path.stat().st_size > 0 for path in kept_here.glob("*.bin"))


class _Pair:
    """An argument type whose rebuilding turns its leaves into arrays (as some libraries' do)."""

    def __init__(self, a, b):
        self.a, self.b = jnp.asarray(a), jnp.asarray(b)


jax.tree_util.register_pytree_node(_Pair, lambda p: ((p.a, p.b), None), lambda _, leaves: _Pair(*leaves))


def test_an_argument_of_a_registered_pytree_type_is_kept(kept_here):
    x = np.linspace(0.0, 1.0, 5)
    pair = _Pair(x, 2.0 * x)
    np.testing.assert_array_equal(_doubled(pair.a + pair.b, 1), 6.0 * x)

    @programs.kept_program(static_argnames=("times",))
    @functools.partial(jax.jit, static_argnames=("times",))
    def summed(p, times):
        return times * (p.a + p.b)

    np.testing.assert_array_equal(summed(pair, 2), 6.0 * x)
    np.testing.assert_array_equal(summed(pair, times=3), 9.0 * x)
    assert len(list(kept_here.glob("*.bin"))) == 3


def test_a_callers_transformation_traces_the_kernel(kept_here):
    x = jnp.linspace(0.0, 1.0, 5)
    grad = jax.grad(lambda s: jnp.sum(_cubic(x, s)))(2.0)
    np.testing.assert_allclose(grad, np.sum(np.asarray(x) ** 3), rtol=1e-15)
    batched = jax.vmap(lambda s: _cubic(x, s))(jnp.array([1.0, 2.0]))
    np.testing.assert_array_equal(batched[1], 2.0 * np.asarray(x) ** 3)
    assert not kept_here.exists() or not list(kept_here.glob("*.bin"))


def test_a_loop_over_static_values_stops_keeping(kept_here, monkeypatch):
    monkeypatch.setattr(programs, "PROGRAMS_PER_KERNEL", 2)
    x = np.linspace(0.0, 1.0, 4)
    for power in range(1, 6):
        np.testing.assert_array_equal(_cubic(x, 1.0, power=power), x**power)
    assert len(list(kept_here.glob("*.bin"))) == 2


def test_programs_are_off_where_asked(kept_here, monkeypatch):
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")
    assert programs.program_folder() is None
    monkeypatch.delenv("ROTOR_PROGRAM_CACHE")
    folder = programs.program_folder()
    assert folder is not None and folder.name == "rotor-programs"  # in the compilation cache's folder


@programs.kept_program()
@jax.jit
def _reporting(x):
    jax.debug.callback(lambda v: None, x)
    return 2.0 * x


def test_a_program_that_calls_back_into_python_is_not_kept(kept_here):
    x = np.arange(3.0)
    for _ in range(2):  # the second call finds the mark and calls the jitted kernel
        np.testing.assert_array_equal(_reporting(x), 2.0 * x)
    (path,) = kept_here.glob("rotor-program-*.bin")
    assert path.stat().st_size == 0  # marked: compiled in each process, as JAX's cache does


def test_the_oldest_programs_go_past_the_size_cap(kept_here, monkeypatch):
    x = np.linspace(0.0, 1.0, 4)
    _cubic(x, 1.0, power=1)
    (first,) = kept_here.glob("*.bin")
    monkeypatch.setattr(programs, "PROGRAM_BYTES", int(1.5 * first.stat().st_size))
    os.utime(first, ns=(1, 1))  # the oldest
    stranger = kept_here / "notes.txt"
    stranger.write_text("mine")
    _cubic(x, 1.0, power=2)
    assert not first.exists() and len(list(kept_here.glob("*.bin"))) == 1 and stranger.exists()


def test_compiling_programs_in_threads_leaves_jaxs_cache_on(kept_here):
    """A program to keep is compiled without JAX's cache (an executable read back from it
    cannot be serialized again whole); threads doing so at once leave it on after."""
    import threading

    x = np.linspace(0.0, 1.0, 6)
    threads = [threading.Thread(target=_cubic, args=(x, 1.0), kwargs={"power": p}) for p in range(5, 11)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(list(kept_here.glob("*.bin"))) == 6
    asked = []
    jax.monitoring.register_event_listener(
        lambda event, **kw: (
            asked.append(event) if event == "/jax/compilation_cache/compile_requests_use_cache" else None
        )
    )
    jax.block_until_ready(jax.jit(lambda v: jnp.cos(v) * 7.0 - 1.0)(jnp.arange(11.0)))
    assert asked, "JAX's persistent cache is no longer asked"


EIGEN_CHILD = """
import json, sys
import jax, jax.numpy as jnp, numpy as np
traced = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, secs, **kw: traced.append(kw.get("fun_name")) if event.endswith("jaxpr_trace_duration") else None
)
import rotor
from rotor import programs
rotor.enable_compilation_cache()

@programs.kept_program()
@jax.jit
def eigenvalues(a):
    return jnp.linalg.eigvalsh(a)

a = np.array([[2.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 4.0]])
print(json.dumps({"values": np.asarray(eigenvalues(a)).tolist(), "traced": "eigenvalues" in traced}))
"""


def test_a_program_that_calls_lapack_is_kept_and_runs_in_the_next_process(tmp_path):
    """LAPACK's functions are readied by JAX while it lowers a program: a process that loads
    such a program lowers none, and readies them itself before it runs it (unreadied, the
    process would crash)."""
    env = dict(os.environ, ROTOR_COMPILATION_CACHE=str(tmp_path / "jax"), ROTOR_PROGRAM_CACHE=str(tmp_path / "p"))
    runs = []
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", EIGEN_CHILD], env=env, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr[-2000:]
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    a = np.array([[2.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 4.0]])
    assert runs[0]["traced"] and not runs[1]["traced"]  # the second process loaded it
    assert runs[1]["values"] == runs[0]["values"]
    np.testing.assert_allclose(runs[1]["values"], np.linalg.eigvalsh(a), rtol=1e-14)
    (path,) = (tmp_path / "p").glob("rotor-program-*.bin")
    assert path.stat().st_size > 0


class _Tagged:
    """A result whose structure holds an object that another process would not recognise
    (as an equinox module's sentinel for a missing field)."""

    TAG = object()

    def __init__(self, x):
        self.x = x


jax.tree_util.register_pytree_node(_Tagged, lambda b: ((b.x,), _Tagged.TAG), lambda tag, kids: _Tagged(*kids))


@programs.kept_program()
@jax.jit
def _tagged(x):
    return _Tagged(3.0 * x)


def test_a_program_whose_structure_would_not_come_back_is_not_kept(kept_here):
    x = np.arange(3.0)
    for _ in range(2):
        np.testing.assert_array_equal(_tagged(x).x, 3.0 * x)
    (path,) = kept_here.glob("rotor-program-*.bin")
    assert path.stat().st_size == 0


def test_every_kernel_of_an_identification_is_kept(kept_here):
    """A steady state, a closed-form run and the identification of its speed: every kernel
    they compile is kept on disk (none marked as one that cannot be kept), and done again
    with the programs read back from disk (as a new process would), nothing is traced."""
    import rotor

    def work():
        engine = rotor.load_engine("4chn15")
        load = rotor.ConstantLoad(rotor.steady_state(engine, rpm=1250).load_torque_Nm)
        run = rotor.simulate(engine, cycles=4, rpm=1250, load=load, method="closed", progress=False)
        return rotor.identify(engine, run, block_cycles=2)

    first = work()
    kept = sorted(kept_here.glob("rotor-program-*.bin"))
    assert len(kept) >= 4
    assert [p.name for p in kept if p.stat().st_size == 0] == []
    programs.clear_programs()  # forgotten in this process: read back from the folder
    traced: list[str] = []

    def listen(event, duration, **kw):
        if event.endswith("jaxpr_trace_duration"):
            traced.append(str(kw.get("fun_name")))

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        again = work()
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)
    assert traced == []
    np.testing.assert_array_equal(np.asarray(first.imep_pa), np.asarray(again.imep_pa))


def _read_ahead_done():
    import threading

    for thread in threading.enumerate():
        if thread.name == "rotor-read-ahead":
            thread.join()


def _calls(x):
    return _cubic(x, 2.0), _cubic(x, 2.0, power=2), _doubled(x, times=3)


def test_the_programs_of_a_task_are_read_ahead_on_its_next_run(kept_here):
    """What a task used is noted; its next run loads those programs on a thread, and the
    kernels' calls take them from there (their files gone, nothing is compiled again), with
    the same results."""
    x = np.linspace(0.0, 1.0, 5)
    programs.read_ahead("a task")  # its first run: nothing noted yet
    first = _calls(x)
    programs.remember_programs("a task")
    (noted,) = kept_here.glob("recent-*.txt")
    assert len(noted.read_text().split()) == 3
    programs.clear_programs()
    programs.read_ahead("a task")
    _read_ahead_done()
    for path in kept_here.glob("rotor-program-*.bin"):
        path.unlink()
    again = _calls(x)
    programs.remember_programs("a task")
    assert list(kept_here.glob("rotor-program-*.bin")) == []
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)


def test_another_task_reads_nothing_ahead(kept_here):
    x = np.linspace(0.0, 1.0, 5)
    programs.read_ahead("a task")
    _calls(x)
    programs.remember_programs("a task")
    programs.clear_programs()
    programs.read_ahead("another task")
    _read_ahead_done()
    for path in kept_here.glob("rotor-program-*.bin"):
        path.unlink()
    _calls(x)  # compiled and kept again: nothing was loaded ahead
    programs.remember_programs("another task")
    assert len(list(kept_here.glob("rotor-program-*.bin"))) == 3
    assert len(list(kept_here.glob("recent-*.txt"))) == 2


# ---------------------------------------------------------------------- what a kept program must prove
def _entries(folder):
    return sorted(folder.glob("rotor-program-*.bin"), key=lambda p: p.stat().st_mtime_ns)


def test_the_folder_and_its_key_are_the_users_own(kept_here):
    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    key = kept_here / "rotor-program-key"
    assert key.stat().st_size == 32 and key.stat().st_mode & 0o077 == 0
    assert kept_here.stat().st_mode & 0o077 == 0  # made 0700
    (entry,) = _entries(kept_here)
    assert entry.read_bytes().startswith(b"rotor program 2\n")


@pytest.mark.parametrize("mode", [0o770, 0o757, 0o1777], ids=["group-writable", "world-writable", "like /tmp"])
def test_programs_are_neither_read_nor_written_in_a_folder_others_can_write(kept_here, mode, capfd, monkeypatch):
    """A folder others can write: its programs (here, whole ones with their key, copied from
    a folder of the user's own) are not loaded, nothing is written there, and rotor says
    once, in one line, why and what to do."""
    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    shared = kept_here.parent / f"shared-{mode:o}"
    shared.mkdir()
    for path in kept_here.iterdir():
        (shared / path.name).write_bytes(path.read_bytes())
    key = shared / "rotor-program-key"
    if key.exists():
        key.chmod(0o600)
    before = {p.name: p.read_bytes() for p in shared.iterdir()}
    shared.chmod(mode)
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", str(shared))
    programs.clear_programs()
    capfd.readouterr()

    loaded = []

    def load(*args, **kwargs):
        loaded.append(args)
        raise AssertionError("a program was loaded from a folder others can write")

    monkeypatch.setattr(programs.serialize_executable, "deserialize_and_load", load)
    for power in (3, 3, 2):
        np.testing.assert_array_equal(_cubic(x, 2.0, power=power), 2.0 * x**power)
    programs.read_ahead("a task")
    programs.remember_programs("a task")
    assert loaded == []
    assert {p.name: p.read_bytes() for p in shared.iterdir()} == before
    assert programs.program_folder() is None
    lines = capfd.readouterr().err.splitlines()
    assert len(lines) == 1, lines
    assert str(shared) in lines[0] and "writable by" in lines[0] and "chmod go-w" in lines[0]
    assert "ROTOR_PROGRAM_CACHE" in lines[0]


def test_programs_are_not_kept_in_a_folder_of_another_user(kept_here, capfd, monkeypatch):
    # the folder (made by this process) belongs to this uid: the process seen as another user's
    monkeypatch.setattr(os, "getuid", lambda: os.stat(kept_here.parent).st_uid + 4242)
    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    assert _entries(kept_here) == []
    (line,) = capfd.readouterr().err.splitlines()
    assert "owned by another user" in line and "ROTOR_PROGRAM_CACHE" in line


@pytest.mark.parametrize("spoil", ["readable by others", "a link", "not a key"])
def test_a_key_that_is_not_rotors_own_is_not_used(kept_here, spoil, capfd):
    x = np.linspace(0.0, 1.0, 5)
    kept_here.mkdir()
    key = kept_here / "rotor-program-key"
    if spoil == "readable by others":
        key.write_bytes(bytes(32))
        key.chmod(0o644)
    elif spoil == "a link":
        (kept_here.parent / "elsewhere").write_bytes(bytes(32))
        key.symlink_to(kept_here.parent / "elsewhere")
    else:
        key.write_bytes(b"short")
        key.chmod(0o600)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    assert _entries(kept_here) == []
    (line,) = capfd.readouterr().err.splitlines()
    assert str(key) in line and "delete it" in line


def test_a_changed_program_is_never_unpickled(kept_here, tmp_path):
    """A kept file replaced by a pickle that would run code (bare, or framed as rotor frames
    its programs but with a seal of its own making) is not unpickled: a miss, compiled again
    and written in its place."""
    import pickle

    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    (entry,) = _entries(kept_here)
    good = entry.read_bytes()
    ran = tmp_path / "ran"

    class Runs:
        def __reduce__(self):
            return (open, (str(ran), "w"))  # unpickling it makes the file

    payload = pickle.dumps(Runs())
    for spoilt in (payload, b"rotor program 2\n" + bytes(32) + payload, good[:-1] + bytes([good[-1] ^ 1])):
        entry.write_bytes(spoilt)
        programs.clear_programs()
        np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
        assert not ran.exists()
        assert entry.read_bytes() != spoilt and entry.read_bytes().startswith(b"rotor program 2\n")


def test_a_program_copied_under_another_programs_name_is_compiled_again(kept_here):
    """A program file copied under the name of another kernel's program (another structure of
    arguments: run, it would fail; the same: it would give the other kernel's results) is a
    miss: the kernel is compiled again and its file written in its place, with its results."""
    x = np.linspace(0.0, 1.0, 5)
    np.testing.assert_array_equal(_cubic(x, 2.0), 2.0 * x**3)
    np.testing.assert_array_equal(_cubic(x, 2.0, power=2), 2.0 * x**2)
    np.testing.assert_array_equal(_doubled(x, 3), 8.0 * x)
    cube, square, doubled = _entries(kept_here)
    for source, target in ((cube, doubled), (cube, square)):
        target.write_bytes(source.read_bytes())
        programs.clear_programs()
        np.testing.assert_array_equal(_cubic(x, 2.0, power=2), 2.0 * x**2)
        np.testing.assert_array_equal(_doubled(x, 3), 8.0 * x)
        assert target.read_bytes() != source.read_bytes()
