"""Kernels compiled once and kept: a warm process runs them without tracing them again.

``jax.jit`` turns a kernel's Python into a program by tracing it and lowering it to XLA's
input in every new process, even where JAX's persistent compilation cache
(:mod:`rotor.cache`) then finds the compiled code: for the adaptive angle-domain solver
(diffrax's Dopri8 with an event) that is 2–4 s a process, for the closed-form steady state
about 0.5 s. A kernel declared with :func:`kept_program` is compiled on its first call with
arguments of a new structure and its executable kept on disk (JAX's
``serialize_executable``, as the compilation cache keeps them); a later process loads it
(tens of ms) and runs it, with no tracing, lowering or compiling. It is the same program:
the results agree to the last bit (``tests/project/test_programs.py``);
``benchmarks/cli_latency.py`` and ``benchmarks/warm_call_profile.py`` measure what it saves.

Programs are kept where rotor has switched the compilation cache on
(:func:`rotor.cache.enable_compilation_cache`: the ``rotor`` command does; in Python, call
it), in its folder's subfolder ``rotor-programs`` (``$ROTOR_PROGRAM_CACHE`` if set; ``0``,
``off`` or ``no`` switches them off), at most :data:`PROGRAM_BYTES` in all (the most
recently written; 0.02–1.3 MB each). A program is found by the kernel's name, the structure, shapes and
dtypes of its array arguments, the values of its other arguments, rotor's source files, the
versions of JAX and the numerical packages, XLA's options and the processor
(:func:`rotor.cache.source_fingerprint`): a change to any of them compiles the kernel again.
The ``rotor`` command loads the programs that its last run of the same command line used
ahead of their first call, on a thread (:func:`read_ahead`).
Delete the folder to clear them. As with JAX's own cache, a kept program is loaded by
unpickling: keep the folder where only you can write.

Inside a transformation (``jit``, ``vmap``, ``grad`` of the caller's: an argument is a
tracer), with an argument that is neither an array nor a number, string or None, or where
a program cannot be kept (it calls back into Python, calls a library function other than
LAPACK's, or cannot be serialized), the kernel is called as it is jitted (``jax.jit`` or
``equinox.filter_jit``), as it would be without this module.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import os
import pickle
import platform
import re
import sys
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from pathlib import Path
from typing import Any, TypeVar

import equinox as eqx
import numpy as np
from jax.experimental import serialize_executable

from .cache import RECENT_PROGRAMS, asked_read_ahead, kept_program_folder, prune, recent_programs, source_fingerprint
from .fileio import atomic_path
from .jaxconfig import jax

__all__ = [
    "PROGRAMS_PER_KERNEL",
    "PROGRAM_BYTES",
    "clear_programs",
    "kept_program",
    "program_folder",
    "read_ahead",
    "remember_programs",
]

PROGRAM_BYTES = 512 << 20
"""The size cap of the kept programs on disk [bytes] (half of JAX's compilation cache's):
past it the least recently written go."""

_ENTRY = "rotor-program-"
_NAME = re.compile(rf"^{_ENTRY}[0-9a-f]{{40}}\.bin$")
_MISSING = object()
_PLAIN = (bool, int, float, complex, str, bytes, type(None))
PROGRAMS_PER_KERNEL = 32
"""At most this many programs of one kernel a process (a loop over a static argument's values is
traced as ``jit`` would trace it, not kept)."""

F = TypeVar("F", bound=Callable[..., Any])


def program_folder() -> Path | None:
    """Where kernels' programs are kept between processes, or None where they are not (see
    the module doc)."""
    return kept_program_folder(getattr(jax.config, "jax_compilation_cache_dir", None))


def _spec(leaf: Any) -> tuple[tuple[int, ...], np.dtype, bool]:
    """(shape, dtype, weak type) of an argument: its part of a program's key, a plain tuple
    (a ``jax.ShapeDtypeStruct`` per argument and call cost more than the rest of the key)."""
    if isinstance(leaf, jax.Array):
        return leaf.shape, leaf.dtype, leaf.weak_type
    a = np.asarray(leaf)
    return a.shape, a.dtype, False


class _Kept:
    """One kernel's programs, found in this process or on disk, by their arguments."""

    def __init__(self, traced: Callable[..., Any], static_argnames: tuple[str, ...]) -> None:
        self.traced = traced
        # the function jitted, one level down (a vmap of another function stays one)
        self.fn: Callable[..., Any] = traced.__wrapped__  # type: ignore[attr-defined]
        self.static_argnames = static_argnames
        # what is traced: as the kernel's own jit traces it (eqx.filter_jit: arrays; jax.jit:
        # arrays and numbers), so that a check made while tracing sees the same values
        self.is_dynamic = eqx.is_array if isinstance(traced, eqx.Module) else _array_or_number
        self.name = f"{self.fn.__module__}.{self.fn.__qualname__}"
        self.calls: dict[Any, Any] = {}
        self.named: dict[Any, frozenset[int]] = {}  # per argument structure: the leaves named static
        _KERNELS.append(self)
        self.positions = {
            i: name for i, name in enumerate(inspect.signature(self.fn).parameters) if name in static_argnames
        }

    def __getattr__(self, name: str) -> Any:  # ``lower``, ``trace`` and the rest of the jitted function's
        return getattr(self.traced, name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        folder = program_folder()
        if folder is None:
            return self.traced(*args, **kwargs)
        # one flattening of the arguments (not an equinox partition and combine on every
        # call); which leaves are traced: as the kernel's jit decides, except those of the
        # arguments named static
        leaves, tree = jax.tree_util.tree_flatten((args, kwargs))
        named = self.named.get(tree)
        if named is None:
            named = self._named_leaves(args, kwargs)
            if len(self.named) < PROGRAMS_PER_KERNEL:
                self.named[tree] = named
        is_dynamic = self.is_dynamic
        mask = tuple(i not in named and is_dynamic(x) for i, x in enumerate(leaves))
        dynamic = [x for x, m in zip(leaves, mask, strict=True) if m]
        fixed = tuple((type(x), x) for x, m in zip(leaves, mask, strict=True) if not m)
        if any(isinstance(x, jax.core.Tracer) for x in dynamic) or not all(t in _PLAIN for t, _ in fixed):
            return self.traced(*args, **kwargs)
        specs = tuple(_spec(x) for x in dynamic)
        key = (tree, mask, fixed, specs)
        call = self.calls.get(key, _MISSING)
        if call is _MISSING:
            if len(self.calls) >= PROGRAMS_PER_KERNEL:  # a loop over static values: traced as it would be
                return self.traced(*args, **kwargs)
            call = self.calls[key] = self._program(folder, key)
        if call is None:
            return self.traced(*args, **kwargs)
        return call(*dynamic)

    def _named_leaves(self, args: tuple, kwargs: dict) -> frozenset[int]:
        """The indices of the leaves of the arguments named static in the flattening of
        ``(args, kwargs)`` (positional arguments first, then keyword arguments in sorted
        order, as JAX flattens a dict)."""
        parts = [(i, a) for i, a in enumerate(args)] + [(k, kwargs[k]) for k in sorted(kwargs)]
        named: set[int] = set()
        start = 0
        for key, value in parts:
            count = len(jax.tree_util.tree_leaves(value))
            if (isinstance(key, int) and key in self.positions) or (
                isinstance(key, str) and key in self.static_argnames
            ):
                named.update(range(start, start + count))
            start += count
        return frozenset(named)

    def _program(self, folder: Path, key: tuple) -> Callable[..., Any] | None:
        """The kept program for ``key`` (the arguments' structure, which leaves are traced,
        the others' values and the traced ones' specs), read from disk or compiled now and
        kept, or None where the kernel cannot be kept."""
        tree, mask, fixed, specs = key
        text = repr((self.name, str(tree), mask, fixed, [(shape, str(dtype), weak) for shape, dtype, weak in specs]))
        digest = hashlib.blake2b(text.encode() + b"\0" + _machine(), digest_size=20).hexdigest()
        path = folder / f"{_ENTRY}{digest}.bin"
        _USED.setdefault(path.name, None)
        early = _EARLY.pop(path.name, None)  # read ahead: wait for it, or read it here if not begun
        found: Any = early.result() if early is not None and not early.cancel() else _MISSING
        if found is _MISSING:  # not read ahead, or the reading stopped before it
            found = _load(path)
        if found is not _MISSING:
            return found

        def flat(*traced: Any) -> Any:
            values, given = iter(traced), iter(fixed)
            leaves = [next(values) if m else next(given)[1] for m in mask]
            args, kwargs = jax.tree_util.tree_unflatten(tree, leaves)
            return self.fn(*args, **kwargs)

        flat.__name__, flat.__qualname__ = self.fn.__name__, self.fn.__qualname__  # JAX's events name the kernel

        try:
            lowered = jax.jit(flat).lower(*(jax.ShapeDtypeStruct(sh, dt, weak_type=w) for sh, dt, w in specs))
            calls = _library_calls(lowered.as_text())
            if not _self_contained(lowered, calls):  # marked, and left to the jitted kernel: compiled once, not twice
                _write(folder, path, b"")
                return None
            with _compiled_afresh() as fresh:
                compiled = lowered.compile()
        except Exception:  # noqa: BLE001 - e.g. a number that must be static: called as jitted, which says what is wrong
            return None
        if not fresh():  # read back from JAX's cache: such an executable cannot be serialized again whole
            return compiled
        try:
            serialized, in_tree, out_tree = serialize_executable.serialize(compiled)
            lapack = bool(calls)  # LAPACK's alone (any other is not kept)
            blob = pickle.dumps((serialized, in_tree, out_tree, lapack))
            # its argument and result structures must come back equal: an equinox module's
            # holds sentinels that another process would not recognise (not kept)
            if pickle.loads(blob)[1:3] != (in_tree, out_tree):
                blob = b""
        except Exception:  # noqa: BLE001 - a program that cannot be serialized is compiled in each process
            blob = b""
        _write(folder, path, blob)
        return compiled


def _load(path: Path) -> Any:
    """The program kept at ``path`` loaded, None where it is marked as a kernel that cannot
    be kept, ``_MISSING`` where there is none (no file, a partial or a foreign one)."""
    try:
        blob = path.read_bytes()
    except OSError:
        return _MISSING
    if blob == b"":
        return None
    try:
        serialized, in_tree, out_tree, lapack = pickle.loads(blob)
        if lapack:
            _ready_lapack()
        return serialize_executable.deserialize_and_load(serialized, in_tree, out_tree)
    except Exception:  # noqa: BLE001 - a partial or foreign file is a miss, whatever it raises
        return _MISSING


_USED: dict[str, None] = {}  # the program files looked up since the reading ahead began, in order
_EARLY: dict[str, Future[Any]] = {}  # the programs being read ahead of their first call
_READING: list[threading.Thread] = []
_STOP = threading.Event()


def read_ahead(task: str) -> None:
    """Start loading, on a thread of its own, the kept programs that the last run of ``task``
    used (:func:`rotor.cache.recent_programs`; the ``rotor`` command's task is its command
    line), the largest first: a kernel's first call then takes its program from there
    (waiting for it if it is being loaded, loading it itself if it is not begun) while the
    process goes on with its imports and input, since loading a program releases the
    interpreter's lock. Nothing where programs are not kept or ``task`` never ran;
    :func:`remember_programs` ends it and notes the programs looked up since this call for
    the next run."""
    _USED.clear()
    folder = program_folder()
    if folder is None or _READING:
        return
    try:
        names = recent_programs(folder, task).read_text().split()
    except OSError:
        return
    sizes = {}
    for name in names:
        with contextlib.suppress(OSError):
            if _NAME.match(name):
                sizes[name] = (folder / name).stat().st_size
    early: dict[str, Future[Any]] = {name: Future() for name in sorted(sizes, key=sizes.__getitem__, reverse=True)}
    _EARLY.update(early)
    _STOP.clear()

    def load_them() -> None:
        for name, future in early.items():
            if future.set_running_or_notify_cancel():  # else a kernel's call loads it itself
                try:
                    future.set_result(_MISSING if _STOP.is_set() else _load(folder / name))
                except BaseException:  # noqa: BLE001 - whatever stops it, the call waiting loads it itself
                    future.set_result(_MISSING)

    thread = threading.Thread(target=load_them, name="rotor-read-ahead", daemon=True)
    _READING.append(thread)
    thread.start()


def remember_programs(task: str | None) -> None:
    """Stop the reading ahead (:func:`read_ahead`), waiting for the program being loaded
    (a fraction of a second, Ctrl-C or not: a thread still loading one as the interpreter
    exits could crash it), and note the kept programs looked up since it began for the
    next run of ``task`` (None: note nothing)."""
    _STOP.set()
    for thread in _READING:
        while thread.is_alive():
            with contextlib.suppress(KeyboardInterrupt):
                thread.join()
    _READING.clear()
    _EARLY.clear()
    text = "".join(f"{name}\n" for name in _USED)
    _USED.clear()
    folder = program_folder()
    if folder is None or not text or task is None:
        return
    path = recent_programs(folder, task)
    try:
        if path.is_file() and path.read_text() == text:
            os.utime(path)  # used again: the last of the notes to be pruned
            return
        with atomic_path(path) as tmp:
            Path(tmp).write_text(text)
        prune(folder, RECENT_PROGRAMS, keep=256)
    except OSError:
        pass


def _write(folder: Path, path: Path, blob: bytes) -> None:
    """Keep ``blob`` at ``path``, whole or not at all, within the size cap; silently nothing
    where the folder cannot be written."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            Path(tmp).write_bytes(blob)
        prune(folder, _NAME, max_bytes=PROGRAM_BYTES)
    except OSError:
        pass


@functools.cache
def _machine() -> bytes:
    """What a compiled program depends on besides its kernel and arguments: rotor's source and
    the numerical packages (:func:`rotor.cache.source_fingerprint`), XLA's options, the
    backend and the processor (a program compiled for one CPU may not run on another)."""
    cpu = ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = "".join(line for line in f if line.startswith(("model name", "flags")))[:4096]
    except OSError:
        cpu = platform.processor() or platform.machine()
    backend = jax.devices()[0].client
    parts = (
        os.environ.get("XLA_FLAGS", ""),
        str(getattr(jax.config, "jax_enable_x64", None)),
        backend.platform,
        backend.platform_version,
        jax.devices()[0].device_kind,
        cpu,
    )
    return source_fingerprint() + b"\0" + "\n".join(parts).encode()


_CACHE_HITS = [0]


def _count_cache_hit(event: str, **kwargs: Any) -> None:
    if event == "/jax/compilation_cache/cache_hits":
        _CACHE_HITS[0] += 1


jax.monitoring.register_event_listener(_count_cache_hit)


@contextlib.contextmanager
def _compiled_afresh() -> Iterator[Callable[[], bool]]:
    """Compile without JAX's persistent compilation cache, and say whether it was so.

    An executable that JAX read back from its cache serializes without parts of its code
    (the next process fails with "Function … not found"), so a program to keep is compiled
    afresh: JAX's cache key is withheld for the block (``jax._src.compiler._get_cache_key``,
    JAX's own switch, private: where this version of JAX lacks it, the cache is left on and
    the yielded check says whether the executable was read back). The check is False where
    the executable came from the cache."""
    hits = _CACHE_HITS[0]
    with _AFRESH_LOCK:  # threads compiling at once: the first in switches JAX's key off, the last out on
        compiler = sys.modules.get("jax._src.compiler")
        if _AFRESH["depth"] == 0 and getattr(compiler, "_get_cache_key", None) is not None:
            _AFRESH["original"] = compiler._get_cache_key  # type: ignore[union-attr]
            compiler._get_cache_key = lambda *args, **kwargs: None  # type: ignore[union-attr]
        _AFRESH["depth"] += 1
    try:
        yield lambda: _CACHE_HITS[0] == hits
    finally:
        with _AFRESH_LOCK:
            _AFRESH["depth"] -= 1
            if _AFRESH["depth"] == 0 and _AFRESH["original"] is not None:
                compiler._get_cache_key = _AFRESH["original"]  # type: ignore[union-attr]
                _AFRESH["original"] = None


_AFRESH_LOCK = threading.Lock()
_AFRESH: dict[str, Any] = {"depth": 0, "original": None}


def _self_contained(lowered: Any, calls: set[str]) -> bool:
    """Whether a lowered program runs without this process: no call back into Python (a
    progress bar, a debug print) and no other side effect, which JAX's compilation cache
    never keeps either (the callback's address is part of its key), and no library function
    but LAPACK's; where this version of JAX does not say, the program is not kept."""
    args = getattr(getattr(lowered, "_lowering", None), "compile_args", None)
    if not isinstance(args, dict) or not {"host_callbacks", "ordered_effects", "unordered_effects"} <= set(args):
        return False
    if args["host_callbacks"] or args["ordered_effects"] or args["unordered_effects"] or args.get("keepalive"):
        return False
    # nor a call of a library function (``calls``, :func:`_library_calls`) other than LAPACK's,
    # which is readied before such a program loads
    return all(target.startswith("lapack_") for target in calls)


_CALL = re.compile(r"custom_call\s*@([\w.$-]+)")


def _library_calls(text: str) -> set[str]:
    """The library functions (XLA custom calls) a lowered program's text calls."""
    return set(_CALL.findall(text)) | ({"?"} if "custom_call" in text and not _CALL.search(text) else set())


def _ready_lapack() -> None:
    """Ready LAPACK's functions, as JAX does while it lowers a program that calls them: a
    loaded program calls them without lowering anything (unreadied, the process crashes)."""
    from jaxlib import lapack

    lapack.prepare_lapack_call("syevd_ffi", np.dtype(np.float64))


_KERNELS: list[_Kept] = []


def clear_programs() -> None:
    """Forget the programs this process has read or compiled (as ``jax.clear_caches()`` does
    JAX's): their compiled code is freed, and a later call reads it from disk again."""
    for kernel in _KERNELS:
        kernel.calls.clear()
        kernel.named.clear()


def _array_or_number(x: Any) -> bool:
    return eqx.is_array(x) or isinstance(x, (bool, int, float, complex))


def kept_program(*, static_argnames: tuple[str, ...] = ()) -> Callable[[F], F]:
    """Declare a jitted kernel (``jax.jit`` or ``equinox.filter_jit`` of it, called so where
    no program is kept) one whose program is kept between processes (see the module doc).
    The arguments are traced as the kernel's own jit traces them (``equinox.filter_jit``:
    arrays; ``jax.jit``: arrays and numbers), the rest and the arguments ``static_argnames``
    (the jit's own static ones) are static: part of the program's key, so they must be
    numbers, strings, bools or None (else the kernel is called as jitted)."""

    def declare(traced: F) -> F:
        kept = _Kept(traced, tuple(static_argnames))
        return functools.wraps(kept.fn)(kept)  # type: ignore[return-value]

    return declare


_TASK = asked_read_ahead()  # the command line asked before this module was imported
if _TASK is not None:
    read_ahead(_TASK)
