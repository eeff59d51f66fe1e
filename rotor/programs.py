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
Delete the folder to clear them.

**A kept program is verified before anything of it is read.** A program is compiled code,
and loading it unpickles its structure (JAX's ``deserialize_and_load``): a file that someone
else wrote would run their code. So programs are kept only in a folder of the user's own
(:func:`rotor.cache.own_folder`: made mode 0700 where missing; one owned by another user or
writable by its group or everyone is neither read nor written, and rotor says once on
stderr why and what to do), and each file is sealed with an HMAC-SHA256, over its name and
its bytes, under a secret key of rotor's own: 32 random bytes in the folder's
``rotor-program-key``, written by rotor (mode 0600) the first time it keeps a program there.
A key file that is not the user's own, is readable or writable by others, is a link or is
not 32 bytes is not used (nothing is kept; rotor says so once: delete it and rotor writes
a new one). A file whose seal does not match (changed, cut off, of an older rotor, sealed
under another key, or copied under another program's name) is never unpickled: it is a
miss, compiled again and written in its place. The check costs under a millisecond a
megabyte. An empty file marks a kernel that cannot be kept (compiled as jitted in every
process); it holds nothing to run. The key stays in the folder, so that a folder moved or
copied by its owner keeps its programs, and goes with it when the folder is deleted.

Inside a transformation (``jit``, ``vmap``, ``grad`` of the caller's: an argument is a
tracer), with an argument that is neither an array nor a number, string or None, or where
a program cannot be kept (it calls back into Python, calls a library function other than
LAPACK's, or cannot be serialized), the kernel is called as it is jitted (``jax.jit`` or
``equinox.filter_jit``), as it would be without this module.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import hashlib
import hmac
import inspect
import os
import pickle
import platform
import re
import secrets
import stat
import sys
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from pathlib import Path
from typing import Any, TypeVar

import equinox as eqx
import numpy as np
from jax.experimental import serialize_executable

from .cache import (
    RECENT_PROGRAMS,
    asked_read_ahead,
    compilation_cache_on,
    kept_program_folder,
    own_folder,
    prune,
    recent_programs,
    say_once,
    source_fingerprint,
)
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
    """Where kernels' programs are kept between processes, or None where they are not: off,
    a folder that is not the user's own, or one whose key cannot be used (see the module
    doc)."""
    store = _store()
    return None if store is None else store[0]


_KEY_FILE = "rotor-program-key"
_KEY_BYTES = 32
_MAGIC = b"rotor program 2\n"  # a sealed program: this line, the HMAC, the pickled program
_SEAL = len(_MAGIC) + hashlib.sha256().digest_size
_STORES: dict[tuple, tuple[Path, bytes] | None] = {}
"""Per setting (``$ROTOR_PROGRAM_CACHE``, JAX's cache folder, whether rotor switched it on):
the folder of the kept programs and its key, or None where none are kept."""


def _store() -> tuple[Path, bytes] | None:
    """The folder where kernels' programs are kept and its key, or None where none are kept;
    a folder is checked and its key read once a process (every kernel call asks: a lookup)."""
    setting = (
        os.environ.get("ROTOR_PROGRAM_CACHE"),
        getattr(jax.config, "jax_compilation_cache_dir", None),
        compilation_cache_on(),
    )
    try:
        return _STORES[setting]
    except KeyError:
        pass
    folder = kept_program_folder(setting[1])
    key = None
    with contextlib.suppress(OSError):  # (a working folder that is gone: no programs kept)
        if folder is not None:
            folder = folder.absolute()  # a relative one: where it was first used
        if folder is not None and own_folder(folder, "kernels' programs", "ROTOR_PROGRAM_CACHE"):
            key = _folder_key(folder)
    store = _STORES[setting] = None if folder is None or key is None else (folder, key)
    return store


def _folder_key(folder: Path) -> bytes | None:
    """The key that seals the programs kept in ``folder`` (the user's own), written (mode
    0600) where there is none; None where it cannot be used (said once) or written."""
    path = folder / _KEY_FILE
    for _ in range(3):
        try:
            fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        except FileNotFoundError:
            if not _write_key(path):
                return None
            continue
        except OSError as e:
            if e.errno == errno.ELOOP:
                _refuse_key(path, "is a link")
            return None
        try:
            with os.fdopen(fd, "rb") as f:
                st = os.fstat(f.fileno())
                key = f.read(_KEY_BYTES + 1) if stat.S_ISREG(st.st_mode) else b""
        except OSError:
            return None
        getuid = getattr(os, "getuid", None)
        if getuid is not None and st.st_uid != getuid():
            _refuse_key(path, f"is owned by another user (uid {st.st_uid})")
        elif getuid is not None and st.st_mode & 0o077:
            _refuse_key(path, f"can be read or written by others (mode {stat.S_IMODE(st.st_mode):o})")
        elif len(key) != _KEY_BYTES:
            _refuse_key(path, "is not a key that rotor wrote")
        else:
            return key
        return None
    return None


def _refuse_key(path: Path, why: str) -> None:
    say_once(
        f"kernels' programs are not kept in {path.parent}: its key {path} {why}; delete it, and rotor writes a new one"
    )


def _write_key(path: Path) -> bool:
    """Write a new key at ``path`` (mode 0600), unless another process has just written one;
    False where it cannot be written."""
    tmp = path.with_name(f".rotor-key-{secrets.token_hex(4)}")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(secrets.token_bytes(_KEY_BYTES))
        try:
            os.link(tmp, path)  # never over a key another process has just written
        except FileExistsError:
            pass
        except OSError:  # a file system without links: the key put in place whole all the same
            os.replace(tmp, path)
        return True
    except OSError:
        return False
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)


def _seal(key: bytes, name: str, body: bytes | memoryview) -> bytes:
    """The HMAC-SHA256 under ``key`` over a program file's name and its pickled program."""
    h = hmac.new(key, name.encode() + b"\0", hashlib.sha256)
    h.update(body)
    return h.digest()


def _sealed(key: bytes, name: str, body: bytes) -> bytes:
    """A program file's bytes: the pickled program ``body`` sealed for the file ``name``."""
    return _MAGIC + _seal(key, name, body) + body


def _opened(key: bytes, name: str, blob: bytes) -> memoryview | None:
    """The pickled program of a file ``name`` with bytes ``blob``, where its seal matches
    (else None: nothing of it is to be unpickled)."""
    if not blob.startswith(_MAGIC) or len(blob) <= _SEAL:
        return None
    view = memoryview(blob)
    body = view[_SEAL:]
    return body if hmac.compare_digest(view[len(_MAGIC) : _SEAL], _seal(key, name, body)) else None


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
        store = _store()
        if store is None:
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
            call = self.calls[key] = self._program(store, key)
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

    def _program(self, store: tuple[Path, bytes], key: tuple) -> Callable[..., Any] | None:
        """The kept program for ``key`` (the arguments' structure, which leaves are traced,
        the others' values and the traced ones' specs), read from the folder of ``store``
        (with its key) or compiled now and kept, or None where the kernel cannot be kept."""
        folder, secret = store
        tree, mask, fixed, specs = key
        text = repr((self.name, str(tree), mask, fixed, [(shape, str(dtype), weak) for shape, dtype, weak in specs]))
        digest = hashlib.blake2b(text.encode() + b"\0" + _machine(), digest_size=20).hexdigest()
        path = folder / f"{_ENTRY}{digest}.bin"
        _USED.setdefault(path.name, None)
        early = _EARLY.pop(path.name, None)  # read ahead: wait for it, or read it here if not begun
        found: Any = early.result() if early is not None and not early.cancel() else _MISSING
        if found is _MISSING:  # not read ahead, or the reading stopped before it
            found = _load(path, secret)
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
            body = pickle.dumps((serialized, in_tree, out_tree, lapack))
            # its argument and result structures must come back equal: an equinox module's
            # holds sentinels that another process would not recognise (not kept)
            blob = _sealed(secret, path.name, body) if pickle.loads(body)[1:3] == (in_tree, out_tree) else b""
        except Exception:  # noqa: BLE001 - a program that cannot be serialized is compiled in each process
            blob = b""
        _write(folder, path, blob)
        return compiled


def _load(path: Path, key: bytes) -> Any:
    """The program kept at ``path`` loaded, None where it is marked as a kernel that cannot
    be kept, ``_MISSING`` where there is none (no file, or one whose seal under ``key`` does
    not match: partial, changed, foreign or another program's; nothing of it is unpickled)."""
    try:
        blob = path.read_bytes()
    except OSError:
        return _MISSING
    if blob == b"":
        return None
    body = _opened(key, path.name, blob)
    if body is None:
        return _MISSING
    try:
        serialized, in_tree, out_tree, lapack = pickle.loads(body)
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
    store = _store()
    if store is None or _READING:
        return
    folder, key = store
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
                    future.set_result(_MISSING if _STOP.is_set() else _load(folder / name, key))
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
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
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
