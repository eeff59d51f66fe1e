"""Flywheel sizing: the textbook rule and the smallest flywheel found through the simulator.

**Textbook** (Shishkov, "Dinamika dvigatelei" [Engine dynamics: guide to the course project],
South Ural State University, 2014, §3.2.12, after Kolchin & Demidov and Popyk): from one turning-moment diagram at constant speed (gas
plus reciprocating inertia torque), the excess work L_excess (the largest swing of
∫(M − M_mean)dθ) gives the inertia of everything that turns, J₀ = L_excess/(δ·ω²); the
flywheel takes J_flywheel = 0.85·J₀ and, at a mean diameter D = (2…3)·S, a mass
m = 4·J_flywheel/D² (a thin rim).

**Through the simulator** (:func:`design_flywheel`): the smallest ``[crankshaft]
inertia_kgm2`` for which the periodic steady state (:func:`rotor.steady_state`, with the
variable inertia I(θ), friction and the load of each point) has δ ≤ δ_target at every
operating point. δ falls monotonically with the inertia, so at each point the inertia that
gives exactly δ_target is the root of log δ(J) − log δ_target in u = log J, found by
Newton's method (optimistix) with dδ/dJ by forward-mode autodiff through the steady state;
log δ is nearly linear in log J (δ ∝ 1/J to first order), so it converges in a few steps.
The design is the largest of these roots; its point is the binding one.

The flywheel enters the one-degree-of-freedom model only through its inertia, so the
lightest flywheel splits exactly from the inertia: a disc of outer diameter D, bore d and
width b has J = ρπb(D⁴ − d⁴)/32 and m = 8J/(D² + d²), so for the required inertia the
lightest disc is the widest allowed diameter (outer diameter and rim-speed limits), with
the width that gives the inertia, which must not exceed the width limit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any, Literal, NamedTuple, cast

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Float

from ..dynamics.loads import Load, parse_load
from ..dynamics.prepared import PreparedEngine, checked_on_host, nameless, prepare, resolve_engine
from ..dynamics.steady import steady_state
from ..engine.friction import Friction
from ..engine.inertia import mean_reduced_inertia
from ..engine.model import Engine, require_engine
from ..engine.plausible import PLAUSIBLE, check_results_finite, check_speed_rpm, require_known, require_number
from ..errors import EngineError, NoSteadyStateError, SolverError
from ..plotting.design import plot_disc_flywheel, plot_flywheel_design, plot_textbook_flywheel
from ..programs import kept_program
from ..results import Result, json_safe
from ..units import rpm_to_rad_s

__all__ = [
    "OperatingPoint",
    "TextbookFlywheel",
    "DiscFlywheel",
    "PointResult",
    "DeltaSweep",
    "FlywheelDesign",
    "DeltaOfInertia",
    "textbook_flywheel",
    "design_flywheel",
    "lightest_disc",
    "disc_limits",
    "DiscLimits",
    "MAX_WIDTH_PER_DIAMETER",
    "inertia_for_delta",
    "with_crankshaft_inertia",
]

MAX_INERTIA_KGM2 = PLAUSIBLE[("crankshaft", "inertia_kgm2")][1]
"""The largest crankshaft inertia rotor takes [kg·m²] (see :data:`rotor.engine.plausible.PLAUSIBLE`)."""
DENSITY_RANGE_KG_M3 = (100.0, 25000.0)
"""Plausible flywheel material densities [kg/m³]: from foams and wood to tungsten alloys."""
MAX_DISC_DIAMETER_M = 20.0
"""The largest disc :func:`lightest_disc` makes [m]: a limit that allows more is a unit mistake."""
MAX_SWEEP_SPEEDS = 2000
"""The most speeds a δ sweep takes (each is one steady state: 2000 take about a minute)."""
TEXTBOOK_SHARE = 0.85  # Shishkov (2014) §3.2.12: J_flywheel = 0.85·J₀
CAST_IRON_KG_M3 = 7200.0

#: what a friction argument may be, as in :func:`rotor.steady_state`
FrictionArg = Friction | Literal[False] | None


class OperatingPoint(NamedTuple):
    """One operating point: mean speed ``rpm`` [rev/min], the fuelling ``imep_scale``
    (combustion scale [-], 1 = the engine file's pressure; one number or one per
    cylinder), a ``load`` (None: a constant load balances the engine's mean torque at this
    fuelling; any load, or its spec such as ``"propeller:3000,1250"``: the fuelling is
    scaled to carry it) and its own target ``delta`` [-] (None: the design's;
    e.g. a looser one at idle)."""

    rpm: float
    imep_scale: float | Sequence[float] = 1.0
    load: Load | str | None = None
    delta: float | None = None


PointsArg = float | OperatingPoint | Sequence[float | OperatingPoint | tuple] | None


def _points(points: PointsArg, engine: Engine) -> list[OperatingPoint]:
    if points is None:
        points = [float(engine.operating.rpm)]
    if isinstance(points, (int, float, OperatingPoint)):
        points = [points]
    if isinstance(points, (str, bytes)) or not isinstance(points, (Sequence, np.ndarray)):
        raise TypeError(
            f"points: expected rpm values, OperatingPoints or a list of them, got {type(points).__name__} {points!r:.40}"
        )
    out = []
    for given in points:
        p = (
            given
            if isinstance(given, OperatingPoint)
            else OperatingPoint(*given)
            if isinstance(given, tuple)
            else OperatingPoint(cast(float, given))
        )
        rpm = check_speed_rpm(p.rpm, "operating point rpm")
        try:
            scale = np.asarray(p.imep_scale, dtype=float)
        except (TypeError, ValueError):
            scale = np.array(np.nan)
        if not (np.all(np.isfinite(scale)) and np.all(scale >= 0)) or scale.shape not in ((), (engine.cylinders,)):
            raise EngineError(
                f"operating point at {rpm:g} rpm: imep_scale = {p.imep_scale!r} must be one number ≥ 0 "
                f"or one per cylinder ({engine.cylinders})"
            )
        load = parse_load(p.load) if isinstance(p.load, str) else p.load
        if load is not None and not isinstance(load, Load):
            raise EngineError(
                f"operating point at {rpm:g} rpm: load = {p.load!r} is not a load (a rotor.ConstantLoad, "
                "rotor.PropellerLoad, … or a spec such as 'propeller:3000,1250')"
            )
        if p.delta is not None:
            _check_delta(p.delta)
        out.append(OperatingPoint(rpm, p.imep_scale, load, p.delta))
    if not out:
        raise EngineError("no operating points: give at least one rpm")
    return out


DELTA_MIN = 1e-5
"""The smallest target δ a design takes [-]: generator sets, the most demanding, ask for
about 1/300; at 1e-6 the root find on 4chn15 no longer converges (the δ of the steady
state nears the solver's own noise), and 1e-5 already asks 700 times 4chn15's inertia."""


def _known_values(call: str, **values: Any) -> None:
    """Refuse a value traced by ``jax.jit``/``vmap``/``grad``, naming ``call(argument)``."""
    require_known(call, "the design searches on the host, over compiled steady states", **values)


def _check_delta(delta: float) -> float:
    d = require_number(delta, "delta")
    if not (math.isfinite(d) and 0 < d < 1):
        raise EngineError(
            f"delta = {delta!r}: the target irregularity (ω_max − ω_min)/ω_mean must lie in (0, 1), e.g. 0.01 for 1 %"
        )
    if d < DELTA_MIN:
        raise EngineError(
            f"delta = {delta!r}: a target below {DELTA_MIN:g} asks for an inertia past any flywheel "
            "(generator sets ask about 0.003); give a larger delta"
        )
    return d


def _one_row(result: Any) -> Any:
    import pandas as pd

    return pd.DataFrame([asdict(result)])


# ----------------------------------------------------------------------------- textbook
@dataclass(frozen=True, repr=False)
class TextbookFlywheel(Result):
    """The textbook sizing at one operating point (Shishkov (2014) §3.2.12), SI units.

    ``rpm`` [rev/min] and ``delta`` [-]: the point and the target; ``excess_work_J`` [J]:
    L_excess of the point's turning-moment diagram; ``total_inertia_kgm2`` is J₀
    (everything that turns and reciprocates); ``crankshaft_inertia_kgm2`` is J₀ less the
    cycle-mean inertia of the rods and pistons, the ``[crankshaft] inertia_kgm2`` the
    textbook implies; ``flywheel_kgm2`` = 0.85·J₀, ``mean_diameter_m`` =
    ``diameter_strokes``·S and ``mass_kg`` = 4·J_flywheel/D² (a thin rim)."""

    rpm: float
    delta: float
    excess_work_J: float
    total_inertia_kgm2: float
    crankshaft_inertia_kgm2: float
    flywheel_kgm2: float
    mean_diameter_m: float
    mass_kg: float

    @property
    def mechanism_inertia_kgm2(self) -> float:
        """The cycle-mean inertia of the rods and pistons, J₀ less the crankshaft [kg·m²]."""
        return self.total_inertia_kgm2 - self.crankshaft_inertia_kgm2

    def summary(self) -> str:
        """The textbook sizing, step by step, as text."""
        omega = rpm_to_rad_s(self.rpm)
        lines = [
            f"textbook flywheel (Shishkov 2014, §3.2.12) at {self.rpm:g} rpm for δ = {self.delta:g}",
            f"  {'excess work L_excess':42} {self.excess_work_J:10.1f} J",
            f"  {f'J₀ = L_excess/(δ·ω²), ω = {omega:.1f} rad/s':42} {self.total_inertia_kgm2:10.4f} kg·m²",
            f"  {'rods and pistons (cycle mean)':42} {self.mechanism_inertia_kgm2:10.4f} kg·m²",
            f"  {'[crankshaft] inertia_kgm2 (J₀ less them)':42} {self.crankshaft_inertia_kgm2:10.4f} kg·m²"
            + ("" if self.crankshaft_inertia_kgm2 > 0 else "  (not applicable: < 0)"),
            f"  {'flywheel 0.85·J₀':42} {self.flywheel_kgm2:10.4f} kg·m²",
            f"  {f'as a rim of mean diameter {self.mean_diameter_m:.3f} m':42} {self.mass_kg:10.1f} kg",
        ]
        if self.delta > 0.2:
            lines.append(f"  (δ = {self.delta:g} is not small: the textbook's first-order theory does not hold)")
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """One row: the fields, units in their names."""
        return _one_row(self)

    def to_json_dict(self) -> dict:
        """The fields as plain JSON; ``crankshaft_inertia_kgm2`` is null, with a ``note``,
        where J₀ is smaller than the rods' and pistons' own inertia (the textbook does not
        apply: a [crankshaft] inertia is never negative)."""
        d: dict[str, Any] = asdict(self)
        d["note"] = None
        if not self.crankshaft_inertia_kgm2 > 0:
            d["crankshaft_inertia_kgm2"] = None
            d["note"] = (
                f"not applicable: J₀ = {self.total_inertia_kgm2:.4g} kg·m² is smaller than the rods' and pistons' "
                f"own mean inertia ({self.mechanism_inertia_kgm2:.4g} kg·m²)"
            )
        return json_safe(d)

    def plot(self, ax: Any = None) -> Any:
        """The split of J₀ [kg·m²] (bars); see :func:`rotor.plotting.plot_textbook_flywheel`."""
        return plot_textbook_flywheel(self, ax=ax)


def _textbook(
    engine: Engine,
    delta: float,
    point: OperatingPoint,
    excess_work: float,
    mechanism_inertia: float,
    diameter_strokes: float,
) -> TextbookFlywheel:
    omega = rpm_to_rad_s(point.rpm)
    j0 = excess_work / (delta * omega**2)
    jf = TEXTBOOK_SHARE * j0
    dm = diameter_strokes * float(engine.geometry.stroke_m)
    return TextbookFlywheel(
        rpm=point.rpm,
        delta=delta,
        excess_work_J=excess_work,
        total_inertia_kgm2=j0,
        crankshaft_inertia_kgm2=j0 - mechanism_inertia,
        flywheel_kgm2=jf,
        mean_diameter_m=dm,
        mass_kg=4 * jf / dm**2,
    )


def textbook_flywheel(
    engine: Engine,
    delta: float,
    rpm: float | None = None,
    *,
    imep_scale: float | Sequence[float] = 1.0,
    load: Load | str | None = None,
    diameter_strokes: float = 2.5,
    fidelity: str = "variable",
    friction: FrictionArg = None,
    grid_deg: float = 0.25,
) -> TextbookFlywheel:
    """The textbook flywheel of Shishkov (2014) §3.2.12 at one operating point.

    **Arguments:** ``engine`` (a :class:`rotor.Engine`); ``delta``, the target irregularity
    [-]; ``rpm`` [rev/min] (default ``[operating] rpm``); ``imep_scale`` [-] and ``load`` as
    in :func:`rotor.steady_state`; ``diameter_strokes``, the mean diameter in strokes (the
    textbook's 2…3) [-]; ``fidelity``, ``friction``, ``grid_deg`` [deg] as in
    :func:`rotor.steady_state`.

    **Returns:** a :class:`TextbookFlywheel`.

    **Raises:** :class:`rotor.EngineError` for a bad argument; :class:`rotor.NoSteadyStateError`
    where the engine has no steady state at this point with its own inertia; a
    :class:`TypeError` for a value of the wrong type or traced by ``jax.jit``/``vmap``/``grad``.
    """
    _known_values("textbook_flywheel", engine=engine, delta=delta, rpm=rpm, imep_scale=imep_scale, load=load)
    require_engine(engine, "textbook_flywheel(engine)").check()
    delta = _check_delta(delta)
    _number("diameter_strokes", diameter_strokes, 0.0, hi=100.0)
    (point,) = _points([OperatingPoint(float(engine.operating.rpm) if rpm is None else rpm, imep_scale, load)], engine)
    ev = DeltaOfInertia(engine, fidelity, friction, grid_deg)
    _, excess = ev.state(float(engine.crankshaft.inertia_kgm2), point)
    return _textbook(engine, delta, point, excess, ev.mechanism_kgm2, diameter_strokes)


# ----------------------------------------------------------------------------- through the simulator
def with_crankshaft_inertia(engine: Engine, inertia_kgm2: float | Float[jax.Array, ""]) -> Engine:
    """``engine`` with ``[crankshaft] inertia_kgm2`` replaced by ``inertia_kgm2`` [kg·m²];
    works on a traced value too (for ``jax.grad`` or ``jax.vmap`` over the inertia)."""
    return eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, jnp.asarray(inertia_kgm2, dtype=jnp.float64))


@kept_program()
@eqx.filter_jit
def _state(
    prepared: PreparedEngine, inertia: Any, rpm: Any, scale: Any, load: Load | None, friction: FrictionArg
) -> tuple[Any, Any]:
    """δ (NaN where the crankshaft nearly stops) and the textbook excess work [J] of the
    steady state with ``[crankshaft] inertia_kgm2 = inertia``, from the prepared tables
    (:class:`DeltaOfInertia`'s own, made by :func:`rotor.prepare` and never changed)."""
    prepared = checked_on_host(prepared)
    r = steady_state(prepared.with_inertia(inertia), rpm, load, friction=friction, imep_scale=scale, throw=False)
    ok = r.converged & (jnp.min(r.omega) > 0.01 * r.mean_omega)
    return jnp.where(ok, r.delta, jnp.nan), r.excess_work_J


@eqx.filter_jit
def _root(
    prepared: PreparedEngine,
    u0: Any,
    log_target: Any,
    rpm: Any,
    scale: Any,
    load: Load | None,
    friction: FrictionArg,
    rtol: float,
) -> tuple[Any, Any, Any]:
    import optimistix as optx  # here: a flywheel's state alone (the report's) needs no root finder

    def fn(u, _):
        d, _ = _state(prepared, jnp.exp(u), rpm, scale, load, friction)
        return jnp.log(d) - log_target

    sol: Any = optx.root_find(fn, optx.Newton(rtol=rtol, atol=rtol), u0, max_steps=60, throw=False)
    return sol.value, sol.result == optx.RESULTS.successful, sol.stats["num_steps"]


class DeltaOfInertia:
    """The steady state of one engine at operating points as a function of its
    ``[crankshaft] inertia_kgm2``, compiled once (the closed form of
    :func:`rotor.steady_state`). Where the crankshaft nearly stops within the cycle, δ is
    NaN instead of an error, so that a search over the inertia can step past it.

    **Arguments:** ``engine`` (a :class:`rotor.Engine`); ``fidelity``, ``friction`` and
    ``grid_deg`` [deg] as in :func:`rotor.steady_state`.

    ``mechanism_kgm2``: the cycle-mean inertia of the rods and pistons [kg·m²].
    """

    def __init__(
        self, engine: Engine, fidelity: str = "variable", friction: FrictionArg = None, grid_deg: float = 0.25
    ):
        self.friction = friction
        # the tables are built once, outside the compiled search: the crankshaft inertia only
        # shifts I(θ), so every inertia the search tries reuses them
        # its name left out: another engine of the same shape runs the same compiled search
        self.prepared = nameless(prepare(engine, fidelity, grid_deg))
        self.mechanism_kgm2 = float(mean_reduced_inertia(engine)) - float(engine.crankshaft.inertia_kgm2)

    def _args(self, point: OperatingPoint) -> tuple[Any, Any, Any]:
        rpm = jnp.asarray(point.rpm, dtype=jnp.float64)
        scale = jnp.asarray(point.imep_scale, dtype=jnp.float64)
        return rpm, scale, point.load

    def state(self, inertia_kgm2: float, point: OperatingPoint) -> tuple[float, float]:
        """δ [-] (NaN where the crankshaft nearly stops) and the textbook excess work [J]
        at ``point`` (its load already parsed) with ``[crankshaft] inertia_kgm2`` [kg·m²]."""
        out = _state(self.prepared, jnp.asarray(inertia_kgm2, dtype=jnp.float64), *self._args(point), self.friction)
        delta, excess = (float(v) for v in jax.device_get(out))
        return delta, excess

    def delta(self, inertia_kgm2: float, point: OperatingPoint) -> float:
        """δ [-] at ``point`` with ``[crankshaft] inertia_kgm2`` [kg·m²] (NaN where the
        crankshaft nearly stops)."""
        return self.state(inertia_kgm2, point)[0]

    def root(self, u0: float, log_target: float, point: OperatingPoint, rtol: float) -> tuple[float, bool, int]:
        """Newton's method on log δ(e^u) = ``log_target`` from ``u0`` (u = log of the
        inertia in kg·m²) to relative tolerance ``rtol`` [-]: u, whether it converged, and
        the number of steps."""
        u, ok, steps = _root(
            self.prepared,
            jnp.asarray(u0, dtype=jnp.float64),
            jnp.asarray(log_target),
            *self._args(point),
            self.friction,
            rtol,
        )
        return float(u), bool(ok), int(steps)


def inertia_for_delta(
    engine: Engine,
    delta: float,
    rpm: float | None = None,
    *,
    imep_scale: float | Sequence[float] = 1.0,
    load: Load | str | None = None,
    fidelity: str = "variable",
    friction: FrictionArg = None,
    grid_deg: float = 0.25,
    rtol: float = 1e-10,
) -> float:
    """The ``[crankshaft] inertia_kgm2`` [kg·m²] at which the steady state at one operating
    point has exactly δ = ``delta`` [-] (Newton's method through :func:`rotor.steady_state`).

    **Arguments:** ``engine`` (a :class:`rotor.Engine`); ``rpm`` [rev/min] (default
    ``[operating] rpm``); ``imep_scale`` [-] and ``load`` as in :class:`OperatingPoint`;
    ``fidelity``, ``friction``, ``grid_deg`` [deg] as in :func:`rotor.steady_state`;
    ``rtol``: Newton tolerance on log J [-]. As :func:`design_flywheel` for one point,
    with the same errors.
    """
    _known_values("inertia_for_delta", engine=engine, delta=delta, rpm=rpm, imep_scale=imep_scale, load=load)
    require_engine(engine, "inertia_for_delta(engine)")
    design = design_flywheel(
        engine,
        delta,
        [OperatingPoint(float(engine.operating.rpm) if rpm is None else rpm, imep_scale, load)],
        fidelity=fidelity,
        friction=friction,
        grid_deg=grid_deg,
        rtol=rtol,
    )
    return design.crankshaft_inertia_kgm2


# ----------------------------------------------------------------------------- geometry
@dataclass(frozen=True, repr=False)
class DiscFlywheel(Result):
    """A steel or cast-iron disc flywheel: ``outer_diameter_m`` [m], ``bore_m`` [m],
    ``width_m`` (axial) [m], ``density_kg_m3`` [kg/m³], its ``inertia_kgm2`` [kg·m²] and
    ``mass_kg`` [kg], and its rim speed ``rim_speed_m_s`` [m/s] at ``peak_rpm`` [rev/min];
    ``limited_by``: the limit that sets the outer diameter (``"outer diameter"`` or
    ``"rim speed"``)."""

    outer_diameter_m: float
    bore_m: float
    width_m: float
    density_kg_m3: float
    inertia_kgm2: float
    mass_kg: float
    rim_speed_m_s: float
    peak_rpm: float
    limited_by: str

    def summary(self) -> str:
        """The disc in one line."""
        return (
            f"lightest disc: D = {self.outer_diameter_m:.3f} m ({self.limited_by} limit), bore "
            f"{self.bore_m:.3f} m, width {self.width_m * 1e3:.1f} mm, {self.mass_kg:.1f} kg, rim speed "
            f"{self.rim_speed_m_s:.1f} m/s at {self.peak_rpm:.0f} rpm (the highest speed it must stand)"
        )

    def to_pandas(self) -> Any:
        """One row: the fields, units in their names."""
        return _one_row(self)

    def to_json_dict(self) -> dict:
        """The fields as plain JSON."""
        return json_safe(asdict(self))

    def plot(self, ax: Any = None) -> Any:
        """The disc's axial section [mm]; see :func:`rotor.plotting.plot_disc_flywheel`."""
        return plot_disc_flywheel(self, ax=ax)


MAX_WIDTH_PER_DIAMETER = 1.0
"""The widest disc :func:`lightest_disc` makes where no width limit is given, as a multiple of
its outer diameter [-]: a disc is no wider than it is across (wider, it is a drum, and
needs a larger diameter or a looser target)."""


class DiscLimits(NamedTuple):
    """The limits of a disc flywheel, checked (:func:`disc_limits`): ``limited_by`` (the
    limit that sets the outer diameter, ``"outer diameter"`` or ``"rim speed"``), the
    ``outer_diameter_m`` it allows [m], the ``max_width_m`` [m] (the given one, or
    :data:`MAX_WIDTH_PER_DIAMETER` times the outer diameter: ``width_given`` says which),
    ``density_kg_m3`` [kg/m³], ``bore_m`` [m] and ``omega`` (the peak speed [rad/s])."""

    limited_by: str
    outer_diameter_m: float
    max_width_m: float
    width_given: bool
    density_kg_m3: float
    bore_m: float
    omega: float

    def largest_inertia_kgm2(self) -> float:
        """The inertia of the largest disc the limits allow [kg·m²]."""
        D, d = self.outer_diameter_m, self.bore_m
        return self.density_kg_m3 * math.pi * self.max_width_m * (D**4 - d**4) / 32

    def what(self) -> str:
        """The limit that sets the outer diameter, in the arguments' words."""
        if self.limited_by == "outer diameter":
            return f"max_outer_diameter_m = {self.outer_diameter_m:.4g} m"
        return (
            f"max_rim_speed_m_s = {self.omega * self.outer_diameter_m / 2:.4g} m/s (an outer diameter of "
            f"{self.outer_diameter_m:.4g} m at the peak speed)"
        )

    def smallest_diameter_m(self, inertia_kgm2: float) -> float:
        """The smallest outer diameter [m] at which a disc no wider than the width limit (the
        given one, else :data:`MAX_WIDTH_PER_DIAMETER` times that diameter) carries
        ``inertia_kgm2`` [kg·m²]."""
        rho, d = self.density_kg_m3, self.bore_m

        def inertia(D: float) -> float:
            width = self.max_width_m if self.width_given else MAX_WIDTH_PER_DIAMETER * D
            return rho * math.pi * width * (D**4 - d**4) / 32

        lo, hi = d, max(2 * d, self.outer_diameter_m, 1e-3)
        while inertia(hi) < inertia_kgm2:
            lo, hi = hi, 2 * hi
        for _ in range(200):  # bisection: the inertia grows with the diameter
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if inertia(mid) < inertia_kgm2 else (lo, mid)
            if hi - lo <= 1e-12 * hi:
                break
        return hi

    def way_out(self, inertia_kgm2: float) -> str:
        """What would let a disc carry ``inertia_kgm2`` [kg·m²]: the diameter or rim speed it
        needs, or a wider disc."""
        need_D = self.smallest_diameter_m(inertia_kgm2)
        larger = (
            f"max_outer_diameter_m ≥ {need_D:.4g} m"
            if self.limited_by == "outer diameter"
            else f"max_rim_speed_m_s ≥ {need_D * self.omega / 2:.4g} m/s (an outer diameter of {need_D:.4g} m)"
        )
        width = "" if self.width_given else " no wider than it is across"
        return f"a disc{width} needs {larger}"


def disc_limits(
    *,
    peak_rpm: float,
    density_kg_m3: float = CAST_IRON_KG_M3,
    bore_m: float = 0.0,
    max_outer_diameter_m: float | None = None,
    max_width_m: float | None = None,
    max_rim_speed_m_s: float | None = None,
) -> DiscLimits:
    """The limits of :func:`lightest_disc` checked (units as there): a
    :class:`rotor.EngineError` or a :class:`TypeError` naming the argument at fault."""
    for name, x, unit in (("density_kg_m3", density_kg_m3, "kg/m³"), ("peak_rpm", peak_rpm, "rpm")):
        v = require_number(x, name, unit)
        if not (v is not None and math.isfinite(v) and v > 0):
            raise EngineError(f"{name} = {x!r}: must be positive")
    rho = float(density_kg_m3)
    lo, hi = DENSITY_RANGE_KG_M3
    if not lo <= rho <= hi:
        raise EngineError(
            f"density_kg_m3 = {rho:g}: outside the plausible {lo:g} … {hi:g} kg/m³ of a flywheel's material "
            "(cast iron 7200, steel 7850)"
        )
    check_speed_rpm(peak_rpm, "peak_rpm")
    for name, given, unit in (
        ("max_outer_diameter_m", max_outer_diameter_m, "m"),
        ("max_width_m", max_width_m, "m"),
        ("max_rim_speed_m_s", max_rim_speed_m_s, "m/s"),
    ):
        limit = require_number(given, name, unit, optional=True)
        if limit is not None and not (math.isfinite(limit) and limit > 0):
            raise EngineError(f"{name} = {given!r}: a limit must be positive (or left out)")
    bore = require_number(bore_m, "bore_m", "m")
    if not (bore >= 0 and math.isfinite(bore)):
        raise EngineError("bore_m: must be a number ≥ 0 [m]")
    omega = rpm_to_rad_s(float(peak_rpm))
    bounds: dict[str, float] = {}
    if max_outer_diameter_m is not None:
        bounds["outer diameter"] = float(max_outer_diameter_m)
    if max_rim_speed_m_s is not None:
        bounds["rim speed"] = 2 * float(max_rim_speed_m_s) / omega
    if not bounds:
        raise EngineError(
            "the lightest disc is as large as allowed: give max_outer_diameter_m or max_rim_speed_m_s "
            "(or use the textbook's mean diameter of 2…3 strokes)"
        )
    limited_by = min(bounds, key=lambda k: bounds[k])
    D = bounds[limited_by]
    if D > MAX_DISC_DIAMETER_M:
        raise EngineError(
            f"the {limited_by} limit allows an outer diameter of {D:.4g} m, more than any flywheel "
            f"({MAX_DISC_DIAMETER_M:g} m): check the unit of the limit (max_outer_diameter_m is metres, "
            "max_rim_speed_m_s metres per second), or give a tighter one"
        )
    if not D**4 - bore**4 > 0 or D <= bore:
        raise EngineError(
            f"the outer diameter allowed by the {limited_by} limit, {D:.4g} m, is not larger than the bore {bore:.4g} m"
        )
    width = MAX_WIDTH_PER_DIAMETER * D if max_width_m is None else float(max_width_m)
    return DiscLimits(limited_by, D, width, max_width_m is not None, rho, bore, omega)


def lightest_disc(
    inertia_kgm2: float,
    *,
    peak_rpm: float,
    density_kg_m3: float = CAST_IRON_KG_M3,
    bore_m: float = 0.0,
    max_outer_diameter_m: float | None = None,
    max_width_m: float | None = None,
    max_rim_speed_m_s: float | None = None,
) -> DiscFlywheel:
    """The lightest disc with inertia ``inertia_kgm2`` [kg·m²] under the limits.

    A disc of outer diameter D, bore d and width b has J = ρπb(D⁴ − d⁴)/32 and mass
    m = 8J/(D² + d²): for a given inertia the lightest is the largest allowed D, with the
    width b = 32J/(ρπ(D⁴ − d⁴)). **Arguments:** ``peak_rpm``, the highest crank speed
    [rev/min] (for the rim speed); ``density_kg_m3`` [kg/m³] (default cast iron 7200);
    ``bore_m`` [m]; the limits: outer diameter [m], width [m] (default: the outer
    diameter, :data:`MAX_WIDTH_PER_DIAMETER`), rim speed [m/s]; at least one of the outer
    diameter or the rim speed must be given.

    **Raises:** :class:`rotor.EngineError` for a bad argument, and where no disc within the
    limits carries the inertia (it names the limit and the outer diameter or rim speed
    that would do); a :class:`TypeError` for a value that is not a number (or is traced by
    ``jax.jit``/``vmap``/``grad``: the design is computed on the host).
    """
    J = require_number(inertia_kgm2, "lightest_disc(inertia_kgm2)", "kg·m²")
    if not (math.isfinite(J) and J > 0):
        raise EngineError(
            f"flywheel inertia {J:.4g} kg·m²: must be positive (the shaft's own inertia already meets "
            "the target: no flywheel is needed)"
        )
    if J > MAX_INERTIA_KGM2:
        raise EngineError(f"flywheel inertia {J:.4g} kg·m²: above the plausible {MAX_INERTIA_KGM2:g} kg·m²")
    lim = disc_limits(
        peak_rpm=peak_rpm,
        density_kg_m3=density_kg_m3,
        bore_m=bore_m,
        max_outer_diameter_m=max_outer_diameter_m,
        max_width_m=max_width_m,
        max_rim_speed_m_s=max_rim_speed_m_s,
    )
    rho, bore, omega, D, limited_by = lim.density_kg_m3, lim.bore_m, lim.omega, lim.outer_diameter_m, lim.limited_by
    width = 32 * J / (rho * math.pi * (D**4 - bore**4))
    if width > lim.max_width_m:
        allowed = (
            f"the {lim.max_width_m:.4g} m allowed; allow a width of {width:.4g} m, or"
            if lim.width_given
            else "its own diameter (max_width_m allows a wider one);"
        )
        raise EngineError(
            f"no disc within {lim.what()} carries {J:.4g} kg·m²: it needs a width of {width:.4g} m, more than "
            f"{allowed} {lim.way_out(J)}, or a smaller inertia (a looser δ target)"
        )
    mass = rho * math.pi * width * (D**2 - bore**2) / 4
    check_results_finite(
        f"the lightest disc for {J:.4g} kg·m²",
        {"width_m": width, "mass_kg": mass, "rim_speed_m_s": omega * D / 2},
    )
    if not (width > 0 and mass > 0):
        raise EngineError(
            f"the lightest disc for {J:.4g} kg·m² at an outer diameter of {D:.4g} m is {width:g} m wide: "
            "too thin to make; give a smaller outer diameter or rim-speed limit"
        )
    return DiscFlywheel(
        outer_diameter_m=D,
        bore_m=float(bore),
        width_m=width,
        density_kg_m3=rho,
        inertia_kgm2=J,
        mass_kg=mass,
        rim_speed_m_s=omega * D / 2,
        peak_rpm=float(peak_rpm),
        limited_by=limited_by,
    )


# ----------------------------------------------------------------------------- the design
@dataclass(frozen=True, repr=False)
class PointResult:
    """One operating point of a :class:`FlywheelDesign` (a part of it, not a result of its
    own): ``rpm`` [rev/min], ``imep_scale`` [-] (a number or one per cylinder), ``load``
    (the load's name, ``"balanced"`` for none), ``delta_target`` [-], ``inertia_kgm2``:
    the ``[crankshaft]`` inertia that meets the target here exactly [kg·m²] (0 where none
    is needed), ``delta``: δ with the designed inertia [-], ``peak_rpm``: the highest speed
    within the cycle [rev/min], ``newton_steps``, ``textbook``: the textbook sizing here,
    ``fuel_scale``: the fuelling solved for a speed-dependent load [-] (None otherwise);
    the operating point in the words of :class:`rotor.SpeedResult`: ``load_torque_Nm`` (the
    load carried, its time mean [N·m]), ``fuel_scale_applied`` (the fuel scale, mean over the
    cylinders [-]) and ``solved_for`` (``"load"`` or ``"fuel_scale"``)."""

    rpm: float
    imep_scale: float | list[float]
    load: str
    delta_target: float
    inertia_kgm2: float
    delta: float
    peak_rpm: float
    newton_steps: int
    textbook: TextbookFlywheel
    fuel_scale: float | None = None
    load_torque_Nm: float | None = None
    fuel_scale_applied: float | None = None
    solved_for: str | None = None

    def __repr__(self) -> str:
        return f"PointResult(rpm={self.rpm:g}, delta={self.delta:.5g}, inertia_kgm2={self.inertia_kgm2:.5g})"


class DeltaSweep(NamedTuple):
    """δ of a design's engine over a sweep of mean speeds (see
    :meth:`FlywheelDesign.delta_sweep`): ``rpm`` [rev/min]; ``designed`` and ``textbook``:
    δ [-] with the designed and with the textbook ``[crankshaft]`` inertia (NaN where the
    crankshaft nearly stops; None where that inertia is not positive)."""

    rpm: Float[np.ndarray, " n"]
    designed: Float[np.ndarray, " n"] | None
    textbook: Float[np.ndarray, " n"] | None


@dataclass(frozen=True, repr=False, eq=False)
class FlywheelDesign(Result):
    """The smallest ``[crankshaft] inertia_kgm2`` meeting each point's δ target, the
    textbook estimate, and (with limits) the lightest disc.

    - ``engine``: the :class:`rotor.Engine` it was designed for (its own ``[crankshaft]
      inertia_kgm2`` was only the starting guess);
    - ``crankshaft_inertia_kgm2``: the designed ``[crankshaft] inertia_kgm2`` [kg·m²];
    - ``binding_rpm`` [rev/min] and ``binding_index``: the point that sets it;
      ``delta_target``: its target [-]; ``delta_achieved``: δ there [-];
    - ``textbook``: the textbook sizing at the point where it asks most (the textbook
      applied at every point; at one point only it can be far off: see ``points``);
      ``textbook_inertia_kgm2``: its ``[crankshaft]`` equivalent (J₀ less the rods and
      pistons); ``textbook_ratio``: that over the design; ``textbook_total_ratio``: J₀ over
      the design's total mean inertia (the fairer ratio when the rods and pistons are a
      large share);
    - ``shaft_inertia_kgm2``: the crankshaft's own inertia without the flywheel [kg·m²];
      ``flywheel_kgm2``: the design less it (what the flywheel must add) [kg·m²], never
      negative: 0 with ``flywheel_needed`` False where the shaft alone meets every target
      (then ``delta_shaft_alone``, δ at the binding point with the shaft alone [-], and
      ``note`` say so); ``delta_shaft_alone`` is None without a shaft inertia;
    - ``disc``: a :class:`DiscFlywheel` or None; ``points``: a :class:`PointResult` per
      point; ``loads``: each point's load (None: balanced);
    - ``fidelity``, ``friction``, ``grid_deg`` [deg]: as given to :func:`rotor.steady_state`;
      ``diameter_strokes``: the textbook's rim diameter in strokes [-].
    """

    engine: Engine
    delta_target: float
    crankshaft_inertia_kgm2: float
    binding_rpm: float
    binding_index: int
    delta_achieved: float
    shaft_inertia_kgm2: float
    flywheel_kgm2: float
    textbook: TextbookFlywheel
    points: tuple[PointResult, ...]
    loads: tuple[Load | None, ...]
    disc: DiscFlywheel | None = None
    fidelity: str = "variable"
    friction: FrictionArg = None
    grid_deg: float = 0.25
    diameter_strokes: float = 2.5
    flywheel_needed: bool = True
    delta_shaft_alone: float | None = None

    @property
    def note(self) -> str | None:
        """Why there is no flywheel, in words; None where one is needed."""
        if self.flywheel_needed:
            return None
        got = "" if self.delta_shaft_alone is None else f" gives δ = {self.delta_shaft_alone:.4g} and"
        return (
            f"no flywheel needed: the crankshaft's own inertia alone ({self.shaft_inertia_kgm2:g} kg·m²){got} "
            f"meets the target δ = {self.delta_target:g} at {self.binding_rpm:g} rpm, which needs only "
            f"{self.crankshaft_inertia_kgm2:.4g} kg·m²"
        )

    @property
    def engine_name(self) -> str:
        """The name of the engine it was designed for."""
        return self.engine.name

    @property
    def textbook_inertia_kgm2(self) -> float:
        """The textbook's ``[crankshaft]`` equivalent, J₀ less the rods and pistons [kg·m²]."""
        return self.textbook.crankshaft_inertia_kgm2

    @property
    def textbook_ratio(self) -> float:
        """textbook ``[crankshaft]`` inertia / designed [-] (> 1: the textbook oversizes)."""
        return self.textbook_inertia_kgm2 / self.crankshaft_inertia_kgm2

    @property
    def textbook_total_ratio(self) -> float:
        """textbook J₀ / the design's total mean inertia (crankshaft + rods and pistons) [-]."""
        t = self.textbook
        return t.total_inertia_kgm2 / (self.crankshaft_inertia_kgm2 + t.mechanism_inertia_kgm2)

    def to_json_dict(self) -> dict:
        """The design as plain JSON (what ``rotor flywheel --json`` prints, less the plots).

        The textbook's ``[crankshaft]`` equivalent and its ratio are null where J₀ is smaller
        than the rods' and pistons' own inertia (the textbook does not apply: see its note)."""
        applicable = self.textbook_inertia_kgm2 > 0
        d = {
            "engine": self.engine_name,
            "delta_target": self.delta_target,
            "crankshaft_inertia_kgm2": self.crankshaft_inertia_kgm2,
            "textbook_inertia_kgm2": self.textbook_inertia_kgm2 if applicable else None,
            "textbook_ratio": self.textbook_ratio if applicable else None,
            "textbook_total_ratio": self.textbook_total_ratio,
            "binding_rpm": self.binding_rpm,
            "delta_achieved": self.delta_achieved,
            "shaft_inertia_kgm2": self.shaft_inertia_kgm2,
            "flywheel_kgm2": self.flywheel_kgm2,
            "flywheel_needed": self.flywheel_needed,
            "delta_shaft_alone": self.delta_shaft_alone,
            "note": self.note,
            "textbook": self.textbook.to_json_dict(),
            "fidelity": self.fidelity,
            "points": [{**asdict(p), "textbook": p.textbook.to_json_dict()} for p in self.points],
            "disc": None if self.disc is None else asdict(self.disc),
            "grid_deg": self.grid_deg,
            "diameter_strokes": self.diameter_strokes,
        }
        return json_safe(d)

    def to_pandas(self) -> Any:
        """One row per operating point: speed [rpm], fuelling [-], load, δ target [-], the
        inertia that meets it there [kg·m²], δ with the design [-], peak speed [rpm], Newton
        steps, solved fuelling [-], the textbook there [J, kg·m²], and the binding point."""
        import pandas as pd

        return pd.DataFrame(
            {
                "rpm": [p.rpm for p in self.points],
                "imep_scale": [p.imep_scale for p in self.points],
                "load": [p.load for p in self.points],
                "delta_target": [p.delta_target for p in self.points],
                "inertia_for_target_kgm2": [p.inertia_kgm2 for p in self.points],
                "delta_designed": [p.delta for p in self.points],
                "peak_rpm": [p.peak_rpm for p in self.points],
                "newton_steps": [p.newton_steps for p in self.points],
                "fuel_scale": [np.nan if p.fuel_scale is None else p.fuel_scale for p in self.points],
                "load_torque_Nm": [np.nan if p.load_torque_Nm is None else p.load_torque_Nm for p in self.points],
                "solved_for": [p.solved_for for p in self.points],
                "textbook_excess_work_J": [p.textbook.excess_work_J for p in self.points],
                "textbook_total_inertia_kgm2": [p.textbook.total_inertia_kgm2 for p in self.points],
                "textbook_crankshaft_inertia_kgm2": [p.textbook.crankshaft_inertia_kgm2 for p in self.points],
                "binding": [i == self.binding_index for i in range(len(self.points))],
            }
        )

    def summary(self) -> str:
        """A comparison of the textbook and the designed flywheel, as text."""
        t = self.textbook
        lines = [
            f"{self.engine_name}: the smallest flywheel for δ ≤ target at {len(self.points)} operating point(s)",
            "",
            f"  {'rpm':>7} {'fuel scale':>11} {'load [N·m]':>11} {'load model':>13} {'δ target':>9} "
            f"{'J for target':>13} {'δ (design)':>11} {'J textbook':>11}",
        ]
        for i, p in enumerate(self.points):
            mark = "  ← binding" if i == self.binding_index else ""
            scale = f"{p.imep_scale:g}" if isinstance(p.imep_scale, (int, float)) else "per cyl."
            if p.fuel_scale_applied is not None:
                scale = f"{p.fuel_scale_applied:.4g}"
            if p.solved_for == "fuel_scale":
                scale += "*"
            load = "—" if p.load_torque_Nm is None else f"{p.load_torque_Nm:.1f}"
            if p.solved_for == "load":
                load += "*"
            need = f"{p.inertia_kgm2:13.4f}" if p.inertia_kgm2 > 0 else f"{'none':>13}"
            tb_j = p.textbook.crankshaft_inertia_kgm2
            tb = f"{tb_j:11.4f}" if tb_j > 0 else f"{'n/a':>11}"
            lines.append(
                f"  {p.rpm:7g} {scale:>11} {load:>11} {p.load:>13} {p.delta_target:9.4g} {need} {p.delta:11.5f} "
                f"{tb}{mark}"
            )
        lines.append(
            "  (fuel scale: the combustion as a multiple of the engine file's; load: the torque carried; "
            "* solved, the other given)"
        )
        lines += [
            "",
            f"  designed [crankshaft] inertia_kgm2   {self.crankshaft_inertia_kgm2:10.4f} kg·m²  (binding at "
            f"{self.binding_rpm:g} rpm, δ = {self.delta_achieved:.5f})",
            f"  textbook (Shishkov 2014, §3.2.12) at {t.rpm:g} rpm: J₀ = L_excess/(δ·ω²) = {t.excess_work_J:.1f} J / "
            f"({t.delta:g}·{rpm_to_rad_s(t.rpm):.1f}²) = {t.total_inertia_kgm2:.4f} kg·m²",
        ]
        if t.crankshaft_inertia_kgm2 > 0:
            lines.append(
                f"    as [crankshaft] inertia_kgm2 (J₀ less rods and pistons) {t.crankshaft_inertia_kgm2:10.4f} kg·m²  "
                f"= {self.textbook_ratio:.3f} × the design ({100 * (self.textbook_ratio - 1):+.1f} %; as total "
                f"inertias {100 * (self.textbook_total_ratio - 1):+.1f} %)"
            )
        else:
            lines.append(
                "    not applicable: J₀ is smaller than the rods' and pistons' own mean inertia "
                f"({t.mechanism_inertia_kgm2:.4g} kg·m²)"
            )
        if t.delta > 0.2:
            lines.append(f"    (δ = {t.delta:g} is not small: the textbook's first-order theory does not hold)")
        lines.append(
            f"    the textbook's flywheel 0.85·J₀ = {t.flywheel_kgm2:.4f} kg·m², {t.mass_kg:.1f} kg as a rim of mean "
            f"diameter {t.mean_diameter_m:.3f} m; its 0.85 assumes the shaft, rods and pistons make "
            f"0.15·J₀ = {0.15 * t.total_inertia_kgm2:.4g} kg·m² (rods and pistons here: {t.mechanism_inertia_kgm2:.4g})"
        )
        if self.shaft_inertia_kgm2:
            if self.flywheel_kgm2 > 0:
                r = t.flywheel_kgm2 / self.flywheel_kgm2
                lines.append(
                    f"  flywheel to add to a shaft of {self.shaft_inertia_kgm2:g} kg·m²: "
                    f"{self.flywheel_kgm2:.4f} kg·m² (the textbook's 0.85·J₀ is {r:.3f} × it, {100 * (r - 1):+.1f} %)"
                )
            else:
                lines.append(f"  {self.note} (the shaft alone meets the target)")
        if self.disc is not None:
            lines.append("  " + self.disc.summary())
        return "\n".join(lines)

    def delta_sweep(self, rpm_range: tuple[float, float] | None = None, n: int = 25) -> DeltaSweep:
        """δ over ``n`` mean speeds from ``rpm_range`` = (low, high) [rev/min] (default the
        points' range ±20 %), with the designed and with the textbook ``[crankshaft]``
        inertia: each cylinder's fuelling interpolated between the points, the nearest
        point's load.

        **Returns:** a :class:`DeltaSweep` of the speeds [rev/min] and δ [-].
        """
        rpms = np.array([p.rpm for p in self.points])
        if rpm_range is None:
            lo, hi = 0.8 * rpms.min(), 1.2 * rpms.max()
        else:
            if (
                isinstance(rpm_range, (str, bytes))
                or not isinstance(rpm_range, (Sequence, np.ndarray))
                or len(rpm_range) != 2
            ):
                raise EngineError(f"rpm_range = {rpm_range!r:.40}: give (low, high) speeds with 0 < low ≤ high [rpm]")
            lo, hi = (check_speed_rpm(v, "rpm_range") for v in rpm_range)
            if not lo <= hi:
                raise EngineError(f"rpm_range = {rpm_range!r}: give (low, high) speeds with 0 < low ≤ high [rpm]")
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"delta_sweep(n): expected a whole number of sweep speeds, got {type(n).__name__}")
        if not 1 <= n <= MAX_SWEEP_SPEEDS:
            raise EngineError(
                f"n = {n!r}: the number of sweep speeds must lie in 1 … {MAX_SWEEP_SPEEDS} (each is a steady "
                "state; 25 draw a smooth curve)"
            )
        cylinders = self.engine.cylinders
        sweep = np.linspace(lo, hi, n)
        ev = DeltaOfInertia(self.engine, self.fidelity, self.friction, self.grid_deg)
        order = np.argsort(rpms)
        scales = np.stack([np.broadcast_to(np.asarray(p.imep_scale, float), (cylinders,)) for p in self.points])
        fuel = np.stack([np.interp(sweep, rpms[order], scales[order, c]) for c in range(cylinders)], axis=1)
        loads = self.loads or (None,) * len(rpms)
        near = [loads[int(np.argmin(np.abs(rpms - r)))] for r in sweep]

        def deltas(J: float) -> Float[np.ndarray, " n"] | None:
            if J <= 0:
                return None
            return np.array(
                [
                    ev.delta(J, OperatingPoint(r, f if np.ptp(f) else float(f[0]), ld))
                    for r, f, ld in zip(sweep, fuel, near)
                ]
            )

        return DeltaSweep(sweep, deltas(self.crankshaft_inertia_kgm2), deltas(self.textbook_inertia_kgm2))

    def plot(self, ax: Any = None, rpm_range: tuple[float, float] | None = None, n: int = 25) -> Any:
        """δ against mean speed with the designed and the textbook inertia and the points
        (left); the inertia each point needs, by Newton and by the textbook (right). ``ax``:
        two Axes (one: the left panel only) or None; ``rpm_range`` [rev/min] and ``n`` as in
        :meth:`delta_sweep`. See :func:`rotor.plotting.plot_flywheel_design`.

        **Returns:** what it drew on (the two Axes, or the one given).
        """
        s = self.delta_sweep(rpm_range, n)
        return plot_flywheel_design(self, s.rpm, s.designed, s.textbook, ax=ax)


def _load_name(load: Load | None) -> str:
    return "balanced" if load is None else type(load).__name__


def _checked_points(
    engine: Engine,
    results: list,
    J_design: float,
    fidelity: str,
    friction: FrictionArg,
    grid_deg: float,
    max_rpm: float | None,
) -> tuple[list[PointResult], float]:
    """The steady state of every operating point with the designed crankshaft inertia
    ``J_design`` [kg·m²] (``results``: (point, its own inertia, Newton steps, textbook
    sizing, δ target) each): the :class:`PointResult` of each, and the highest speed the
    flywheel must stand [rpm] (``max_rpm``, else the larger of ``[operating] rpm`` and
    the highest speed within the cycle at any point)."""
    point_results = []
    peak = float(engine.operating.rpm) if max_rpm is None else float(max_rpm)
    for p, J, steps, tb, target in results:
        try:  # the eager steady state: every check of rotor.steady_state applies to the design
            r = steady_state(
                with_crankshaft_inertia(engine, J_design),
                p.rpm,
                cast("Load | None", p.load),  # parsed by _points
                fidelity=fidelity,
                friction=friction,
                imep_scale=cast(Any, p.imep_scale),
                grid_deg=grid_deg,
            )
        except NoSteadyStateError as e:
            raise NoSteadyStateError(
                f"the designed inertia {J_design:.4g} kg·m² has no steady state at {p.rpm:g} rpm: {e}"
            ) from e
        if max_rpm is None:
            peak = max(peak, float(r.max_rpm))
        fuel = r.fuel_scale if r.solved_for == "fuel_scale" else None
        point_results.append(
            PointResult(
                rpm=p.rpm,
                imep_scale=_jsonable(p.imep_scale),
                load=_load_name(cast("Load | None", p.load)),  # parsed by _points
                delta_target=target,
                inertia_kgm2=J,
                delta=float(r.delta),
                peak_rpm=float(r.max_rpm),
                newton_steps=steps,
                textbook=tb,
                fuel_scale=None if fuel is None else float(np.asarray(fuel)),
                load_torque_Nm=None if r.load_torque_Nm is None else float(np.asarray(r.load_torque_Nm)),
                fuel_scale_applied=None if r.fuel_scale is None else float(np.asarray(r.fuel_scale)),
                solved_for=r.solved_for,
            )
        )
    return point_results, peak


def design_flywheel(
    engine: Engine | PreparedEngine,
    delta: float | None,
    points: PointsArg = None,
    *,
    shaft_inertia_kgm2: float = 0.0,
    diameter_strokes: float = 2.5,
    density_kg_m3: float = CAST_IRON_KG_M3,
    bore_m: float = 0.0,
    max_outer_diameter_m: float | None = None,
    max_width_m: float | None = None,
    max_rim_speed_m_s: float | None = None,
    max_rpm: float | None = None,
    fidelity: str = "variable",
    friction: FrictionArg = None,
    grid_deg: float = 0.25,
    rtol: float = 1e-10,
) -> FlywheelDesign:
    """The smallest flywheel keeping δ ≤ ``delta`` at every operating point.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine` (or a :class:`rotor.PreparedEngine`); its ``[crankshaft] inertia_kgm2`` is only the
      starting guess.
    - ``delta``: the target irregularity (ω_max − ω_min)/ω_mean [-], e.g. 0.01, for
      every point that gives none of its own (None if all do).
    - ``points``: the operating points: rpm values [rev/min], :class:`OperatingPoint`
      (rpm, imep_scale, load, delta) or tuples of those; default the engine's
      ``[operating] rpm`` at full fuelling with a balancing load.
    - ``shaft_inertia_kgm2``: the crankshaft's own inertia without the flywheel [kg·m²]
      (``flywheel_kgm2`` is the design less this).
    - ``diameter_strokes``: the textbook's mean diameter in strokes [-] (2…3).
    - ``density_kg_m3`` [kg/m³], ``bore_m`` [m], ``max_outer_diameter_m`` [m],
      ``max_width_m`` [m], ``max_rim_speed_m_s`` [m/s]: the lightest disc
      (:func:`lightest_disc`), made when an outer diameter or rim-speed limit is given.
    - ``max_rpm``: the highest crank speed the flywheel must stand, for the rim speed
      [rev/min]; default the larger of the engine's ``[operating] rpm`` and the highest
      speed within the cycle at any point.
    - ``fidelity``, ``friction``, ``grid_deg`` [deg]: as in :func:`rotor.steady_state`.
    - ``rtol``: Newton tolerance on log J [-].

    **Returns:** a :class:`FlywheelDesign`; ``.summary()`` compares it with the textbook.

    **Raises:** :class:`rotor.EngineError` for a bad target, point or limit, limits no disc
    can meet (the message names the limit, the outer diameter or rim speed that would carry
    the flywheel, and the δ the largest disc allowed gives), or a target met with no
    flywheel at all; :class:`rotor.NoSteadyStateError` (a :class:`rotor.SolverError`) for
    an operating point with no steady state, and :class:`rotor.SolverError` where Newton's
    method finds no inertia; a :class:`TypeError` for a value of the wrong type or traced by
    ``jax.jit``/``vmap``/``grad`` (the design is a search on the host).
    """
    _known_values(
        "design_flywheel",
        engine=engine,
        delta=delta,
        points=points,
        shaft_inertia_kgm2=shaft_inertia_kgm2,
        max_outer_diameter_m=max_outer_diameter_m,
        max_width_m=max_width_m,
        max_rim_speed_m_s=max_rim_speed_m_s,
        max_rpm=max_rpm,
    )
    engine = resolve_engine(engine)  # a prepared engine: its tables are reused
    require_engine(engine, "design_flywheel(engine)").check()
    pts = _points(points, engine)
    if delta is None and any(p.delta is None for p in pts):
        raise EngineError("no δ target: give delta, or one in every OperatingPoint")
    default = None if delta is None else _check_delta(delta)
    _check_design_args(
        shaft_inertia_kgm2,
        diameter_strokes,
        grid_deg,
        max_rpm,
        max_outer_diameter_m is not None or max_rim_speed_m_s is not None,
        max_width_m,
        bore_m,
    )
    ev = DeltaOfInertia(engine, fidelity, friction, grid_deg)
    j_start = float(engine.crankshaft.inertia_kgm2)
    results = []
    for p in pts:
        target = float(cast(float, default if p.delta is None else p.delta))
        J, steps, tb = _point_inertia(engine, ev, p, target, j_start, diameter_strokes, rtol)
        results.append((p, J, steps, tb, target))
    i_bind = int(np.argmax([r[1] for r in results]))
    J_design = results[i_bind][1]
    if J_design <= 0:
        raise EngineError(
            "no flywheel is needed: δ stays below the target at every point even with (almost) no "
            "crankshaft inertia; the rods and pistons alone are enough (a [crankshaft] inertia_kgm2 "
            "must still be > 0)"
        )
    point_results, peak = _checked_points(engine, results, J_design, fidelity, friction, grid_deg, max_rpm)
    tb_worst = max((r[3] for r in results), key=lambda t: t.crankshaft_inertia_kgm2)
    shaft = float(shaft_inertia_kgm2)
    needed = J_design > shaft
    flywheel = J_design - shaft if needed else 0.0  # never negative: a shaft that is enough needs none
    delta_shaft = None
    if shaft > 0:  # δ at the binding point with the shaft alone, no flywheel
        delta_shaft = ev.delta(shaft, pts[i_bind])
        if not math.isfinite(delta_shaft):
            delta_shaft = None
    disc = None
    if (max_outer_diameter_m is not None or max_rim_speed_m_s is not None) and flywheel > 0:
        limits = disc_limits(
            peak_rpm=peak,
            density_kg_m3=density_kg_m3,
            bore_m=bore_m,
            max_outer_diameter_m=max_outer_diameter_m,
            max_width_m=max_width_m,
            max_rim_speed_m_s=max_rim_speed_m_s,
        )
        if flywheel > limits.largest_inertia_kgm2():
            _refuse_disc(limits, flywheel, shaft, ev, pts, [r[4] for r in results])
        disc = lightest_disc(
            flywheel,
            peak_rpm=peak,
            density_kg_m3=density_kg_m3,
            bore_m=bore_m,
            max_outer_diameter_m=max_outer_diameter_m,
            max_width_m=max_width_m,
            max_rim_speed_m_s=max_rim_speed_m_s,
        )
    return FlywheelDesign(
        engine=engine,
        delta_target=results[i_bind][4],
        crankshaft_inertia_kgm2=J_design,
        binding_rpm=pts[i_bind].rpm,
        binding_index=i_bind,
        delta_achieved=point_results[i_bind].delta,
        shaft_inertia_kgm2=shaft,
        flywheel_kgm2=flywheel,
        flywheel_needed=needed,
        delta_shaft_alone=delta_shaft,
        textbook=tb_worst,
        points=tuple(point_results),
        loads=tuple(cast("Load | None", p.load) for p in pts),  # parsed by _points
        disc=disc,
        fidelity=fidelity,
        friction=friction,
        grid_deg=float(grid_deg),
        diameter_strokes=float(diameter_strokes),
    )


def _refuse_disc(
    limits: DiscLimits,
    flywheel: float,
    shaft: float,
    ev: DeltaOfInertia,
    pts: list[OperatingPoint],
    targets: list[float],
) -> None:
    """Refuse a design whose flywheel of ``flywheel`` [kg·m²] no disc within ``limits``
    carries: a :class:`rotor.EngineError` naming the limit, the outer diameter (or rim
    speed) that would carry it, and the δ the largest disc allowed gives at the point
    where it is furthest above its target (``targets``; ``shaft``: the crankshaft's own
    inertia [kg·m²])."""
    largest = limits.largest_inertia_kgm2()
    deltas = [ev.delta(shaft + largest, p) for p in pts]
    ratios = [d / t if math.isfinite(d) else math.inf for d, t in zip(deltas, targets)]
    worst = int(np.argmax(ratios))
    rpm = pts[worst].rpm
    d = deltas[worst]
    if math.isfinite(d) and d < 1:
        looser = f", or a δ target of {d:.4g} or more (what that largest disc gives at {rpm:g} rpm)"
    else:
        got = f"δ = {d:.4g}" if math.isfinite(d) else "no steady state"
        looser = f"; no δ target below 1 is met with that largest disc ({got} at {rpm:g} rpm)"
    width = f"{limits.max_width_m:.4g} m wide" if limits.width_given else "as wide as it is across"
    raise EngineError(
        f"no disc within {limits.what()} meets the δ target: the flywheel needs {flywheel:.4g} kg·m², the largest "
        f"disc allowed ({limits.outer_diameter_m:.4g} m across, {width}) carries {largest:.4g} kg·m²; "
        f"{limits.way_out(flywheel)}{looser}"
    )


def _number(name: str, v: Any, lo: float, strict: bool = True, hi: float = math.inf, unit: str = "") -> float:
    x = require_number(v, name, unit)
    if not (math.isfinite(x) and (x > lo if strict else x >= lo)):
        raise EngineError(f"{name} = {v!r}: must be a number {'>' if strict else '≥'} {lo:g}")
    if x > hi:
        raise EngineError(f"{name} = {v!r}: lies above the plausible {hi:g} {unit} (check its unit)")
    return x


def _check_design_args(
    shaft: float,
    diameter_strokes: float,
    grid_deg: float,
    max_rpm: float | None,
    disc: bool,
    max_width_m: float | None,
    bore_m: float,
) -> None:
    _number("shaft_inertia_kgm2", shaft, 0.0, strict=False, hi=MAX_INERTIA_KGM2, unit="kg·m²")
    _number("diameter_strokes", diameter_strokes, 0.0, hi=100.0)
    _number("grid_deg", grid_deg, 0.0, unit="deg")
    if max_rpm is not None:
        _number("max_rpm", max_rpm, 0.0, hi=PLAUSIBLE[("operating", "rpm")][1], unit="rev/min")
    if not disc and (max_width_m is not None or bore_m):
        raise EngineError(
            "a width limit or a bore shapes the lightest disc, which needs an outer-diameter or a "
            "rim-speed limit as well (max_outer_diameter_m or max_rim_speed_m_s)"
        )


def _point_inertia(
    engine: Engine,
    ev: DeltaOfInertia,
    p: OperatingPoint,
    target: float,
    j_start: float,
    diameter_strokes: float,
    rtol: float,
) -> tuple[float, int, TextbookFlywheel]:
    """The [crankshaft] inertia with δ = target at one point (0 where none is needed), the
    Newton steps and the textbook there."""
    j_try = j_start
    for _ in range(6):  # the textbook diagram does not depend on the inertia; find a start with a steady state
        d0, excess = ev.state(j_try, p)
        if math.isfinite(d0):
            break
        j_try *= 10
    else:
        raise NoSteadyStateError(
            f"no steady state at {p.rpm:g} rpm even with a {j_try / 10:g} kg·m² crankshaft: the engine "
            "cannot run at this point (check its fuelling and load)"
        )
    mech = ev.mechanism_kgm2
    tb = _textbook(engine, target, p, excess, mech, diameter_strokes)
    # start from this point's own δ/J slope (δ ∝ 1/(J + mech))
    u0 = math.log(max((j_try + mech) * d0 / target - mech, 1e-3 * (j_try + mech)))
    u, ok, steps = ev.root(u0, math.log(target), p, rtol)
    J = math.exp(u)
    d_check = ev.delta(J, p) if ok else float("nan")
    if ok and abs(d_check / target - 1) < 1e-6:
        return J, steps, tb
    # why not: no flywheel needed (δ below the target with almost no crankshaft inertia), or a target too tight
    j_floor = 1e-6 * (j_try + mech)
    d_floor = ev.delta(j_floor, p)
    if math.isfinite(d_floor) and d_floor <= target:
        return 0.0, steps, tb
    raise SolverError(
        f"at {p.rpm:g} rpm Newton's method found no crankshaft inertia with δ = {target:g} (it stopped at "
        f"{J:.4g} kg·m², δ = {d_check:.4g}; with a {j_try:g} kg·m² crankshaft δ = {d0:.4g}): check the target "
        "(too tight for float64 below about 1e-8?), the tolerance rtol, and rotor.steady_state at this point"
    )


def _jsonable(x: float | Sequence[float]) -> float | list[float]:
    a = np.asarray(x, dtype=float)
    return float(a) if a.ndim == 0 else a.tolist()
