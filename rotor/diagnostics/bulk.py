"""Many recordings in one call: :func:`diagnose_many` and :func:`analyze_many`, and the
machinery under ``rotor diagnose`` and ``rotor analyze`` with several LOGs.

**Where the work runs** (:func:`map_files`):

- ``jobs=1``: in this process, one file after the other; the compiled kernels of the first
  file serve all the others.
- ``jobs=N`` (default: the machine's cores): N threads of this process (``pool="thread"``,
  the default), which share its compiled kernels: nothing to start, nothing to compile
  again. The diagnosis holds the GIL much of the time, so they overlap only in part.
  Measured on 2 cores shared with other work (load 5–9;
  ``benchmarks/results/diagnose_files.json``): 20 warm files 6.7 s on two threads against
  7.5 s one after the other, but one whole ``rotor diagnose`` call 22 s with ``--jobs 2``
  against 18.5 s with ``--jobs 1``; a pool of two spawned processes took 54 s against
  27 s in one process (each worker imports and compiles before its first file).
- ``pool="process"``: N worker *processes* started with the ``spawn`` method (JAX is not
  fork-safe), for many files on many cores, where the GIL limits the threads. Each worker
  imports rotor and compiles its kernels once, for its first file (10–20 s on a 2-core
  machine); where the caller has JAX's persistent compilation cache on
  (:func:`rotor.enable_compilation_cache`; the ``rotor`` command does), the workers use
  the same folder and read back what was compiled before.
- ``client=``: a ``dask.distributed.Client`` (the optional ``dask`` extra,
  ``pip install 'crank-rotor[dask]'``): one task per file on the cluster's workers, which
  need rotor installed; the files' paths must be readable there.

A file that cannot be done does not stop the others: its place in the list holds the
exception it raised. The order of the results is the order of the files.
"""

from __future__ import annotations

import functools
import glob
import os
import pickle
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ..errors import EngineError, LogError
from ..progress import Progress

__all__ = [
    "DASK_HINT",
    "analyze_many",
    "default_jobs",
    "diagnose_many",
    "expand_logs",
    "is_pattern",
    "map_files",
]

DASK_HINT = "pip install 'crank-rotor[dask]'"
"""How to install the optional Dask backend (the ``dask`` extra)."""

_MAGIC = ("*", "?", "[")


def is_pattern(text: str | os.PathLike) -> bool:
    """Whether ``text`` is a glob pattern (``*``, ``?``, ``[…]``) rather than the path of an
    existing file (a file whose name holds such a character is taken as it is)."""
    s = os.fspath(text)
    return any(c in s for c in _MAGIC) and not os.path.exists(s)


def expand_logs(logs: str | os.PathLike | Sequence[str | os.PathLike]) -> list[str]:
    """The files named by ``logs``: paths and glob patterns, expanded here (so that a
    pattern works where no shell expands it, and past the shell's length limit).

    ``logs``: one path or pattern, or a sequence of them. A pattern (``*``, ``?``,
    ``[…]``; ``**`` for any depth of folders) becomes its matching files in sorted order;
    a pattern that matches no file raises :class:`rotor.LogError`. A path is kept as it is
    (a missing file is that file's error, not the call's). A file named twice is done once.
    """
    items = [logs] if isinstance(logs, (str, os.PathLike)) else list(logs)
    if not items:
        raise LogError("no log files given")
    out: list[str] = []
    for item in items:
        if not isinstance(item, (str, os.PathLike)):
            raise TypeError(f"logs: {item!r} is not a path (a str or path-like)")
        s = os.fspath(item)
        if is_pattern(s):
            found = sorted(p for p in glob.glob(os.path.expanduser(s), recursive=True) if os.path.isfile(p))
            if not found:
                raise LogError(f"{s}: the pattern matches no file")
            out.extend(found)
        else:
            out.append(s)
    return list(dict.fromkeys(out))


def default_jobs() -> int:
    """Local worker processes by default: the cores this process may use."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # not on Linux
        return max(os.cpu_count() or 1, 1)


# ----------------------------------------------------------------------------- workers
def _start_worker(cache_dir: str | None) -> None:
    """A pool worker's start: rotor imported (float64 on), JAX's persistent compilation
    cache in the caller's folder if the caller has one."""
    if cache_dir:
        from ..cache import enable_compilation_cache

        enable_compilation_cache(cache_dir)


def _start_dask_worker() -> None:
    """On each Dask worker: rotor imported, JAX's persistent cache as the worker's own
    environment sets it (``$ROTOR_COMPILATION_CACHE`` or ``~/.cache/rotor/jax``)."""
    from ..cache import enable_compilation_cache

    enable_compilation_cache()


def _caller_cache() -> str | None:
    import jax

    return getattr(jax.config, "jax_compilation_cache_dir", None) or None


def _safe(e: Exception) -> Exception:
    """``e`` if it survives pickling (to come back from a worker), else a
    :class:`RuntimeError` with its type and message."""
    try:
        pickle.loads(pickle.dumps(e))
        return e
    except Exception:  # noqa: BLE001 - any exception that cannot travel
        return RuntimeError(f"{type(e).__name__}: {e}")


def _capture(fn: Callable[[Any], Any], item: Any) -> tuple[bool, Any]:
    """``(True, fn(item))``, or ``(False, the exception)`` where ``fn`` raised."""
    try:
        return True, fn(item)
    except Exception as e:  # noqa: BLE001 - one file's error is that file's result
        return False, _safe(e)


def map_files(
    fn: Callable[[Any], Any],
    items: Sequence[Any],
    *,
    jobs: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    verb: str = "doing",
    pool: str = "thread",
) -> Iterator[tuple[int, bool, Any]]:
    """Run ``fn`` on each of ``items``; yield ``(index, ok, value)`` as each finishes (not
    in order): ``value`` is what ``fn`` returned, or the exception it raised where ``ok`` is
    False. ``fn`` must be picklable (a module's function or a ``functools.partial`` of one)
    unless it runs in this process.

    ``jobs``: local workers (default :func:`default_jobs`; 1 = in this process; never more
    than the items); ``client``: a ``dask.distributed.Client`` (then ``jobs`` is not used);
    ``progress``: a progress bar on stderr (default: when stderr is a terminal);
    ``verb``: the bar's word; ``pool``: ``"thread"`` (default) or ``"process"`` (see the
    module doc).
    """
    n = len(items)
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
        raise EngineError(f"jobs = {jobs!r}: a whole number of workers, 1 or more")
    if pool not in ("process", "thread"):
        raise EngineError(f"pool = {pool!r}: 'process' or 'thread'")
    bar = Progress(n, progress, verb, unit="files")
    try:
        if client is not None:
            yield from _on_dask(client, fn, items, bar)
            return
        workers = min(default_jobs() if jobs is None else jobs, n)
        if workers <= 1:
            for i, item in enumerate(items):
                ok, value = _capture(fn, item)
                bar.update(i + 1)
                yield i, ok, value
            return
        yield from _on_pool(fn, items, workers, pool, bar)
    finally:
        bar.close()


def _on_pool(fn, items, workers, pool, bar):
    import concurrent.futures as cf

    if pool == "thread":
        ex: cf.Executor = cf.ThreadPoolExecutor(max_workers=workers)
    else:
        import multiprocessing

        ex = cf.ProcessPoolExecutor(
            max_workers=workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_start_worker,
            initargs=(_caller_cache(),),
        )
    try:
        futures = {ex.submit(_capture, fn, item): i for i, item in enumerate(items)}
        for done, fut in enumerate(cf.as_completed(futures), 1):
            ok, value = fut.result()
            bar.update(done)
            yield futures[fut], ok, value
    finally:
        ex.shutdown(wait=True, cancel_futures=True)


def _on_dask(client, fn, items, bar):
    try:
        from distributed import as_completed
    except ImportError:  # pragma: no cover - a client without distributed cannot exist
        raise EngineError(f"the Dask backend needs dask.distributed: {DASK_HINT}") from None
    if _caller_cache():
        client.run(_start_dask_worker)
    futures = client.map(functools.partial(_capture, fn), list(items), pure=False)
    where = {f.key: i for i, f in enumerate(futures)}
    try:
        for done, fut in enumerate(as_completed(futures), 1):
            ok, value = fut.result()
            bar.update(done)
            yield where[fut.key], ok, value
    finally:
        client.cancel(futures)


def _in_order(outcomes: Iterator[tuple[int, bool, Any]], n: int) -> list[Any]:
    out: list[Any] = [None] * n
    for i, _ok, value in outcomes:
        out[i] = value
    return out


# ----------------------------------------------------------------------------- the calls
def _diagnose_file(engine, calibration, kwargs, path):
    from .diagnosis import diagnose

    return diagnose(engine, path, calibration, **kwargs)


def diagnose_many(
    engine: Any,
    logs: str | os.PathLike | Sequence[str | os.PathLike],
    calibration: Any = "preset",
    *,
    jobs: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    pool: str = "thread",
    **kwargs: Any,
) -> list[Any]:
    """:func:`rotor.diagnose` of many recordings in one call, across the local cores or on a
    Dask cluster.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`, or a preset name or engine file (loaded once).
    - ``logs``: paths and glob patterns (``"logs/*.csv"``; see :func:`expand_logs`).
    - ``calibration``: as for :func:`rotor.diagnose` (default ``"preset"``), the same for
      every file.
    - ``jobs``: local workers (default: the cores; 1 = in this process).
    - ``pool``: ``"thread"`` (default: threads of this process, sharing its compiled
      code) or ``"process"`` (spawned processes, each compiling once; for many files on
      many cores). See the module doc for what each costs.
    - ``client``: a ``dask.distributed.Client``: the files are diagnosed on its cluster
      (``jobs`` unused); needs the ``dask`` extra.
    - ``progress``: a progress bar on stderr (default: when stderr is a terminal).
    - other keywords (``wheel``, ``columns``, ``tdc_deg``, ``load_per``, ``scaling``,
      ``threshold``, ``edge``, ``check_tdc``, …) go to :func:`rotor.diagnose` for every file.

    **Returns:** a list in the order of the files (after expanding the patterns): for each
    a :class:`rotor.Diagnosis`, or the exception that file raised (e.g. a
    :class:`rotor.LogError`); one bad file does not stop the others. The numbers are those
    of :func:`rotor.diagnose` file by file, whichever backend ran them.

    **Raises:** :class:`rotor.LogError` where a pattern matches no file;
    :class:`rotor.EngineError` for an engine that cannot be loaded or a bad ``jobs``.
    """
    from ..engine.file import load_engine
    from ..engine.model import Engine

    paths = expand_logs(logs)
    eng = engine if isinstance(engine, Engine) else load_engine(engine)
    fn = functools.partial(_diagnose_file, eng, calibration, kwargs)
    outcomes = map_files(fn, paths, jobs=jobs, client=client, progress=progress, verb="diagnosing", pool=pool)
    return _in_order(outcomes, len(paths))


def _analyze_file(kwargs, path):
    from ..logs.analysis import analyze_log

    return analyze_log(path, **kwargs)


def analyze_many(
    logs: str | os.PathLike | Sequence[str | os.PathLike],
    wheel: Any = None,
    *,
    jobs: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    pool: str = "thread",
    **kwargs: Any,
) -> list[Any]:
    """:func:`rotor.analyze_log` of many recordings in one call, across the local cores or
    on a Dask cluster.

    **Arguments:** ``logs``: paths and glob patterns (see :func:`expand_logs`); ``wheel``
    and the other keywords (``columns``, ``strokes``, ``cylinders``, ``tdc_deg``, …) go to
    :func:`rotor.analyze_log` for every file; ``jobs``, ``client``, ``progress`` and ``pool``
    as for :func:`diagnose_many`.

    **Returns:** a list in the order of the files: for each a :class:`rotor.LogAnalysis`
    or the exception that file raised.

    **Raises:** :class:`rotor.LogError` where a pattern matches no file.
    """
    paths = expand_logs(logs)
    fn = functools.partial(_analyze_file, {"wheel": wheel, **kwargs})
    outcomes = map_files(fn, paths, jobs=jobs, client=client, progress=progress, verb="analysing", pool=pool)
    return _in_order(outcomes, len(paths))
