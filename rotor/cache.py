"""JAX's persistent compilation cache for rotor's kernels.

The ``rotor`` command switches the cache on; in Python, call :func:`enable_compilation_cache`
(importing rotor does not touch JAX's cache settings). Compiling rotor's kernels takes 1–3 s
per method in a fresh process; with the cache the compiled code of an earlier process is
reused and a first call costs mainly tracing (``benchmarks/compile_time.py`` and
``benchmarks/cli_latency.py`` measure both). The cache lives in ``$ROTOR_COMPILATION_CACHE``
if set (``0``, ``off`` or ``no`` switches it off), else in ``$XDG_CACHE_HOME/rotor/jax``
(``~/.cache/rotor/jax``), is capped at 1 GB and is left alone if the user has configured a
JAX cache directory already.

Importing JAX takes about a second, and the commands that compile nothing (``rotor
presets``, ``rotor --help``) never do: :func:`enable_compilation_cache` sets JAX's cache at
once when JAX is imported already, else it keeps the setting, and :mod:`rotor.jaxconfig`,
where rotor imports JAX, applies it (:func:`apply_compilation_cache`).

With the compilation cache, the engines' tables are kept between processes too
(:func:`table_folder`): a fresh process reads an engine's tables instead of building them.

**Only in a folder of the user's own.** JAX's cache holds compiled code that a later process
runs, the kept programs (:mod:`rotor.programs`) too, and the tables and the command's kept
outputs are trusted as computed: rotor keeps none of them in a folder that another user
could write (:func:`own_folder`). A folder rotor makes is made mode 0700; one that exists
must be owned by the user and writable by neither its group nor everyone (a shared
``/tmp`` folder is not). Where it is not, rotor neither reads from it nor writes to it, and
says once, in one line on stderr, why and what to do (``chmod go-w`` the folder, or choose
another). On a system without POSIX owners (Windows) the folder is not checked.

**A table entry proves itself.** Each holds, beside its arrays, the digest under which it
is kept and a SHA-256 over that digest and every array's name, dtype, shape and bytes: an
entry that is cut off, changed, copied under another name or holds a value that is not a
finite number is ignored, deleted, and the tables are built afresh (and kept again).
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import os
import re
import shlex
import stat
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

__all__ = [
    "MAX_BYTES",
    "RECENT_PROGRAMS",
    "TABLE_FILES",
    "XLA_CPU_FLAG",
    "apply_compilation_cache",
    "ask_read_ahead",
    "asked_read_ahead",
    "choose_xla_emitters",
    "compilation_cache_on",
    "enable_compilation_cache",
    "keep_tables",
    "kept_program_folder",
    "kept_tables",
    "own_folder",
    "padded_size",
    "prune",
    "recent_programs",
    "say_once",
    "source_fingerprint",
    "submodules_on_demand",
    "switched_off",
    "table_folder",
]

XLA_CPU_FLAG = "--xla_cpu_use_fusion_emitters=false"
"""The XLA option rotor adds to ``$XLA_FLAGS``: XLA's elemental emitters for the CPU
instead of its fusion emitters (XLA's default). They compile rotor's kernels in about 0.65
of the time and run them about as fast (the time-domain method up to 1.4× slower); fixed-step
results agree to the last bits, adaptive runs within their tolerance, where a step is
accepted on one side of its error bound and rejected on the other
(``benchmarks/xla_emitters.py`` measures each). XLA reads ``$XLA_FLAGS`` once, when JAX
starts its first backend: the option applies where rotor is imported before the process
computes with JAX (the usual order), and child processes inherit it. Set
``XLA_FLAGS=--xla_cpu_use_fusion_emitters=true`` to keep XLA's default."""


def choose_xla_emitters() -> None:
    """Add :data:`XLA_CPU_FLAG` to ``$XLA_FLAGS`` unless it names that option already."""
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_cpu_use_fusion_emitters" not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} {XLA_CPU_FLAG}".strip()


def kept_program_folder(compilation_cache_dir: str | os.PathLike[str] | None) -> Path | None:
    """Where kernels' programs are kept (:mod:`rotor.programs`) beside JAX's compilation
    cache in ``compilation_cache_dir``: ``$ROTOR_PROGRAM_CACHE`` if set (``0``, ``off`` or
    ``no``: None), else its subfolder ``rotor-programs``; None without a cache."""
    env = os.environ.get("ROTOR_PROGRAM_CACHE")
    if not compilation_cache_on() or (env is not None and switched_off(env)):
        return None
    if env is not None:
        return Path(env).expanduser()
    return Path(compilation_cache_dir) / "rotor-programs" if compilation_cache_dir else None


RECENT_PROGRAMS = re.compile(r"^recent-[0-9a-f]{24}\.txt$")
"""The names of the files that note the kept programs a task used (:func:`recent_programs`)."""


def recent_programs(folder: Path, task: str) -> Path:
    """The file in the kept programs' ``folder`` that notes which programs the last run of
    ``task`` used (a string naming the work: the ``rotor`` command gives its command line),
    one file name a line (:func:`rotor.programs.read_ahead`)."""
    return folder / f"recent-{hashlib.blake2b(task.encode(), digest_size=12).hexdigest()}.txt"


_READ_AHEAD: list[str] = []  # a task whose kept programs to read once rotor.programs is imported


def ask_read_ahead(task: str | None) -> None:
    """Have :func:`rotor.programs.read_ahead` begin for ``task`` as soon as
    :mod:`rotor.programs` is imported, at once if it is: a command that needs no JAX (its
    output kept, its work NumPy alone) never imports it. None withdraws the request."""
    _READ_AHEAD[:] = [] if task is None else [task]
    programs = sys.modules.get("rotor.programs")
    if programs is not None and task is not None:
        _READ_AHEAD.clear()
        programs.read_ahead(task)


def asked_read_ahead() -> str | None:
    """The task :func:`ask_read_ahead` left for :mod:`rotor.programs` (taken), or None."""
    return _READ_AHEAD.pop() if _READ_AHEAD else None


_OFF = ("0", "off", "no", "false", "")


def switched_off(value: str) -> bool:
    """Whether an environment variable's value (``ROTOR_COMPILATION_CACHE`` and the like)
    switches a cache off: ``0``, ``off``, ``no``, ``false`` or empty."""
    return value.strip().lower() in _OFF


_SAID: set[str] = set()  # the warnings said in this process


def say_once(text: str) -> None:
    """Say ``text`` (one line) on stderr as ``rotor: warning: …``, once a process."""
    if text not in _SAID:
        _SAID.add(text)
        print(f"rotor: warning: {text}", file=sys.stderr)


_OWN: set[str] = set()  # the folders found to be the user's own in this process


def _folder_refusal(folder: str | os.PathLike[str]) -> str | None:
    """Why the existing ``folder`` is not one to keep what rotor runs or trusts in, with what
    to do, as the end of a sentence ("it is writable by its group; run chmod go-w …"), or
    None where it is the user's own: owned by this user and writable by neither its group
    nor everyone. Not checked (None) on a system without POSIX owners. An ``OSError``
    where it cannot be looked at."""
    getuid = getattr(os, "getuid", None)
    if getuid is None:
        return None
    st = os.stat(folder)
    uid = getuid()
    if st.st_uid != uid:
        return f"it is owned by another user (uid {st.st_uid}, not {uid}); "
    by = [who for bit, who in ((stat.S_IWGRP, "its group"), (stat.S_IWOTH, "everyone")) if st.st_mode & bit]
    if by:
        return f"it is writable by {' and by '.join(by)}; run chmod go-w {shlex.quote(os.fspath(folder))}, or "
    return None


def own_folder(folder: Path, what: str, variable: str) -> bool:
    """Whether rotor keeps ``what`` (words: "the engines' tables") in ``folder``: made where
    missing (mode 0700), it must be the user's own (:func:`_folder_refusal`; a folder found
    so is not looked at again in this process). Where it is not, rotor neither reads from
    it nor writes to it, and says so once on stderr, with what to do (``variable``: the
    environment variable that chooses the folder). False without a word where the folder
    cannot be made (a read-only home: nothing is kept, as before)."""
    name = os.fspath(folder)
    if name in _OWN:
        return True
    try:
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
        why = _folder_refusal(folder)
    except OSError:
        return False
    if why is not None:
        say_once(f"{what} are not kept in {name}: {why}set {variable} to a folder of your own")
        return False
    _OWN.add(name)
    return True


def compilation_cache_on() -> bool:
    """Whether :func:`enable_compilation_cache` has switched the compilation cache on in this
    process (and so the tables and the kept programs, :mod:`rotor.programs`)."""
    return bool(_TABLES_ON)


MAX_BYTES = 1 << 30
"""The size cap of the persistent compilation cache [bytes]."""


def padded_size(n: int) -> int:
    """The smallest of 1, 2, 3, 4, 6, 8, 12, 16, 24, … (2ᵏ and 3·2ᵏ) that holds ``n`` items.

    A compiled program serves one shape: a batch padded to one of these sizes reuses the
    program of every other batch of that size (a few programs over all record lengths), for
    at most half as much work again as the exact size."""
    if n < 1:
        raise ValueError(f"n = {n!r}: a size of at least 1")
    power = 1 << (n - 1).bit_length()  # the power of two ≥ n
    return 3 * power // 4 if power >= 4 and 3 * power // 4 >= n else power


_WANTED: list[tuple[str, float]] = []  # the cache asked for before JAX was imported (the last one)


def _own_cache_dir() -> str | None:
    """The JAX cache directory the user set (``jax.config`` or ``$JAX_COMPILATION_CACHE_DIR``), if any."""
    jax = sys.modules.get("jax")
    if jax is not None and hasattr(jax, "config"):
        own = getattr(jax.config, "jax_compilation_cache_dir", None)
        return str(own) if own else None
    return os.environ.get("JAX_COMPILATION_CACHE_DIR") or None


def _configure(jax: ModuleType, path: str, min_compile_time_s: float) -> None:
    jax.config.update("jax_compilation_cache_dir", path)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", min_compile_time_s)
    jax.config.update("jax_compilation_cache_max_size", MAX_BYTES)


def enable_compilation_cache(
    path: str | os.PathLike[str] | None = None, *, min_compile_time_s: float = 0.1
) -> str | None:
    """Use JAX's persistent compilation cache at ``path`` (see the module doc for the default).

    ``path``: a folder (created if missing, mode 0700) of the user's own: one that another
    user could write is refused (:func:`own_folder`: one line on stderr, the cache off).
    ``min_compile_time_s``: only what takes at least this long to compile is written to the
    cache [s] (the ``rotor`` command gives 0: its few small eager operations, 20–100 ms
    each to compile, read back in a few ms; a long Python session would fill the cache
    with them). Returns the directory in use, or
    None when the cache is off. Sets JAX's process-wide cache directory, the compile-time
    threshold and the size cap (1 GB) — at once if JAX is imported, else as soon as rotor
    imports it (so that a command that never needs JAX does not import it); the ``rotor`` command
    calls it once per run. Call it again with another ``path`` to move the cache.
    """
    env = os.environ.get("ROTOR_COMPILATION_CACHE")
    if path is None:
        if env is not None and switched_off(env):
            _TABLES_ON.clear()
            return None
        own = _own_cache_dir()
        if own:  # the user's own choice wins
            return own
        if env:
            path = env
        else:
            base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
            path = Path(base) / "rotor" / "jax"
    path = Path(path).expanduser()
    # compiled code that a later process runs: only in a folder of the user's own (made
    # 0700 where missing); a read-only home: without the cache rather than fail
    if not own_folder(path, "JAX's compiled programs", "ROTOR_COMPILATION_CACHE"):
        _TABLES_ON.clear()
        return None
    folder = str(path)
    _TABLES_ON[:] = [True]
    _WANTED[:] = [(folder, float(min_compile_time_s))]
    jax = sys.modules.get("jax")
    if jax is not None and hasattr(jax, "config"):
        apply_compilation_cache(jax)
    return folder


def apply_compilation_cache(jax: ModuleType) -> None:
    """Set JAX's persistent cache as :func:`enable_compilation_cache` last asked, if it
    asked before JAX was imported (:mod:`rotor.jaxconfig` calls this once JAX is)."""
    while _WANTED:
        folder, min_compile_time_s = _WANTED.pop()
        _configure(jax, folder, min_compile_time_s)


def submodules_on_demand(package: str) -> Callable[[str], ModuleType]:
    """A module ``__getattr__`` for a subpackage's ``__init__``: ``rotor.diagnostics.calibration``
    imports :mod:`rotor.diagnostics.calibration` on first use, as an eager ``import`` of
    every module once did, while ``import rotor`` stays cheap."""

    def __getattr__(name: str) -> ModuleType:
        if not name.startswith("_"):
            try:
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as e:
                if e.name != f"{package}.{name}":
                    raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__


# ---------------------------------------------------------------------- the engines' tables
TABLE_FILES = 64
"""How many engines' tables are kept on disk (the most recently written)."""

_TABLES_ON: list[bool] = []  # set by enable_compilation_cache: the tables are kept from then on
_TABLE_ENTRY = "rotor-tables-"
_PACKAGES = ("jax", "jaxlib", "equinox", "numpy")


def prune(folder: Path, name: re.Pattern, keep: int | None = None, max_bytes: int | None = None) -> None:
    """Delete the oldest files of ``folder`` whose names match ``name`` (no other file of the
    folder is touched) until at most ``keep`` of them are left and they hold at most
    ``max_bytes`` [bytes] (either bound may be None)."""
    found = []
    for item in os.scandir(folder):
        if name.match(item.name) and item.is_file(follow_symlinks=False):
            try:
                st = item.stat(follow_symlinks=False)
            except OSError:
                continue
            found.append((st.st_mtime_ns, st.st_size, item.path))
    count, total = len(found), sum(size for _, size, _ in found)
    for _, size, old in sorted(found):
        if (keep is None or count <= keep) and (max_bytes is None or total <= max_bytes):
            break
        Path(old).unlink(missing_ok=True)
        count, total = count - 1, total - size


def table_folder() -> Path | None:
    """Where the tables of the engines (:func:`rotor.crank_train`: I(θ), the torques and
    their integrals over a cycle) are kept between processes, or None where they are not.

    They are kept once :func:`enable_compilation_cache` has switched the compilation cache
    on (the ``rotor`` command does at every run; in Python, call it), in
    ``$ROTOR_TABLE_CACHE`` if set (``0``, ``off`` or ``no`` switches them off), else in
    ``$XDG_CACHE_HOME/rotor/tables`` (``~/.cache/rotor/tables``); at most
    :data:`TABLE_FILES` files of 0.2–1 MB each (0.8 MB for a six-cylinder engine). A fresh process then reads an
    engine's tables (a few ms) instead of tracing and running the table builder (0.2–0.7 s).
    Delete the folder to clear them."""
    if not _TABLES_ON:
        return None
    env = os.environ.get("ROTOR_TABLE_CACHE")
    if env is not None:
        return None if switched_off(env) else Path(env).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rotor" / "tables"


@functools.cache
def source_fingerprint() -> bytes:
    """rotor's source files (path, size, modification time) and the versions of the
    numerical packages: what a kept result depends on besides its inputs (computed once a
    process)."""
    from importlib import metadata

    root = Path(__file__).resolve().parent
    parts = []
    for folder, _, files in sorted(os.walk(root)):
        for name in sorted(files):
            if name.endswith((".py", ".toml")):
                st = os.stat(os.path.join(folder, name))
                parts.append(f"{os.path.relpath(os.path.join(folder, name), root)}:{st.st_size}:{st.st_mtime_ns}")
    for package in _PACKAGES:
        try:
            parts.append(f"{package}=={metadata.version(package)}")
        except metadata.PackageNotFoundError:
            parts.append(f"{package} missing")
    return "\n".join(parts).encode()


def _table_entry(key: str) -> tuple[Path, str] | None:
    folder = table_folder()
    if folder is None or not own_folder(folder, "the engines' tables", "ROTOR_TABLE_CACHE"):
        return None
    digest = hashlib.blake2b(key.encode() + b"\0" + source_fingerprint(), digest_size=20).hexdigest()
    return folder / f"{_TABLE_ENTRY}{digest}.npz", digest


_TABLE_FIELDS = ("entry", "check")  # the fields of an entry besides its arrays


def _tables_check(digest: str, arrays: dict) -> str:
    """The SHA-256 over the digest an entry is kept under and each array's name, dtype,
    shape and bytes (in the order of their names): an entry whose arrays are not those it
    was written with, or that is copied under another name, does not match it."""
    import numpy as np

    h = hashlib.sha256(digest.encode())
    for name in sorted(arrays):
        a = np.asarray(arrays[name])
        h.update(f"\0{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _all_finite(arrays: dict) -> bool:
    """Whether every array is of numbers (bool, integer, float or complex), all finite."""
    import numpy as np

    for a in arrays.values():
        a = np.asarray(a)
        if a.dtype.kind not in "biufc" or (a.dtype.kind in "fc" and not np.all(np.isfinite(a))):
            return False
    return True


def kept_tables(key: str) -> dict | None:
    """The arrays kept under ``key`` (the digest of an engine's table inputs), or None: also
    where the entry is cut off, changed, copied under another name, holds a value that is not
    a finite number, or was kept by another version of rotor or of the numerical packages
    (its own digest of all of them and the check over its arrays must match) — such an entry
    is deleted, and the caller builds the tables afresh."""
    entry = _table_entry(key)
    if entry is None:
        return None
    path, digest = entry
    import numpy as np

    try:
        z = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        return None
    except Exception:  # noqa: BLE001 - a partial or foreign file is a miss, whatever it raises
        z = None
    arrays = None
    if z is not None:
        try:
            with z:
                fields = {name: z[name] for name in z.files}
            arrays = {name: a for name, a in fields.items() if name not in _TABLE_FIELDS}
            if (
                set(_TABLE_FIELDS) - set(fields)
                or str(fields["entry"]) != digest
                or str(fields["check"]) != _tables_check(digest, arrays)
                or not _all_finite(arrays)
            ):
                arrays = None
        except Exception:  # noqa: BLE001 - as above: a miss
            arrays = None
    if arrays is None:  # not the entry it claims to be: gone, and built afresh
        try:
            path.unlink(missing_ok=True)
        except OSError:
            pass
    return arrays


def keep_tables(key: str, arrays: dict) -> None:
    """Keep ``arrays`` (name → numpy array of finite numbers) under ``key``, whole or not at
    all, with the check over them (:func:`kept_tables`), and only the newest
    :data:`TABLE_FILES` entries of rotor's (no other file of the folder); silently nothing
    where the folder cannot be written or an array holds a value that is not a finite
    number (such tables are never read back)."""
    if set(arrays) & set(_TABLE_FIELDS) or not _all_finite(arrays):
        return
    entry = _table_entry(key)
    if entry is None:
        return
    path, digest = entry
    import numpy as np

    from .fileio import atomic_path

    arrays = {name: np.asarray(a) for name, a in arrays.items()}
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez(f, entry=np.array(digest), check=np.array(_tables_check(digest, arrays)), **arrays)
        prune(path.parent, re.compile(rf"^{_TABLE_ENTRY}[0-9a-f]{{40}}\.npz$"), TABLE_FILES)
    except OSError:
        return
