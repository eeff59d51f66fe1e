"""Prepare once: an engine's tables made once and reused by every solve.

The equation of motion needs the engine's reduced inertia I(θ), its slope and each
cylinder's torques on a cycle grid (:mod:`rotor.dynamics.crank_train`: 2880 nodes at the
default 0.25°). Building them is most of a steady state's cost, and a sweep over the
flywheel, the speed, the fuelling or the load changes none of them: the crankshaft inertia
only adds a constant to I(θ). :func:`prepare` builds them once::

    prepared = rotor.prepare(engine)                         # tables, once
    rotor.steady_state(prepared, rpm=1500)                   # reuses them
    rotor.steady_state(prepared.with_inertia(0.8), rpm=900)  # so does another flywheel

A prepared engine is a pytree (an ``eqx.Module``): it can be passed through ``jax.jit``
and ``jax.vmap``, and ``jax.grad`` over its crankshaft inertia works. Its tables belong to
the values it was prepared from: a change to ``[geometry]``, ``[masses]``, ``[layout]``,
``[pressure]`` or the articulated rods made afterwards (``eqx.tree_at`` on
``prepared.engine``) is refused (:class:`rotor.EngineError`, or under ``jit`` an
``eqx.error_if`` runtime error) instead of reusing stale tables: prepare the changed engine
again, or pass the :class:`rotor.Engine` itself (its tables are then built in the trace,
which is how a sweep over the geometry runs).

The tables live in one place: :func:`prepare` builds them through
:func:`rotor.dynamics.crank_train.checked_train`, which keeps the tables of the last engines
it saw, keyed on their values bit for bit, and every solver given an :class:`rotor.Engine`
(or a prepared engine's) finds them there: ``rotor.steady_state(engine)`` called again with
the same engine reuses them as ``rotor.prepare`` would.
"""

from __future__ import annotations

import copy
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..checks import called_from_outside, concrete, guard, tracing
from ..engine.model import Engine, guard_engine, require_engine
from ..engine.plausible import require_real
from ..errors import EngineError
from .crank_train import (
    CrankTrain,
    check_fidelity,
    checked_train,
    grid_points,
    table_inputs,
)

__all__ = ["PreparedEngine", "prepare", "resolve_engine"]


class PreparedEngine(eqx.Module):
    """An engine with its tables over one cycle (:func:`prepare`).

    **Fields:** ``engine``: the :class:`rotor.Engine` (its crankshaft inertia, friction and
    operating point may change freely); ``train``: the tables
    (:class:`rotor.dynamics.crank_train.CrankTrain`) at ``inertia_ref_kgm2``;
    ``inertia_ref_kgm2``: the crankshaft inertia the tables were built with [kg·m²];
    ``source``: the table inputs the tables were built from (compared with ``engine``'s at
    every use); ``grid_deg``: node spacing [deg].
    """

    engine: Engine
    train: CrankTrain
    inertia_ref_kgm2: jnp.ndarray
    source: tuple
    grid_deg: float = eqx.field(static=True)

    @property
    def fidelity(self) -> str:
        """The fidelity the tables were built at (see :mod:`rotor.dynamics.crank_train`)."""
        return self.train.fidelity

    @property
    def points(self) -> int:
        """Nodes of the cycle grid."""
        return self.train.points

    def with_inertia(self, inertia_kgm2: ArrayLike) -> PreparedEngine:
        """The same prepared engine with the crankshaft inertia ``inertia_kgm2`` [kg·m²]
        (``[crankshaft] inertia_kgm2``, flywheel included): nothing is built again. The value
        is checked where it is used (:func:`checked_reference`; traced, when the program runs)."""
        require_real("with_inertia", "inertia_kgm2", inertia_kgm2, "kg·m²")
        value = jnp.asarray(inertia_kgm2, dtype=jnp.float64)
        return eqx.tree_at(lambda p: p.engine.crankshaft.inertia_kgm2, self, value)


def prepare(engine: Engine, fidelity: str = "variable", grid_deg: float = 0.25) -> PreparedEngine:
    """Build ``engine``'s tables once, for every later solve (see the module doc).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``fidelity``: ``"variable"`` (default), ``"series"``, ``"coefficients"`` or
      ``"constant"`` (:mod:`rotor.dynamics.crank_train`).
    - ``grid_deg``: node spacing of the tables [deg]; must divide the cycle (default 0.25°).

    **Returns:** a :class:`rotor.PreparedEngine`, accepted wherever an engine is by
    :func:`rotor.steady_state`, :func:`rotor.steady_sweep`, :func:`rotor.simulate`,
    :func:`rotor.identify` and :func:`rotor.design_flywheel`.

    **Raises:** a :class:`TypeError` for what is not a :class:`rotor.Engine`, a
    :class:`rotor.EngineError` for an engine whose table inputs are traced; a traced
    crankshaft inertia is checked when the program runs.
    """
    check_fidelity(fidelity, require_engine(engine, "prepare(engine)"), recheck=False)
    if tracing() and called_from_outside():  # a traced crankshaft inertia: checked when the program runs
        engine = guard_engine(engine)
    points = grid_points(engine.strokes, grid_deg, engine.cylinders)
    if any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(table_inputs(engine))):
        raise EngineError(
            "prepare(engine) needs an engine with known values (not traced inside jit/vmap/grad): prepare it "
            "outside, or pass the Engine itself to build its tables in the trace"
        )
    train = checked_train(engine, fidelity, points, "prepare(engine)")
    return PreparedEngine(
        engine=engine,
        train=train,
        inertia_ref_kgm2=jnp.asarray(engine.crankshaft.inertia_kgm2, dtype=jnp.float64),
        source=table_inputs(engine),
        grid_deg=float(grid_deg),
    )


_STALE = (
    "this prepared engine's {what} changed after rotor.prepare: its tables belong to the old values; call "
    "rotor.prepare(engine) again with the changed engine (or pass the Engine itself)"
)


def checked_reference(prepared: PreparedEngine, checks: Any = None) -> Any:
    """``prepared.inertia_ref_kgm2`` after checking that the crankshaft inertia is a
    positive number and that the table inputs
    (:func:`rotor.dynamics.crank_train.table_inputs`) are those it was prepared from: a
    :class:`rotor.EngineError` for known values that differ; for traced ones the returned
    value carries an ``eqx.error_if`` check that raises when the compiled call runs (with
    ``checks``, a :class:`rotor.checks.TracedChecks`, the check is recorded there, for the
    caller to make with its others)."""
    ref = prepared.inertia_ref_kgm2
    inertia = concrete(prepared.engine.crankshaft.inertia_kgm2)
    if inertia is not None and not (inertia.ndim == 0 and np.isfinite(inertia) and inertia > 0):
        raise EngineError(
            f"[crankshaft] inertia_kgm2 = {inertia!r}: must be a positive, finite number [kg·m²] (with_inertia)"
        )
    now_leaves, now_def = jax.tree_util.tree_flatten(table_inputs(prepared.engine))
    then_leaves, then_def = jax.tree_util.tree_flatten(prepared.source)
    if str(now_def) != str(then_def) or len(now_leaves) != len(then_leaves):
        raise EngineError(_STALE.format(what="structure (a table, or a static field such as the firing order)"))
    traced = []
    for a, b in zip(now_leaves, then_leaves):
        if a is b:
            continue
        if isinstance(a, jax.core.Tracer) or isinstance(b, jax.core.Tracer):
            traced.append((a, b))
        elif np.shape(a) != np.shape(b) or not np.array_equal(np.asarray(a), np.asarray(b)):
            raise EngineError(_STALE.format(what="geometry, masses, layout or pressure"))
    if traced:
        same = jnp.all(jnp.stack([jnp.all(jnp.asarray(a) == jnp.asarray(b)) for a, b in traced]))
        ref = guard(ref, ~same, _STALE.format(what="geometry, masses, layout or pressure"), checks)
    return ref


def checked_on_host(prepared: PreparedEngine) -> PreparedEngine:
    """``prepared`` inside a compiled call whose caller checked it before the call
    (:func:`checked_reference` on the host, or made it there with :func:`prepare`): its
    record of the table inputs replaced by its engine's own, so that the check for stale
    tables finds nothing to compare in the trace. Left there, that check is an
    ``eqx.error_if`` host callback, and a program holding one is not stored in JAX's
    persistent compilation cache: it would be compiled again in every process."""
    return eqx.tree_at(lambda p: p.source, prepared, table_inputs(prepared.engine))


def nameless(prepared: PreparedEngine) -> PreparedEngine:
    """``prepared`` with its engine's name left out (""): what a compiled call of it is
    keyed by is then its structure and shapes alone (the name is a static field, part of
    the key), so that another engine of the same shape (cylinders, tables, grid) runs the
    same program with its own numbers as arguments."""
    if prepared.engine.name == "":
        return prepared
    engine = copy.copy(prepared.engine)
    object.__setattr__(engine, "name", "")  # a static field: no numbers change, nothing is checked again
    return eqx.tree_at(lambda p: p.engine, prepared, engine)


def resolve_engine(engine: Engine | PreparedEngine) -> Engine:
    """The :class:`rotor.Engine` of ``engine`` (an engine, returned as it is, or a prepared
    one, checked first: :func:`checked_reference`). A solver then finds the prepared
    engine's tables where :func:`prepare` built and keeps them, with every engine's
    (:func:`rotor.dynamics.crank_train.checked_train`, at the same fidelity and grid;
    another fidelity or grid builds its own)."""
    if isinstance(engine, PreparedEngine):
        checked_reference(engine)
        return engine.engine
    return engine
