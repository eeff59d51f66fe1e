"""Steady states in bulk: ``jax.vmap`` over speeds, flywheels, fuelling and loads.

:func:`steady_sweep` prepares the engine once (:func:`rotor.prepare`) and solves
:func:`rotor.steady_state` for every item of the given arrays in compiled calls of up to
:data:`MAX_CHUNK` items, one thread per processor core; inside a call the items are
solved :data:`BATCH` at a time (vectorised), so that their arrays stay in the
processor's cache and the memory stays bounded however many items there are.
The speed, the crankshaft inertia, the combustion scale and a constant load change
nothing prepared. Any other field of the engine (masses, geometry) is swept by passing
``jax.vmap`` an engine whose field is batched, e.g.::

    engines = eqx.tree_at(lambda e: e.masses.reciprocating_kg, engine, masses_kg)
    delta = jax.vmap(lambda e: rotor.steady_state(e).delta)(
        jax.tree_util.tree_map(lambda x: x, engines))   # in_axes as the batch requires

where every item builds its own tables in the trace (about the cost of one unprepared
steady state each). Under ``vmap`` an item with no steady state raises when the program
runs (``eqx.error_if``), as do implausible values; ``steady_state(..., throw=False)``
returns each item's ``converged`` instead.

The same code runs on a GPU where JAX has one (``pip install -U "jax[cuda12]"``): arrays
then live on the device, a chunk's items are vectorised all together, and a chunk of
10⁴–10⁵ items fills it; nothing in rotor requires one.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..engine.friction import Friction
from ..engine.model import Engine, require_engine
from ..engine.plausible import PLAUSIBLE, require_known, require_real
from ..errors import EngineError
from ..progress import Progress
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S
from .crank_train import COL_I
from .equation import friction_coefficients
from .loads import ConstantLoad
from .prepared import PreparedEngine, checked_on_host, checked_reference, nameless, prepare
from .result import parabola_peak
from .steady import (
    SPEED_TERM_TOL,
    STOP_FRACTION,
    coarse_stride,
    flat_fixed_point,
    steady_state,
    textbook_excess,
)

__all__ = ["SteadySweep", "steady_sweep"]

MAX_CHUNK = 4096  # items per compiled call at most: progress is reported after each
BATCH = 8  # items solved together inside a chunk: their (8 × grid) arrays stay in a core's cache
SWEEP_PASSES = 2  # of the fixed point on friction's speed-linear term (the sweep needs no derivatives)


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class SteadySweep(Result):
    """Steady states of many operating points or designs (:func:`steady_sweep`), one row each.

    **Fields:** ``rpm`` [rpm], ``inertia_kgm2`` [kg·m²], ``imep_scale`` [-] (items ×
    cylinders), ``load_Nm`` [N·m] (the given constant load, or None): the inputs;
    ``delta`` [-]: the speed irregularity δ of each steady state; ``min_rpm``,
    ``max_rpm`` [rpm]; ``load_torque_Nm`` [N·m] (the balancing load, with no load given)
    or ``fuel_scale`` [-] (the fuelling that carries a given load); ``textbook_delta``
    [-]; ``converged``: whether each item is a solution; ``engine_name``, ``fidelity``,
    ``grid_deg`` [deg]; ``chunk``: items per compiled call; ``compile_s`` and ``wall_s``
    [s]: compiling, and everything.
    """

    rpm: np.ndarray
    inertia_kgm2: np.ndarray
    imep_scale: np.ndarray
    load_Nm: np.ndarray | None
    delta: np.ndarray
    min_rpm: np.ndarray
    max_rpm: np.ndarray
    load_torque_Nm: np.ndarray | None
    fuel_scale: np.ndarray | None
    textbook_delta: np.ndarray
    converged: np.ndarray
    engine_name: str
    fidelity: str
    grid_deg: float
    chunk: int
    compile_s: float
    wall_s: float

    @property
    def size(self) -> int:
        """Number of items."""
        return int(self.delta.shape[0])

    def _columns(self) -> dict[str, np.ndarray]:
        cols: dict[str, np.ndarray] = {"rpm": self.rpm, "inertia_kgm2": self.inertia_kgm2}
        for c in range(self.imep_scale.shape[1]):
            cols[f"imep_scale_{c + 1}"] = self.imep_scale[:, c]
        if self.load_Nm is not None:
            cols["load_Nm"] = self.load_Nm
        cols.update(delta=self.delta, min_rpm=self.min_rpm, max_rpm=self.max_rpm)
        if self.load_torque_Nm is not None:
            cols["load_torque_Nm"] = self.load_torque_Nm
        if self.fuel_scale is not None:
            cols["fuel_scale"] = self.fuel_scale
        cols.update(textbook_delta=self.textbook_delta, converged=self.converged)
        return cols

    def summary(self) -> str:
        """Counts, the range of δ and of each input, and the time taken."""
        ok = self.converged
        n_ok = int(np.sum(ok))
        lines = [
            f"steady sweep of {self.engine_name}: {self.size} items, {n_ok} converged "
            f"({self.fidelity} inertia, {self.grid_deg:g}° grid)",
        ]
        if n_ok:
            d = self.delta[ok]
            lines.append(f"  delta            {np.min(d):.6g} … {np.max(d):.6g}")
        for name, unit, x in (("rpm", "rpm", self.rpm), ("inertia_kgm2", "kg·m²", self.inertia_kgm2)):
            lines.append(f"  {name:<16} {np.min(x):.6g} … {np.max(x):.6g} {unit}")
        if self.load_torque_Nm is not None and n_ok:
            x = self.load_torque_Nm[ok]
            lines.append(f"  load_torque_Nm   {np.min(x):.6g} … {np.max(x):.6g} N·m (balancing the engine)")
        if self.fuel_scale is not None and n_ok:
            x = self.fuel_scale[ok]
            lines.append(f"  fuel_scale       {np.min(x):.6g} … {np.max(x):.6g} (carrying the given load)")
        per = self.wall_s - self.compile_s
        lines.append(
            f"  time             {self.wall_s:.3g} s ({self.compile_s:.3g} s compiling; "
            f"{self.size / per if per > 0 else float('nan'):.3g} steady states per second after it, "
            f"chunks of {self.chunk})"
        )
        if n_ok < self.size:
            lines.append(
                f"  {self.size - n_ok} items have no steady state (the crankshaft would stop once a cycle): "
                "their rows say converged = False"
            )
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """One row per item: the inputs, δ, the speed range and the balancing figure."""
        import pandas as pd

        return pd.DataFrame(self._columns())

    def to_json_dict(self) -> dict:
        """The columns as lists (NaN as None), with the settings and times."""
        out: dict[str, Any] = {
            "engine": self.engine_name,
            "fidelity": self.fidelity,
            "grid_deg": self.grid_deg,
            "items": self.size,
            "converged_items": int(np.sum(self.converged)),
            "chunk": self.chunk,
            "compile_s": self.compile_s,
            "wall_s": self.wall_s,
        }
        out.update({k: v.tolist() for k, v in self._columns().items()})
        return json_safe(out)

    def plot(self, ax: Any = None) -> Any:
        """δ against the input that varies most (rpm, else the inertia, else the first
        cylinder's scale, else the load), one dot per converged item."""
        from ..plotting.speed import plot_sweep

        cols = self._columns()
        x_name = next(
            (k for k in ("rpm", "inertia_kgm2", "imep_scale_1", "load_Nm") if k in cols and np.ptp(cols[k]) > 0),
            "rpm",
        )
        labels = {"rpm": "speed [rpm]", "inertia_kgm2": "crankshaft inertia [kg·m²]", "load_Nm": "load [N·m]"}
        ok = self.converged
        title = f"{self.engine_name}: steady-state δ of {int(np.sum(ok))} items"
        return plot_sweep(cols[x_name][ok], self.delta[ok], labels.get(x_name, "combustion scale [-]"), title, ax=ax)


def _real(name: str, value: Any, unit: str) -> np.ndarray:
    """``value`` as a float64 array, or a :class:`TypeError` naming ``name`` for what is not
    real numbers (a string, a complex number: never a part of it dropped)."""
    require_real("steady_sweep", name, value, unit)
    return np.asarray(value, dtype=np.float64)


def _column(name: str, value: Any, unit: str) -> np.ndarray:
    a = _real(name, value, unit)
    if a.ndim > 1:
        raise EngineError(f"{name}: takes a number or a 1-D array of numbers [{unit}], got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        i = int(np.argmax(~np.isfinite(a.ravel())))
        raise EngineError(f"{name}[{i}] = {a.ravel()[i]!r}: must be a finite number [{unit}]")
    return a.reshape(-1)


def _items(rpm, inertia, scale, load):
    """The inputs as arrays of one common length (a single value is repeated)."""
    cols = {"rpm": rpm, "inertia_kgm2": inertia} | ({} if load is None else {"load_torque_Nm": load})
    sizes = {k: v.shape[0] for k, v in cols.items()} | {"imep_scale": scale.shape[0]}
    n = max(sizes.values())
    bad = {k: s for k, s in sizes.items() if s not in (1, n)}
    if bad:
        raise EngineError(
            "steady_sweep: the inputs must have one length (or be single values); got "
            + ", ".join(f"{k}: {s}" for k, s in sizes.items())
        )
    return n


def _check_values(rpm, inertia, scale):
    lo, hi, _, _ = PLAUSIBLE[("operating", "rpm")]
    if np.any((rpm < lo) | (rpm > hi)):
        i = int(np.argmax((rpm < lo) | (rpm > hi)))
        raise EngineError(f"rpm[{i}] = {rpm[i]:g}: must be a speed between {lo:g} and {hi:g} rpm")
    if np.any(inertia <= 0):
        i = int(np.argmax(inertia <= 0))
        raise EngineError(f"inertia_kgm2[{i}] = {inertia[i]:g}: must be positive [kg·m²]")
    if np.any(scale < 0):
        i = int(np.argmax(np.any(scale < 0, axis=1)))
        raise EngineError(f"imep_scale[{i}] = {scale[i].tolist()}: must not be negative")


def default_chunk(n: int, workers: int) -> int:
    """Items per compiled call for ``n`` items on ``workers`` threads: as few calls as
    :data:`MAX_CHUNK` allows, a multiple of ``workers`` of them (every thread busy to the
    end), of equal size (the last one padded least). The memory does not grow with the
    chunk: inside it the items are solved :data:`BATCH` at a time."""
    calls = -(-n // MAX_CHUNK)
    calls = -(-calls // workers) * workers
    return max(1, -(-n // calls))


def _flat_item(train, d_inertia, s, a, b, omega_m, balance):
    """One item by the flat closed form (:func:`rotor.dynamics.steady.flat_balance`), with
    only the figures of :class:`SteadySweep`: the same definitions as
    :class:`rotor.SpeedResult`'s (δ from the parabola through the extreme node and its
    neighbours; the textbook δ of Shishkov, "Dinamika dvigatelei", §3.2.12), E(0) as
    :func:`rotor.dynamics.steady.flat_energy` finds it. The extreme nodes are those of its
    first pass over the grid: the largest (smallest) at the final E(0) of the nodes in the
    block it found and two either side; no other pass over the grid. Losses a + b·ω [N·m,
    N·m·s]: b·ω by the fixed point of :func:`rotor.dynamics.steady.flat_fixed_point` (its
    passes only where ``b`` is not None)."""
    rest, passes = (None, 0) if b is None else ((lambda w: b * w), SWEEP_PASSES)
    beta, _, x, E0, ok, (block_hi, block_lo), change = flat_fixed_point(
        train, d_inertia, s, a, omega_m, balance, rest, passes
    )
    k = coarse_stride(train.points)
    inertia = train.values[:, COL_I] + d_inertia
    n = inertia.shape[0]

    def omega_at(j):
        j = j % n
        return jnp.sqrt(2 * jnp.maximum(E0 + beta[j], 0.0) / inertia[j])

    def extreme(block, sign):  # the extreme node's value and the parabola's peak
        near = block * k + jnp.arange(-2, k + 2)
        i = near[jnp.argmax(sign * omega_at(near))]
        return omega_at(i), parabola_peak(omega_at(i - 1), omega_at(i), omega_at(i + 1), sign)

    (hi, hi_peak), (lo, lo_peak) = extreme(block_hi, 1.0), extreme(block_lo, -1.0)
    delta = (hi_peak - lo_peak) / omega_m
    e_ratio = (E0 + jnp.min(beta)) / (E0 + jnp.mean(beta[:-1]))
    converged = ok & jnp.isfinite(e_ratio) & (e_ratio >= STOP_FRACTION)
    textbook = textbook_excess(train, s if balance == "load" else x * s, omega_m)
    textbook = textbook / ((train.mean_inertia + d_inertia) * omega_m**2)
    converged = converged & (change <= SPEED_TERM_TOL)  # else the item is solved again by steady_state
    return delta, lo * RPM_PER_RAD_S, hi * RPM_PER_RAD_S, x, textbook, converged, change


@eqx.filter_jit
def solve_chunk(prepared, rpm, inertia, scale, load, friction, varies):
    """Every item of one chunk by whole :func:`rotor.steady_state` calls (losses that grow
    with ω): the figures of :class:`SteadySweep` per item. ``varies`` (static): which of
    (rpm, inertia, scale, load) hold one value per item; the others hold one value for
    all, so that what depends on them alone is computed once per chunk. The caller checks
    the prepared engine first (:func:`rotor.dynamics.prepared.checked_reference`)."""
    prepared = checked_on_host(prepared)

    def one(rpm_i, inertia_i, scale_i, load_i):
        s = jnp.broadcast_to(scale_i, (prepared.train.cylinders,))
        load_obj = None if load_i is None else ConstantLoad(load_i)
        r = steady_state(
            prepared.with_inertia(inertia_i), rpm_i, load_obj, imep_scale=s, friction=friction, throw=False
        )  # an item with no steady state is a row with converged False
        x = r.load_torque_Nm if load_i is None else r.fuel_scale
        return r.delta, r.min_rpm, r.max_rpm, x, r.textbook_delta, r.converged, jnp.zeros(())

    return _batched(one, (rpm, inertia, scale, load), varies)


@functools.partial(jax.jit, static_argnames="varies")
def solve_flat_chunk(train, inertia_ref, loss, speed_loss, rpm, inertia, scale, load, varies):
    """Every item of one chunk by the flat closed form (:func:`_flat_item`; no loss grows
    with ω²): the figures of :class:`SteadySweep` per item. ``train``: the prepared tables
    at crankshaft inertia ``inertia_ref`` [kg·m²]; ``loss``: the constant friction torque
    [N·m]; ``speed_loss``: friction's speed-linear coefficient [N·m·s], or None for none;
    ``varies`` as :func:`solve_chunk`'s. Only arrays cross into the compiled call:
    the caller checks the prepared engine once (:func:`rotor.dynamics.prepared.checked_reference`)."""

    def one(rpm_i, inertia_i, scale_i, load_i):
        s = jnp.broadcast_to(scale_i, (train.cylinders,))
        a = loss + (0.0 if load_i is None else load_i)
        balance = "load" if load_i is None else "fuel"
        return _flat_item(train, inertia_i - inertia_ref, s, a, speed_loss, rpm_i / RPM_PER_RAD_S, balance)

    return _batched(one, (rpm, inertia, scale, load), varies)


def _batched(one, args, varies):
    """``one`` over the items of ``args`` (those where ``varies``), :data:`BATCH` at a time
    on a CPU (``lax.map``): a batch's arrays over the grid stay in the processor's cache,
    where a ``vmap`` over the whole chunk would write them to memory and read them back."""
    fixed = [None if v else a for a, v in zip(args, varies)]

    def batch(xs):
        given = iter(xs)
        return one(*(next(given) if v else a for v, a in zip(varies, fixed)))

    items = tuple(a for a, v in zip(args, varies) if v)
    if jax.default_backend() != "cpu":  # an accelerator wants the whole chunk at once
        return tuple(jax.vmap(batch)(items))
    return tuple(jax.lax.map(batch, items, batch_size=BATCH))


def _solve_apart(prepared, friction, items, columns, outs) -> None:
    """The ``items`` whose fixed point on friction's speed-linear term did not converge in
    the chunk's passes, each solved by :func:`rotor.steady_state` (more passes, or shooting,
    as it finds needed), written into ``outs`` (δ, min and max rpm, the balancing figure as
    the flat form's, textbook δ, converged). ``columns``: the items' rpm, inertia, fuelling
    and load (or None)."""
    rpm, inertia, scale, load = columns
    for i in items:
        r = steady_state(
            prepared.with_inertia(inertia[i]),
            rpm[i],
            None if load is None else ConstantLoad(load[i]),
            imep_scale=scale[i],
            friction=friction,
            throw=False,
        )
        x = r.load_torque_Nm if load is None else r.fuel_scale / np.mean(scale[i])
        for out, v in zip(outs, (r.delta, r.min_rpm, r.max_rpm, x, r.textbook_delta, r.converged), strict=True):
            out[i] = np.asarray(v)


def steady_sweep(
    engine: Engine | PreparedEngine,
    rpm: ArrayLike | None = None,
    *,
    inertia_kgm2: ArrayLike | None = None,
    imep_scale: ArrayLike = 1.0,
    load_torque_Nm: ArrayLike | None = None,
    friction: Friction | Literal[False] | None = None,
    fidelity: str | None = None,
    grid_deg: float | None = None,
    chunk: int | None = None,
    threads: int | None = None,
    progress: bool | None = None,
) -> SteadySweep:
    """Steady states (:func:`rotor.steady_state`) of many items in vectorised, compiled chunks.

    **Arguments** (each a single value or a 1-D array; arrays share one length, the items):
    - ``engine``: a :class:`rotor.Engine` (prepared here) or a :class:`rotor.PreparedEngine`.
    - ``rpm``: time-mean speed [rpm]; default the engine's ``[operating] rpm``.
    - ``inertia_kgm2``: crankshaft inertia, flywheel included [kg·m²]; default the engine's.
    - ``imep_scale``: combustion scale [-]: a number per item, or an array of shape
      (items, cylinders) (or (1, cylinders)) for each cylinder.
    - ``load_torque_Nm``: None (each item's load balances the engine's mean torque, as
      ``steady_state(load=None)``), or a constant load [N·m] per item that the fuelling
      is scaled to carry (``fuel_scale``).
    - ``friction``, ``fidelity``, ``grid_deg``: as :func:`rotor.steady_state` (a prepared
      engine's fidelity and grid are its own).
    - ``chunk``: items per compiled call (default: up to :data:`MAX_CHUNK`, in equal
      calls, a multiple of ``threads`` of them); the last chunk is padded, so every chunk
      has one shape and is compiled once.
    - ``threads``: chunks solved at once (default: one per processor core).
    - ``progress``: a progress bar on stderr (None: on a terminal, after ~2 s).

    **Returns:** a :class:`rotor.SteadySweep`, one row per item; ``converged`` is False
    where an item has no steady state (no error is raised for one item).

    **Raises:** :class:`rotor.EngineError` for values out of range, a :class:`TypeError`
    for values of the wrong type or traced by ``jax.jit``/``vmap``/``grad`` (the sweep runs
    its own compiled chunks: ``jax.vmap`` :func:`rotor.steady_state` for a sweep inside a
    transformation), each naming the argument.
    """
    start = time.perf_counter()
    require_known(
        "steady_sweep",
        "the sweep compiles and runs its own chunks; jax.vmap rotor.steady_state for a sweep inside one",
        engine=engine,
        rpm=rpm,
        inertia_kgm2=inertia_kgm2,
        imep_scale=imep_scale,
        load_torque_Nm=load_torque_Nm,
        friction=friction,
    )
    if not isinstance(engine, PreparedEngine):
        require_engine(engine, "steady_sweep(engine)")
    if isinstance(engine, PreparedEngine):
        for name, given, own in (("fidelity", fidelity, engine.fidelity), ("grid_deg", grid_deg, engine.grid_deg)):
            if given is not None and given != own:
                raise EngineError(
                    f"{name} = {given!r}: this engine was prepared with {name} = {own!r}; prepare it again "
                    f"(rotor.prepare(engine, {name}={given!r}))"
                )
        prepared = engine
    else:
        prepared = prepare(engine, fidelity or "variable", 0.25 if grid_deg is None else grid_deg)
    base = prepared.engine
    n_cyl = base.cylinders
    rpm_a = _column("rpm", base.operating.rpm if rpm is None else rpm, "rpm")
    inertia_a = _column("inertia_kgm2", base.crankshaft.inertia_kgm2 if inertia_kgm2 is None else inertia_kgm2, "kg·m²")
    scale = _real("imep_scale", imep_scale, "-")
    if scale.ndim <= 1:
        scale = np.broadcast_to(scale.reshape(-1, 1), (scale.size, n_cyl))
    if scale.ndim != 2 or scale.shape[1] != n_cyl or not np.all(np.isfinite(scale)):
        raise EngineError(
            f"imep_scale: takes a number, one per item, or shape (items, {n_cyl}) of finite numbers; "
            f"got shape {np.shape(imep_scale)}"
        )
    load_a = None if load_torque_Nm is None else _column("load_torque_Nm", load_torque_Nm, "N·m")
    n = _items(rpm_a, inertia_a, scale, load_a)
    rpm_a, inertia_a = np.broadcast_to(rpm_a, (n,)), np.broadcast_to(inertia_a, (n,))
    scale = np.broadcast_to(scale, (n, n_cyl))
    load_a = None if load_a is None else np.broadcast_to(load_a, (n,))
    _check_values(rpm_a, inertia_a, scale)
    whole = isinstance(threads, (int, np.integer)) and not isinstance(threads, bool) and threads >= 1
    if threads is not None and not whole:
        raise EngineError(f"threads = {threads!r}: must be a whole number, 1 or more")
    workers = (os.cpu_count() or 1) if threads is None else int(threads)
    if chunk is None:
        size = default_chunk(n, workers)
    elif isinstance(chunk, (int, np.integer)) and not isinstance(chunk, bool) and chunk >= 1:
        size = int(min(chunk, n))
    else:
        raise EngineError(f"chunk = {chunk!r}: must be a whole number of items, 1 or more")
    outs: list[list[np.ndarray]] = []
    bar = Progress(n, progress, verb="solving", unit="steady states")
    fr = np.asarray(friction_coefficients(base, friction))
    flat = bool(prepared.fidelity != "constant" and fr[2] == 0)  # no loss grows with ω²: E = E0 + β(θ) (+ b·ω's part)
    columns = (rpm_a, inertia_a, scale, load_a)
    varies = tuple(c is not None and bool(np.any(c != c[:1])) for c in columns)
    if not any(varies):  # one item, or the same one many times: a batch over rpm all the same
        varies = (True,) + varies[1:]
    firsts = list(range(0, n, size))

    def chunk_args(first):
        idx = np.minimum(np.arange(first, first + size), n - 1)  # the last chunk repeats its last item
        return tuple(None if c is None else jnp.asarray(c[idx] if v else c[0]) for c, v in zip(columns, varies))

    t0 = time.perf_counter()
    if flat:  # checked once here: only the tables cross into the compiled call
        speed_loss = None if fr[1] == 0 else jnp.asarray(fr[1])
        fixed: tuple = (prepared.train, np.float64(checked_reference(prepared)), jnp.asarray(fr[0]), speed_loss)
        kernel = solve_flat_chunk.lower(*fixed, *chunk_args(0), varies).compile()
    else:
        checked_reference(prepared)
        fixed = (nameless(prepared),)  # the program keyed by the engine's shapes, not its name
        kernel = solve_chunk.lower(*fixed, *chunk_args(0), friction, varies).compile()  # type: ignore[attr-defined]
    compile_s = time.perf_counter() - t0
    extra = () if flat else (friction, varies)

    def run(first):
        res = jax.device_get(kernel(*fixed, *chunk_args(first), *extra))
        return [np.broadcast_to(np.asarray(r), (size,))[: min(size, n - first)] for r in res]

    with ThreadPoolExecutor(min(workers, len(firsts))) as pool:  # a compiled call runs without the GIL
        for first, out in zip(firsts, pool.map(run, firsts)):
            outs.append(out)
            bar.update(min(first + size, n))
    bar.close()
    delta, lo, hi, x, tb, ok, error = (np.concatenate(c) for c in zip(*outs))
    _solve_apart(prepared, friction, np.flatnonzero(error > SPEED_TERM_TOL), columns, (delta, lo, hi, x, tb, ok))
    if flat and load_a is not None:  # the flat form's factor on imep_scale; the fuel scale is as SpeedResult's
        x = x * np.mean(scale, axis=1)
    return SteadySweep(
        rpm=np.array(rpm_a),
        inertia_kgm2=np.array(inertia_a),
        imep_scale=np.array(scale),
        load_Nm=None if load_a is None else np.array(load_a),
        delta=delta,
        min_rpm=lo,
        max_rpm=hi,
        load_torque_Nm=x if load_a is None else None,
        fuel_scale=x if load_a is not None else None,
        textbook_delta=tb,
        converged=ok.astype(bool),
        engine_name=base.name,
        fidelity=prepared.fidelity,
        grid_deg=prepared.grid_deg,
        chunk=size,
        compile_s=compile_s,
        wall_s=time.perf_counter() - start,
    )
