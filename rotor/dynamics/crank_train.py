"""The engine prepared for its equation of motion: periodic tables over one cycle.

Every function of the crank angle that the equation of motion needs is sampled once,
with its exact derivative (automatic differentiation), on a uniform grid over the cycle
(0.25° by default), and evaluated between the nodes by cubic Hermite interpolation
(fourth-order accurate, C¹, periodic). The columns are

- ``I``: reduced inertia I(θ) [kg·m²] at the chosen fidelity;
- ``k``: coefficient of the explicit reciprocating inertia torque k(θ)·ω² [kg·m²]
  (nonzero only at the ``"constant"`` fidelity, where I is constant);
- ``M_motored``: the engine's gas torque with no cylinder firing [N·m];
- ``dM_c``: cylinder c's combustion torque, fired minus motored [N·m], one column each.

Fidelity (``fidelity=``):

- ``"variable"``: exact I(θ) (:func:`rotor.reduced_inertia`); the reciprocating inertia
  torque −½·I′(θ)·ω² comes out of I(θ) and k = 0. The default.
- ``"series"``: as ``"variable"`` but with the textbook λ-series piston kinematics
  (Lukanin (ed.), "Internal combustion engines, vol. 2: Dynamics and design", 2009, and Shishkov,
  "Dinamika dvigatelei", SUSU 2014: s′ = R(sin θ + (λ/2)·sin 2θ − λ·z·cos θ)) in I(θ) = J + Σ(m_rot·R² +
  m_rec·s′²) (two-mass split) and in the gas torque's lever arm p·A·s′; ordinary crank
  trains only.
- ``"coefficients"``: I(θ) in the form of Anisimov, Yelenich & Melnyk, "Modelling a piston engine by the
  irregularity of crankshaft rotation", A·cos²θ + B·cosθ + C per cylinder, k = 0.
- ``"constant"``: I = the cycle mean of the exact I(θ) and k(θ) = −Σ m_rec·s″·s′ (the
  textbook inertia torque, Shishkov (2014)); the reciprocating masses are never counted twice.
"""

from __future__ import annotations

import functools
import hashlib
import weakref
from collections import OrderedDict
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..cache import keep_tables, kept_tables
from ..checks import arrays_only, called_from_outside, check_size, concrete, tracing
from ..cycles import array_module
from ..engine.forces import cylinder_gas_torques, reciprocating_inertia_torque
from ..engine.inertia import inertia_coefficients, mean_reduced_inertia, ordinary_cylinder_inertia, reduced_inertia
from ..engine.kinematics import piston_motion
from ..engine.model import Engine, engine_jit, guard_engine, require_engine, unnamed
from ..engine.plausible import require_number
from ..errors import EngineError
from ..programs import kept_program

__all__ = [
    "CrankTrain",
    "crank_train",
    "check_engine",
    "check_inertia",
    "check_finite_tables",
    "checked_train",
    "clear_table_cache",
    "shift_inertia",
    "table_inputs",
    "table_key",
    "FIDELITIES",
    "COL_I",
    "COL_K",
    "COL_MOTORED",
    "COL_COMBUSTION",
]

FIDELITIES = ("variable", "series", "coefficients", "constant")
# the columns of CrankTrain.values and .slopes: I(θ) [kg·m²]; k(θ), the coefficient of ω² in
# the engine torque [kg·m²]; the motored torque [N·m]; the first of one combustion-torque
# column per cylinder [N·m]
COL_I, COL_K, COL_MOTORED, COL_COMBUSTION = 0, 1, 2, 3


def check_engine(engine: Any, call: str = "crank_train(engine)") -> None:
    """Check ``engine`` again before a solver uses it (see :meth:`rotor.Engine.check`): a
    :class:`TypeError` naming ``call`` if it is not an engine, a :class:`rotor.EngineError`
    for a field that ``eqx.tree_at`` put in unchecked. Traced fields pass."""
    require_engine(engine, call).check()


def check_fidelity(fidelity: str, engine: Engine | None = None, *, recheck: bool = True) -> None:
    """Refuse an unknown ``fidelity``, or one ``engine`` cannot use; checks ``engine``
    again (:func:`check_engine`) when it is given, unless ``recheck`` is False."""
    if engine is not None and recheck:
        check_engine(engine, "engine")
    if fidelity not in FIDELITIES:
        raise EngineError(f"fidelity = {fidelity!r}: must be one of {', '.join(map(repr, FIDELITIES))}")
    if fidelity == "series" and engine is not None and engine.articulated is not None:
        raise EngineError(
            "fidelity='series' (λ-series kinematics) is for ordinary crank trains; an articulated engine's slave "
            "rods need fidelity='variable', 'coefficients' or 'constant'"
        )


# memory of the tables per grid point and column while they are built [bytes]: values
# and slopes, and the intermediates of the per-cylinder shifts and derivatives
BYTES_PER_NODE_COLUMN = 8 * 48


def grid_points(strokes: int, grid_deg: float, cylinders: int = 1) -> int:
    """Nodes of the cycle grid at ``grid_deg`` [deg] for a ``strokes``-stroke engine of
    ``cylinders`` cylinders; refuses a step that does not divide the cycle, or a grid whose
    tables would not fit in memory (:func:`rotor.checks.check_size`)."""
    if (
        type(strokes) is int
        and type(grid_deg) is float
        and type(cylinders) is int
        and 180.0 * strokes <= 1e6 * grid_deg  # no memory check, which reads the machine's state
    ):
        return _grid_points_of(strokes, grid_deg, cylinders)  # a repeated call: its answer kept
    return _grid_points(strokes, grid_deg, cylinders)


@functools.lru_cache(maxsize=64)
def _grid_points_of(strokes: int, grid_deg: float, cylinders: int) -> int:
    return _grid_points(strokes, grid_deg, cylinders)


def _grid_points(strokes: int, grid_deg: Any, cylinders: int) -> int:
    grid_deg = require_number(grid_deg, "grid_deg", "deg")
    cycle = 180.0 * strokes
    ok = np.isfinite(grid_deg) and grid_deg > 0
    n_real = cycle / grid_deg if ok else 0.0
    if ok and n_real > 1e6:  # before counting nodes: a grid of 1e-300° has more than int can say
        need = n_real * (COL_COMBUSTION + cylinders) * BYTES_PER_NODE_COLUMN
        check_size(need, f"grid_deg = {grid_deg:g}° ({n_real:.3g} nodes per cycle)", "use a larger grid_deg, e.g. 0.25")
    n = int(round(n_real)) if ok else 0
    if not (ok and np.isclose(n * grid_deg, cycle) and n >= 16):
        raise EngineError(f"grid_deg = {grid_deg!r}: must divide the {cycle:g}° cycle into 16 or more equal steps")
    return n


class CrankTrain(eqx.Module):
    """Periodic tables of the equation of motion on a uniform cycle grid (see module doc).

    **Fields:** ``values``, ``slopes``: (N, 3 + cylinders) node values and dθ-derivatives;
    ``cycle_rad``: cycle angle Θ [rad]; ``firing_rad``: each cylinder's firing TDC in
    [0, Θ) [rad]; ``imep_motored_pa``, ``imep_combustion_pa``: each cylinder's IMEP
    without firing and the part added by its combustion [Pa]; ``mean_inertia``: cycle
    mean of I [kg·m²]; ``textbook_k``: the textbook reciprocating inertia torque per ω²,
    −Σ m_rec·s″·s′, on the nodes [kg·m²]; ``torque_means``: the cycle means of the
    motored and of each combustion torque column [N·m]; ``work``: (N + 1, 1 + cylinders)
    the work of those columns with their means removed, from node 0 to each node by the
    Hermite rule [J]; ``textbook_work``: (N, 2 + cylinders) the running sums (rectangle
    rule, the textbook's) of ``textbook_k`` [J per (rad/s)²], the motored and each
    combustion column, means removed [J]; ``fidelity`` (static). The works depend on the
    tables alone: the steady state's closed form and a sweep read them instead of summing.
    """

    values: jnp.ndarray
    slopes: jnp.ndarray
    firing_rad: jnp.ndarray
    imep_motored_pa: jnp.ndarray
    imep_combustion_pa: jnp.ndarray
    mean_inertia: jnp.ndarray
    textbook_k: jnp.ndarray
    torque_means: jnp.ndarray
    work: jnp.ndarray
    textbook_work: jnp.ndarray
    cycle_rad: float = eqx.field(static=True)
    strokes: int = eqx.field(static=True)
    fidelity: str = eqx.field(static=True)

    @property
    def points(self) -> int:
        return self.values.shape[0]

    @property
    def cylinders(self) -> int:
        return self.values.shape[1] - COL_COMBUSTION

    @property
    def step_rad(self):
        return self.cycle_rad / self.points

    def at(self, theta: ArrayLike) -> tuple[Float[Array, "... K"], Float[Array, "... K"]]:
        """Hermite-interpolated (values, slopes) at engine angle(s) ``theta`` [rad]: shape θ.shape + (K,)."""
        xp = array_module(theta, self.values, self.slopes)  # NumPy for a concrete table
        values, slopes = (np.asarray(self.values), np.asarray(self.slopes)) if xp is np else (self.values, self.slopes)
        angle = xp.asarray(theta, dtype=xp.float64)
        h = self.step_rad
        u = angle / h
        j = xp.floor(u)
        tau = (u - j)[..., None]
        j0 = xp.mod(j, self.points).astype(xp.int32)
        j1 = xp.mod(j0 + 1, self.points)
        return _hermite(values[j0], values[j1], slopes[j0], slopes[j1], tau, h)

    def nodes(self) -> Float[Array, " N"]:  # noqa: F722
        """Node angles over one cycle [rad], shape (N,)."""
        return jnp.arange(self.points) * self.step_rad

    def scale_index(self, theta: ArrayLike, cycles: int) -> Array:
        """Index k of each cylinder's firing whose half-cycle window holds the engine angle
        ``theta`` [rad], clipped to the run's ``cycles``: shape θ.shape + (cylinders,)."""
        k = firing_window(jnp.asarray(theta, dtype=jnp.float64)[..., None], self.firing_rad, self.cycle_rad)
        return jnp.clip(k, 0, cycles - 1)


WINDOW_TIE = 1e-9
"""Share of a cycle by which an angle on the border of two firing windows is moved into the
later one before rounding (:func:`firing_window`)."""


def firing_window(theta, firing_rad, cycle_rad) -> Array:
    """Index k of the firing whose window, half a cycle on either side of its TDC, holds the
    angle ``theta`` [rad]: k·Θ − Θ/2 ≤ θ − θ_fire < k·Θ + Θ/2 (int32, broadcast over the
    arguments). The borders lie on table nodes in every usual engine (a firing TDC on a
    node, half a cycle on a node), where the rounding of (θ − θ_fire)/Θ + ½ would decide
    the window, and XLA may round the same expression differently in two places of one
    program: an angle within :data:`WINDOW_TIE` of a cycle below a border counts as on it,
    so that every evaluation gives the window of exact arithmetic, the later one."""
    return jnp.floor((theta - firing_rad) / cycle_rad + (0.5 + WINDOW_TIE)).astype(jnp.int32)


def _columns(engine, fidelity, theta):
    """The table columns at engine angles θ (shape (N,)) → (N, K), every cylinder evaluated."""
    n = engine.cylinders
    if fidelity == "constant":
        inertia = jnp.broadcast_to(mean_reduced_inertia(engine), theta.shape)
        k = reciprocating_inertia_torque(engine, theta, 1.0)
    else:
        inertia = reduced_inertia(engine, theta, "exact" if fidelity == "variable" else "coefficients")
        k = jnp.zeros_like(theta)
    motored = engine.replace(pressure=engine.pressure.motored(engine.strokes))
    m_mot = cylinder_gas_torques(motored, theta)
    m_fired = cylinder_gas_torques(engine, theta)
    cols = [inertia[..., None], k[..., None], jnp.sum(m_mot, axis=-1, keepdims=True), m_fired - m_mot]
    out = jnp.concatenate(cols, axis=-1)
    assert out.shape[-1] == COL_COMBUSTION + n
    return out, m_mot


def _hermite(f0, f1, s0, s1, tau, h):
    """Cubic Hermite between nodes with values f0, f1 and slopes s0, s1 a step h apart, at
    the fraction tau of the step: (value, slope)."""
    d0, d1 = s0 * h, s1 * h
    t2, t3 = tau * tau, tau * tau * tau
    val = (2 * t3 - 3 * t2 + 1) * f0 + (t3 - 2 * t2 + tau) * d0 + (3 * t2 - 2 * t3) * f1 + (t3 - t2) * d1
    der = ((6 * t2 - 6 * tau) * (f0 - f1) + (3 * t2 - 4 * tau + 1) * d0 + (3 * t2 - 2 * tau) * d1) / h
    return val, der


def _shifted(values, slopes, offset, period):
    """f(φ_i − offset) and its slope at every node φ_i, by periodic cubic Hermite
    interpolation. The fractional position is the same at every node, so this is two
    rolls of the node data and four scalar weights (no gathers)."""
    n = values.shape[0]
    h = period / n
    u = offset / h
    j = jnp.floor(u)
    tau = 1.0 - (u - j)  # evaluation point: node (i − j − 1) plus tau
    j = j.astype(jnp.int32)
    return _hermite(
        jnp.roll(values, j + 1, axis=0),
        jnp.roll(values, j, axis=0),
        jnp.roll(slopes, j + 1, axis=0),
        jnp.roll(slopes, j, axis=0),
        tau,
        h,
    )


def _one_cylinder(engine, fidelity, phi):
    """Functions of one ordinary cylinder's own angle φ (shape (N,)) → (N, 5):
    I_cyl, k_cyl, motored torque, combustion torque, textbook k. A cylinder's firing TDC is one of
    its TDCs, so its mechanical angle equals its cycle angle modulo 2π."""
    g = engine.geometry
    pm = piston_motion(phi, g.crank_radius_m, g.rod_length_m, g.pin_offset_m)
    m_rec, m_rot = engine.masses.two_mass_split(g.rod_length_m)
    lever = pm.ds
    if fidelity == "series":
        lever = piston_motion(phi, g.crank_radius_m, g.rod_length_m, g.pin_offset_m, model="series").ds
        inertia = m_rot * g.crank_radius_m**2 + m_rec * lever**2
        k = jnp.zeros_like(phi)
    elif fidelity == "constant":
        inertia = jnp.zeros_like(phi)
        k = -m_rec * pm.d2s * pm.ds
    elif fidelity == "variable":
        inertia = ordinary_cylinder_inertia(phi, g, engine.masses)
        k = jnp.zeros_like(phi)
    else:
        A, B, C = inertia_coefficients(engine)
        c = jnp.cos(phi)
        inertia = A[0] * c**2 + B[0] * c + C[0]
        k = jnp.zeros_like(phi)
    fired = engine.pressure(phi, g, engine.strokes)
    mot = engine.pressure.motored(engine.strokes)(phi, g, engine.strokes)
    area_ds = g.piston_area_m2 * lever
    m_mot = (mot - engine.pressure.crankcase_pa) * area_ds
    textbook_k = -m_rec * pm.d2s * pm.ds
    return jnp.stack([inertia, k, m_mot, (fired - mot) * area_ds, textbook_k], axis=-1)


class _CylinderParts(eqx.Module):
    """What one ordinary cylinder's functions (:func:`_one_cylinder`) depend on: the engine's
    geometry, masses and pressure, not its cylinders or their layout."""

    geometry: Any
    masses: Any
    pressure: Any
    strokes: int = eqx.field(static=True)
    cycle_rad: float = eqx.field(static=True)


@eqx.filter_jit
def _cylinder_functions(parts, fidelity, points):
    """:func:`_one_cylinder` and its dφ-derivative on ``points`` nodes over the cycle: the
    costly part of the tables, compiled once for engines with any number of cylinders."""
    phi = jnp.arange(points) * (parts.cycle_rad / points)
    return jax.jvp(lambda x: _one_cylinder(parts, fidelity, x), (phi,), (jnp.ones_like(phi),))


def _shifted_columns(engine, fidelity, points, cylinder=None):
    """All columns from one cylinder's functions (``cylinder``: those of
    :func:`_cylinder_functions`, else computed here), shifted to each cylinder's phase."""
    cycle = engine.cycle_rad
    phi = jnp.arange(points) * (cycle / points)
    if cylinder is None:
        cylinder = jax.jvp(lambda x: _one_cylinder(engine, fidelity, x), (phi,), (jnp.ones_like(phi),))
    v1, d1 = cylinder
    tdc = jnp.deg2rad(engine.tdc_angles_deg)
    fire_phase = engine.firing_angles_rad - (2 * np.pi if engine.strokes == 4 else 0.0)
    # each cylinder: I and k at its mechanical angle θ − tdc, torques at its cycle angle
    mech = jax.vmap(lambda o: _shifted(v1[:, [0, 1, 4]], d1[:, [0, 1, 4]], o, cycle))(tdc)  # (n, N, 3) twice
    fired = jax.vmap(lambda o: _shifted(v1[:, 2:4], d1[:, 2:4], o, cycle))(fire_phase)  # (n, N, 2) twice
    (i_v, k_v, tb_v), (i_d, k_d, _) = (jnp.moveaxis(a, -1, 0) for a in mech)  # each (n, N)
    (m_v, g_v), (m_d, g_d) = (jnp.moveaxis(a, -1, 0) for a in fired)
    textbook_k = jnp.sum(tb_v, axis=0)
    J = engine.crankshaft.inertia_kgm2
    if fidelity == "constant":
        inertia = mean_reduced_inertia(engine) + 0.0 * phi
        d_inertia = jnp.zeros_like(phi)
    else:
        inertia = J + jnp.sum(i_v, axis=0)
        d_inertia = jnp.sum(i_d, axis=0)
    values = jnp.concatenate([jnp.stack([inertia, jnp.sum(k_v, axis=0), jnp.sum(m_v, axis=0)]), g_v]).T
    slopes = jnp.concatenate([jnp.stack([d_inertia, jnp.sum(k_d, axis=0), jnp.sum(m_d, axis=0)]), g_d]).T
    work_m = jnp.sum(v1[:, 2]) * cycle / points
    return values, slopes, jnp.full(engine.cylinders, work_m), textbook_k


@engine_jit
def _build(engine, fidelity, points, cylinder=None):
    cycle = engine.cycle_rad
    w = cycle / points  # periodic trapezoid rule: spectrally accurate
    if engine.articulated is None:
        values, slopes, work_m, textbook_k = _shifted_columns(engine, fidelity, points, cylinder)
    else:  # slave rods move differently: every cylinder on its own
        theta = jnp.arange(points) * w
        (values, m_mot), (slopes, _) = jax.jvp(
            lambda t: _columns(engine, fidelity, t), (theta,), (jnp.ones_like(theta),)
        )
        work_m = jnp.sum(m_mot, axis=0) * w
        textbook_k = reciprocating_inertia_torque(engine, theta, 1.0)
    vh = engine.geometry.displacement_m3
    imep_c = jnp.sum(values[:, COL_COMBUSTION:], axis=0) * w / vh
    firing = jnp.mod(engine.firing_angles_rad, cycle)
    torque_cols = jnp.concatenate([values[:, COL_MOTORED : COL_MOTORED + 1], values[:, COL_COMBUSTION:]], axis=1)
    torque_slopes = jnp.concatenate([slopes[:, COL_MOTORED : COL_MOTORED + 1], slopes[:, COL_COMBUSTION:]], axis=1)
    means = jnp.mean(torque_cols, axis=0)  # periodic: the Hermite rule is the trapezoid rule
    wrap = jnp.concatenate([torque_cols, torque_cols[:1]]) - means, jnp.concatenate([torque_slopes, torque_slopes[:1]])
    work = cumulative_columns(*wrap, w)
    plain = jnp.concatenate([textbook_k[:, None], torque_cols], axis=1)
    textbook_work = jnp.cumsum(plain - jnp.mean(plain, axis=0), axis=0) * w
    return (
        values,
        slopes,
        work_m / vh,
        imep_c,
        jnp.mean(values[:, COL_I]),
        firing,
        textbook_k,
        means,
        work,
        textbook_work,
    )


def _build_now(engine, fidelity, points):
    """:func:`_build` run now as compiled programs of their own, also where the caller is
    being traced (a jitted function closing over a concrete engine): the tables are values,
    kept for the calls after, never part of that trace. One ordinary cylinder's functions
    (:func:`_cylinder_functions`) are computed first, by a program shared by engines with any
    number of cylinders; the articulated rods and the A/B/C form build all in one."""
    engine = unnamed(engine)  # one program for every name, as _build is compiled
    cylinder = None
    if engine.articulated is None and fidelity != "coefficients":
        parts = _CylinderParts(engine.geometry, engine.masses, engine.pressure, engine.strokes, engine.cycle_rad)
        cylinder = _now(_cylinder_functions, parts, fidelity, points)
    return _now(_build, engine, fidelity, points, cylinder)


_COMPILED: OrderedDict[tuple, Any] = OrderedDict()


def _now(fn, *args):
    """``fn(*args)`` (a compiled function of equinox's) run by its compiled program, kept per
    structure of ``args`` (the shapes of their arrays, their other values): a compiled
    program runs on the values it is given, also from inside a trace."""
    leaves, treedef = jax.tree_util.tree_flatten(args)
    sig = tuple((x.shape, x.dtype.str) if eqx.is_array(x) else ("static", repr(x)) for x in leaves)
    key = (fn, treedef, sig)
    compiled = _COMPILED.get(key)
    if compiled is None:
        compiled = fn.lower(*args).compile()
        _COMPILED[key] = compiled
        while len(_COMPILED) > 2 * TABLE_CACHE_SIZE:
            _COMPILED.popitem(last=False)
    _COMPILED.move_to_end(key)
    return compiled(*args)


def cumulative_columns(f, df, h):
    """∫ from node 0 to each node of every column of ``f`` (nodes 0…N down the rows, with
    their dθ-derivatives ``df``) by the Hermite rule, step ``h`` [rad]:
    h/2·(f₀+f₁) + h²/12·(f₀′−f₁′) per step."""
    seg = 0.5 * h * (f[:-1] + f[1:]) + h * h / 12.0 * (df[:-1] - df[1:])
    return jnp.concatenate([jnp.zeros((1, f.shape[1])), jnp.cumsum(seg, axis=0)])


def crank_train(engine: Engine, fidelity: str = "variable", grid_deg: float = 0.25) -> CrankTrain:
    """Prepare ``engine`` for the equation of motion (tables over one cycle).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``fidelity``: ``"variable"`` (default), ``"series"``, ``"coefficients"`` or ``"constant"``.
    - ``grid_deg``: node spacing [deg]; must divide the cycle (default 0.25°).

    A traced engine field (``jax.jit``/``vmap``/``grad``) is checked when the program runs
    (:func:`rotor.engine.model.guard_engine`).
    """
    check_fidelity(fidelity, require_engine(engine, "crank_train(engine)"))
    if tracing() and called_from_outside():  # traced fields: checked when the program runs
        engine = guard_engine(engine)
    return train_from_engine(engine, fidelity, grid_points(engine.strokes, grid_deg, engine.cylinders))


def train_from_engine(engine: Engine, fidelity: str, points: int) -> CrankTrain:
    """:func:`crank_train` with the node count given (usable inside jit). A concrete
    ``engine`` is checked again first (:meth:`rotor.Engine.check`) and its tables after:
    every value finite and I(θ) > 0, or a :class:`rotor.EngineError` naming the column.

    Tables of a concrete engine are kept (:func:`table_key`: keyed on the values of every
    field they depend on) and reused by the next call with the same values; the crankshaft
    inertia ``[crankshaft] inertia_kgm2`` is a constant added to I(θ), so a new value of it
    (a flywheel sweep) reuses them too. The tables are built at no crankshaft inertia and
    that inertia added after, so that an engine's tables are the same numbers whatever was
    computed before, in this process or another. Traced fields (inside ``jit``, ``vmap``,
    ``grad``) build the tables in the trace, except a traced crankshaft inertia: it is
    added to tables built outside the trace.

    An engine object is immutable: one that was checked and found here before (at this
    fidelity and node count) is neither checked nor digested again."""
    known = _known_object(engine, fidelity, points)
    if known is not None:
        return known
    check_engine(engine, "train_from_engine(engine)")
    given = engine
    engine = arrays_only(engine)
    key = table_key(engine, fidelity, points)
    if key is None:  # traced inputs besides the crankshaft inertia: the tables in the trace
        tables = dict(zip(_TABLE_NAMES, _build(engine, fidelity, points)))
        return _train(tables, engine, fidelity)
    hit = _TABLES.get(key) or _find_tables(key, engine, fidelity, points)
    _TABLES.move_to_end(key)
    kept = hit
    given_inertia = concrete(engine.crankshaft.inertia_kgm2)  # NumPy where concrete: no program for a difference
    d_inertia = (engine.crankshaft.inertia_kgm2 if given_inertia is None else given_inertia) - kept.inertia_ref
    d = concrete(d_inertia)
    if d is not None:
        check_inertia(kept.low + d, kept.mean + d, engine)
    if d is not None and d.ndim == 0:
        # concrete: shifted now, also where the caller is being traced (the train is kept for
        # the engine object, and a value of a trace must not outlive it)
        with jax.ensure_compile_time_eval():
            train = kept.train if d == 0 else shift_inertia(kept.train, d_inertia)
        remember_object(key, given, train)
        return train
    return shift_inertia(kept.train, d_inertia)


def _find_tables(key: str, engine: Engine, fidelity: str, points: int) -> KeptTables:
    """The tables of ``engine`` (concrete but for its crankshaft inertia) under ``key``: read
    from the table folder, as another process built and checked them, else built and kept."""
    hit = _read_kept(key, engine, fidelity)
    if hit is not None:
        return hit
    # built at no crankshaft inertia, which the caller adds: whichever inertia comes first,
    # the same numbers in every process and in any order of calls
    base = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, np.zeros((), np.float64))
    tables = dict(zip(_TABLE_NAMES, _build_now(base, fidelity, points)))
    check_finite_tables(tables["values"], tables["slopes"], engine)
    keep_tables(key, {**{k: np.asarray(v) for k, v in tables.items()}, "inertia_ref": np.zeros(())})
    _remember_tables(key, _train(tables, engine, fidelity), 0.0)
    return _TABLES[key]


def _read_kept(key: str, engine: Engine, fidelity: str) -> KeptTables | None:
    """The tables kept on disk under ``key`` (:func:`rotor.cache.kept_tables`), put into this
    process's table cache as built with their own crankshaft inertia (the caller shifts
    them to ``engine``'s); None where none are kept."""
    stored = kept_tables(key)
    if stored is None or set(stored) != {*_TABLE_NAMES, "inertia_ref"}:
        return None
    with jax.ensure_compile_time_eval():  # arrays, not values of a trace this call may be in
        train = _train({name: jax.device_put(np.asarray(stored[name])) for name in _TABLE_NAMES}, engine, fidelity)
    _remember_tables(key, train, float(stored["inertia_ref"]))
    return _TABLES[key]


def _train(t: dict, engine: Engine, fidelity: str) -> CrankTrain:
    """A :class:`CrankTrain` of the table builder's arrays (:data:`_TABLE_NAMES`)."""
    return CrankTrain(
        t["values"],
        t["slopes"],
        t["firing"],
        t["imep_m"],
        t["imep_c"],
        t["mean_i"],
        t["textbook_k"],
        t["means"],
        t["work"],
        t["tb_work"],
        engine.cycle_rad,
        engine.strokes,
        fidelity,
    )


KNOWN_OBJECTS = 64
"""How many engine objects the table cache remembers as checked, with their tables (the
most recently used)."""

_KNOWN: OrderedDict[int, tuple[weakref.ref, dict[tuple[str, int], tuple[str, CrankTrain]]]] = OrderedDict()
"""Engine objects checked and found before, by ``id``: a weak reference to the object (an
engine that is dropped is not kept alive, and its entry goes with it) and, per fidelity
and node count, the key of its entry in the table cache and its tables with its own
crankshaft inertia."""


def remember_object(key: str, engine: Any, train: CrankTrain) -> None:
    """Remember that the engine object ``engine`` was checked and has the tables ``train``
    (its own crankshaft inertia added to those kept under ``key``)."""
    ident = id(engine)
    entry = _KNOWN.get(ident)
    if entry is None or entry[0]() is not engine:

        def forget(ref: weakref.ref, ident: int = ident) -> None:
            if ident in _KNOWN and _KNOWN[ident][0] is ref:
                del _KNOWN[ident]

        entry = (weakref.ref(engine, forget), {})
        _KNOWN[ident] = entry
    entry[1][(train.fidelity, train.points)] = (key, train)
    _KNOWN.move_to_end(ident)
    while len(_KNOWN) > KNOWN_OBJECTS:
        _KNOWN.popitem(last=False)


def _known_object(engine: Any, fidelity: str, points: int) -> CrankTrain | None:
    """The tables of ``engine`` if this very object was checked and its tables found
    before, at ``fidelity`` and ``points`` nodes, and they are still kept; else None."""
    entry = _KNOWN.get(id(engine))
    if entry is None or entry[0]() is not engine:
        return None
    hit = entry[1].get((fidelity, points))
    if hit is None or hit[0] not in _TABLES:
        return None
    _TABLES.move_to_end(hit[0])
    _KNOWN.move_to_end(id(engine))
    return hit[1]


def checked_train(engine: Any, fidelity: str, points: int, call: str = "engine") -> CrankTrain:
    """``engine``'s tables at ``fidelity`` on ``points`` nodes, ``engine`` and ``fidelity``
    checked first (:func:`check_fidelity`, :func:`train_from_engine`), as
    :func:`rotor.prepare` does: once per engine object, which is immutable. ``call``
    names the argument in a :class:`TypeError` for what is not an engine."""
    known = _known_object(engine, fidelity, points)
    if known is not None:
        return known
    check_fidelity(fidelity, require_engine(engine, call), recheck=False)
    return train_from_engine(engine, fidelity, points)


def shift_inertia(train: CrankTrain, d_inertia: ArrayLike) -> CrankTrain:
    """``train`` with ``d_inertia`` [kg·m²] added to I(θ) and its mean: the tables of the
    same engine with another crankshaft inertia (a constant in I(θ) at every fidelity)."""
    values, mean = _inertia_added(train.values, train.mean_inertia, d_inertia)
    return eqx.tree_at(lambda t: (t.values, t.mean_inertia), train, (values, mean))


@kept_program()
@jax.jit
def _inertia_added(values: Array, mean_inertia: Array, d_inertia: ArrayLike) -> tuple[Array, Array]:
    return values.at[:, COL_I].add(d_inertia), mean_inertia + d_inertia


# ----------------------------------------------------------------------------- the table cache
TABLE_CACHE_SIZE = 16
"""How many engines' tables :func:`train_from_engine` keeps (least recently used go first)."""


class KeptTables:
    """One entry of the table cache: ``train``, the crankshaft inertia it was built with
    (``inertia_ref`` [kg·m²]), its smallest and mean I(θ) (``low``, ``mean`` [kg·m²], read
    off ``train`` once)."""

    __slots__ = ("train", "inertia_ref", "low", "mean")

    def __init__(self, train: CrankTrain, inertia_ref: float):
        self.train, self.inertia_ref = train, inertia_ref
        self.low = float(np.min(np.asarray(train.values)[:, COL_I]))
        self.mean = float(train.mean_inertia)


_TABLES: OrderedDict[str, KeptTables] = OrderedDict()
_TABLE_NAMES = ("values", "slopes", "imep_m", "imep_c", "mean_i", "firing", "textbook_k", "means", "work", "tb_work")
"""What the table builder returns, in its order: the names its arrays are kept under on disk
(:func:`rotor.cache.keep_tables`)."""


def table_inputs(engine: Engine) -> tuple:
    """Every part of ``engine`` its tables depend on, besides the crankshaft inertia (a
    constant added to I(θ)): strokes, cylinders, ``[geometry]``, ``[masses]``,
    ``[layout]``, ``[pressure]`` and the articulated rods."""
    return (
        engine.strokes,
        engine.cylinders,
        engine.geometry,
        engine.masses,
        engine.layout,
        engine.pressure,
        engine.articulated,
    )


def table_key(engine: Engine, fidelity: str, points: int) -> str | None:
    """A digest of the values of :func:`table_inputs` (every number, bit for bit, and the
    structure with its static fields), the fidelity and the node count; None when any of
    them is traced (no key can be made of a value not yet known)."""
    leaves, treedef = jax.tree_util.tree_flatten(table_inputs(engine))
    if any(isinstance(leaf, jax.core.Tracer) for leaf in leaves):
        return None
    digest = hashlib.blake2b(repr((treedef, fidelity, points)).encode(), digest_size=20)
    for leaf in leaves:
        a = np.asarray(leaf)
        digest.update(f"{a.dtype.str}{a.shape}".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


def _remember_tables(key: str, train: CrankTrain, inertia_ref: float) -> None:
    """Keep ``train``, built with crankshaft inertia ``inertia_ref`` [kg·m²], under ``key``
    (:func:`table_key`), dropping the least recently used beyond :data:`TABLE_CACHE_SIZE`."""
    _TABLES[key] = KeptTables(train, inertia_ref)
    while len(_TABLES) > TABLE_CACHE_SIZE:
        _TABLES.popitem(last=False)


def clear_table_cache() -> None:
    """Forget every table kept in this process (:func:`train_from_engine`); the next call reads
    them from the table folder (:func:`rotor.cache.table_folder`, where tables are kept
    between processes) or builds them again."""
    _TABLES.clear()
    _KNOWN.clear()


_COLUMN_CAUSE = {
    COL_I: ("the reduced inertia I(θ)", "kg·m²", "[crankshaft] inertia_kgm2, [masses] and [geometry]"),
    COL_K: ("the reciprocating inertia torque per ω²", "kg·m²", "[masses] reciprocating_kg and [geometry]"),
    COL_MOTORED: ("the motored gas torque", "N·m", "[pressure] and [geometry] bore_m"),
}


def check_inertia(low: Any, mean: Any, engine: Engine) -> None:
    """Refuse a smallest reduced inertia ``low`` or a mean ``mean`` [kg·m²] that is not
    positive (each may be an array: a sweep over the crankshaft inertia)."""
    low, mean = np.asarray(low), np.asarray(mean)
    if not (np.all(low > 0) and np.all(np.isfinite(mean)) and np.all(mean > 0)):
        raise EngineError(
            f"engine {engine.name!r}: the reduced inertia I(θ) falls to {np.min(low):g} kg·m² (mean "
            f"{np.min(mean):g}): it must stay positive; check [crankshaft] inertia_kgm2 and [masses]"
        )


def check_finite_tables(values: Any, slopes: Any, engine: Engine) -> None:
    """Refuse tables of a concrete ``engine`` with a value or slope that is not finite: a
    :class:`rotor.EngineError` naming the column and the inputs it comes from. (That I(θ)
    stays positive is checked with the crankshaft inertia added, :func:`train_from_engine`.)"""
    v, d = np.asarray(values), np.asarray(slopes)
    for col in range(v.shape[1]):
        what, unit, cause = _COLUMN_CAUSE.get(
            col, (f"cylinder {col - COL_COMBUSTION + 1}'s combustion torque", "N·m", "[pressure] and [geometry]")
        )
        for table, name in ((v, ""), (d, " (its slope)")):
            bad = ~np.isfinite(table[:, col])
            if np.any(bad):
                i = int(np.argmax(bad))
                deg = np.rad2deg(i * engine.cycle_rad / v.shape[0])
                raise EngineError(
                    f"engine {engine.name!r}: {what}{name} is {table[i, col]:g} {unit} at {deg:g}°: not a finite "
                    f"number; check {cause}"
                )
