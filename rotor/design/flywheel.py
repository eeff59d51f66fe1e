"""Flywheel sizing: the textbook rule and the smallest flywheel found through the simulator.

**Textbook** (seed 004 §3.2.12): from one turning-moment diagram at constant speed (gas
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
from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from ..dynamics.result import RPM_PER_RAD_S
from ..dynamics.steady import steady_state
from ..engine.inertia import mean_reduced_inertia
from ..errors import EngineError, NoSteadyStateError

__all__ = [
    "OperatingPoint",
    "TextbookFlywheel",
    "DiscFlywheel",
    "FlywheelDesign",
    "textbook_flywheel",
    "design_flywheel",
    "lightest_disc",
    "inertia_for_delta",
]

TEXTBOOK_SHARE = 0.85  # seed 004 §3.2.12: J_flywheel = 0.85·J₀
CAST_IRON_KG_M3 = 7200.0


class OperatingPoint(NamedTuple):
    """One operating point: mean speed ``rpm`` [rev/min], the fuelling ``imep_scale``
    (combustion scale [-], 1 = the engine file's pressure), a ``load`` (None or a
    :class:`rotor.ConstantLoad`: the load balances the engine; a speed-dependent load:
    the fuelling is scaled to carry it) and its own target ``delta`` [-] (None: the
    design's; e.g. a looser one at idle)."""

    rpm: float
    imep_scale: float = 1.0
    load: object = None
    delta: float | None = None


def _points(points, engine) -> list[OperatingPoint]:
    if points is None:
        points = [float(engine.operating.rpm)]
    if isinstance(points, (int, float, OperatingPoint)):
        points = [points]
    out = []
    for p in points:
        p = p if isinstance(p, OperatingPoint) else OperatingPoint(*p) if isinstance(p, tuple) else OperatingPoint(p)
        rpm = float(p.rpm)
        if not (math.isfinite(rpm) and rpm > 0):
            raise EngineError(f"operating point rpm = {p.rpm!r}: must be a positive, finite speed in rpm")
        try:
            scale = np.asarray(p.imep_scale, dtype=float)
        except (TypeError, ValueError):
            scale = np.array(np.nan)
        if not (np.all(np.isfinite(scale)) and np.all(scale >= 0)) or scale.shape not in ((), (engine.cylinders,)):
            raise EngineError(
                f"operating point at {rpm:g} rpm: imep_scale = {p.imep_scale!r} must be one number ≥ 0 "
                f"or one per cylinder ({engine.cylinders})"
            )
        load = p.load
        if isinstance(load, str):
            from ..dynamics.loads import parse_load

            load = parse_load(load)
        if load is not None and not hasattr(load, "torque"):
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


def _check_delta(delta):
    d = float(delta)
    if not (math.isfinite(d) and 0 < d < 1):
        raise EngineError(
            f"delta = {delta!r}: the target irregularity (ω_max − ω_min)/ω_mean must lie in (0, 1), e.g. 0.01 for 1 %"
        )
    return d


# ----------------------------------------------------------------------------- textbook
@dataclass(frozen=True)
class TextbookFlywheel:
    """The textbook sizing at one operating point (seed 004 §3.2.12), SI units.

    ``total_inertia_kgm2`` is J₀ (everything that turns and reciprocates);
    ``crankshaft_inertia_kgm2`` is J₀ less the cycle-mean inertia of the rods and pistons,
    the ``[crankshaft] inertia_kgm2`` the textbook implies; ``flywheel_kgm2`` = 0.85·J₀,
    ``mean_diameter_m`` = ``diameter_strokes``·S and ``mass_kg`` = 4·J_flywheel/D²."""

    rpm: float
    delta: float
    excess_work_J: float
    total_inertia_kgm2: float
    crankshaft_inertia_kgm2: float
    flywheel_kgm2: float
    mean_diameter_m: float
    mass_kg: float


def _textbook(engine, delta, point, excess_work, mechanism_inertia, diameter_strokes):
    omega = point.rpm / RPM_PER_RAD_S
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
    engine,
    delta: float,
    rpm=None,
    *,
    imep_scale=1.0,
    load=None,
    diameter_strokes: float = 2.5,
    fidelity: str = "variable",
    friction=None,
    grid_deg: float = 0.25,
) -> TextbookFlywheel:
    """The textbook flywheel of seed 004 §3.2.12 at one operating point.

    **Arguments:** ``engine`` (a :class:`rotor.Engine`); ``delta``, the target irregularity
    [-]; ``rpm`` [rev/min] (default ``[operating] rpm``); ``imep_scale`` [-] and ``load`` as
    in :func:`rotor.steady_state`; ``diameter_strokes``, the mean diameter in strokes (the
    seed's 2…3) [-]; ``fidelity``, ``friction``, ``grid_deg`` [deg] as in
    :func:`rotor.steady_state`.
    """
    delta = _check_delta(delta)
    _number("diameter_strokes", diameter_strokes, 0.0)
    (point,) = _points([OperatingPoint(engine.operating.rpm if rpm is None else rpm, imep_scale, load)], engine)
    ev = _Evaluator(engine, fidelity, friction, grid_deg)
    _, excess = ev.state(float(engine.crankshaft.inertia_kgm2), point)
    return _textbook(engine, delta, point, excess, ev.mechanism, diameter_strokes)


# ----------------------------------------------------------------------------- through the simulator
def _with_inertia(engine, inertia):
    return eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, jnp.asarray(inertia, dtype=jnp.float64))


@eqx.filter_jit
def _state(engine, inertia, rpm, scale, load, fidelity, friction, grid_deg):
    """δ (NaN where the crankshaft nearly stops) and the textbook excess work [J] of the
    steady state with ``[crankshaft] inertia_kgm2 = inertia``."""
    r = steady_state(
        _with_inertia(engine, inertia),
        rpm,
        load,
        fidelity=fidelity,
        friction=friction,
        imep_scale=scale,
        grid_deg=grid_deg,
    )
    ok = jnp.min(r.omega) > 0.01 * r.mean_omega
    return jnp.where(ok, r.delta, jnp.nan), r.info["excess_work_J"]


@eqx.filter_jit
def _root(engine, u0, log_target, rpm, scale, load, fidelity, friction, grid_deg, rtol):
    def fn(u, _):
        d, _ = _state(engine, jnp.exp(u), rpm, scale, load, fidelity, friction, grid_deg)
        return jnp.log(d) - log_target

    sol = optx.root_find(fn, optx.Newton(rtol=rtol, atol=rtol), u0, max_steps=60, throw=False)
    return sol.value, sol.result == optx.RESULTS.successful, sol.stats["num_steps"]


class _Evaluator:
    """The steady state of one engine at operating points, as a function of its inertia;
    ``mechanism``: the cycle-mean inertia of its rods and pistons [kg·m²]."""

    def __init__(self, engine, fidelity, friction, grid_deg):
        self.engine, self.fidelity, self.friction, self.grid_deg = engine, fidelity, friction, grid_deg
        self.mechanism = float(mean_reduced_inertia(engine)) - float(engine.crankshaft.inertia_kgm2)

    def _args(self, point):
        rpm = jnp.asarray(point.rpm, dtype=jnp.float64)
        scale = jnp.asarray(point.imep_scale, dtype=jnp.float64)
        return rpm, scale, point.load

    def state(self, inertia, point):
        out = _state(
            self.engine,
            jnp.asarray(inertia, dtype=jnp.float64),
            *self._args(point),
            self.fidelity,
            self.friction,
            self.grid_deg,
        )
        return tuple(float(v) for v in jax.device_get(out))

    def root(self, u0, log_target, point, rtol):
        u, ok, steps = _root(
            self.engine,
            jnp.asarray(u0, dtype=jnp.float64),
            jnp.asarray(log_target),
            *self._args(point),
            self.fidelity,
            self.friction,
            self.grid_deg,
            rtol,
        )
        return float(u), bool(ok), int(steps)


def inertia_for_delta(
    engine,
    delta: float,
    rpm=None,
    *,
    imep_scale=1.0,
    load=None,
    fidelity: str = "variable",
    friction=None,
    grid_deg: float = 0.25,
    rtol: float = 1e-10,
) -> float:
    """The ``[crankshaft] inertia_kgm2`` [kg·m²] at which the steady state at one operating
    point has exactly δ = ``delta`` (Newton's method through :func:`rotor.steady_state`).
    Arguments as in :func:`design_flywheel`, for one point."""
    design = design_flywheel(
        engine,
        delta,
        [OperatingPoint(engine.operating.rpm if rpm is None else rpm, imep_scale, load)],
        fidelity=fidelity,
        friction=friction,
        grid_deg=grid_deg,
        rtol=rtol,
    )
    return design.crankshaft_inertia_kgm2


# ----------------------------------------------------------------------------- geometry
@dataclass(frozen=True)
class DiscFlywheel:
    """A steel or cast-iron disc flywheel [m, kg, kg·m², m/s]: outer diameter, bore, width
    (axial), density, its inertia and mass, and its peak rim speed (at ``peak_rpm``)."""

    outer_diameter_m: float
    bore_m: float
    width_m: float
    density_kg_m3: float
    inertia_kgm2: float
    mass_kg: float
    rim_speed_m_s: float
    peak_rpm: float
    limited_by: str


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
    ``bore_m`` [m]; the limits: outer diameter [m], width [m], rim speed [m/s]; at least
    one of the outer diameter or the rim speed must be given.
    """
    J = float(inertia_kgm2)
    if not (math.isfinite(J) and J > 0):
        raise EngineError(
            f"flywheel inertia {J:.4g} kg·m²: must be positive (the shaft's own inertia already meets "
            "the target: no flywheel is needed)"
        )
    for name, v in (("density_kg_m3", density_kg_m3), ("peak_rpm", peak_rpm)):
        if not (math.isfinite(float(v)) and float(v) > 0):
            raise EngineError(f"{name} = {v!r}: must be positive")
    for name, v in (
        ("max_outer_diameter_m", max_outer_diameter_m),
        ("max_width_m", max_width_m),
        ("max_rim_speed_m_s", max_rim_speed_m_s),
    ):
        if v is not None and not (math.isfinite(float(v)) and float(v) > 0):
            raise EngineError(f"{name} = {v!r}: a limit must be positive (or left out)")
    try:
        bore_m = float(bore_m)
    except (TypeError, ValueError):
        bore_m = float("nan")
    if not (bore_m >= 0 and math.isfinite(bore_m)):
        raise EngineError("bore_m: must be a number ≥ 0 [m]")
    omega = peak_rpm / RPM_PER_RAD_S
    bounds = {}
    if max_outer_diameter_m is not None:
        bounds["outer diameter"] = float(max_outer_diameter_m)
    if max_rim_speed_m_s is not None:
        bounds["rim speed"] = 2 * float(max_rim_speed_m_s) / omega
    if not bounds:
        raise EngineError(
            "the lightest disc is as large as allowed: give max_outer_diameter_m or max_rim_speed_m_s "
            "(or use the textbook's mean diameter of 2…3 strokes)"
        )
    limited_by = min(bounds, key=bounds.get)
    D = bounds[limited_by]
    if not D**4 - bore_m**4 > 0 or D <= bore_m:
        raise EngineError(
            f"the outer diameter allowed by the {limited_by} limit, {D:.4g} m, is not larger than the "
            f"bore {bore_m:.4g} m"
        )
    rho = float(density_kg_m3)
    width = 32 * J / (rho * math.pi * (D**4 - bore_m**4))
    if max_width_m is not None and width > max_width_m:
        need_D = (32 * J / (rho * math.pi * max_width_m) + bore_m**4) ** 0.25
        larger = (
            f"an outer diameter of {need_D:.4g} m"
            if limited_by == "outer diameter"
            else f"a rim speed of {need_D * omega / 2:.4g} m/s"
        )
        raise EngineError(
            f"no disc meets the limits: {J:.4g} kg·m² at an outer diameter of {D:.4g} m ({limited_by} limit) needs a "
            f"width of {width * 1e3:.1f} mm, more than the {max_width_m * 1e3:.1f} mm allowed; allow a width of "
            f"{width * 1e3:.1f} mm, {larger}, or a looser δ target"
        )
    mass = rho * math.pi * width * (D**2 - bore_m**2) / 4
    return DiscFlywheel(
        outer_diameter_m=D,
        bore_m=float(bore_m),
        width_m=width,
        density_kg_m3=rho,
        inertia_kgm2=J,
        mass_kg=mass,
        rim_speed_m_s=omega * D / 2,
        peak_rpm=float(peak_rpm),
        limited_by=limited_by,
    )


# ----------------------------------------------------------------------------- the design
@dataclass(frozen=True)
class PointResult:
    """One operating point of a design: the inertia that meets δ_target there exactly
    [kg·m²], δ with the designed inertia [-], the peak speed [rev/min] and the textbook."""

    rpm: float
    imep_scale: object
    load: str
    delta_target: float
    inertia_kgm2: float
    delta: float
    peak_rpm: float
    newton_steps: int
    textbook: TextbookFlywheel
    fuel_scale: float | None = None  # the fuelling solved for a speed-dependent load [-]


@dataclass(frozen=True)
class FlywheelDesign:
    """The smallest ``[crankshaft] inertia_kgm2`` meeting each point's δ target, the
    textbook estimate, and (with limits) the lightest disc.

    - ``crankshaft_inertia_kgm2``: the designed ``[crankshaft] inertia_kgm2`` [kg·m²];
    - ``binding_rpm``: the point that sets it; ``delta_target``: its target [-];
      ``delta_achieved``: δ there [-];
    - ``textbook``: the textbook sizing at the point where it asks most (the textbook
      applied at every point; at one point only it can be far off: see ``points``);
      ``textbook_inertia_kgm2``: its ``[crankshaft]`` equivalent (J₀ less the rods and
      pistons); ``textbook_ratio``: that over the design; ``textbook_total_ratio``: J₀ over
      the design's total mean inertia (the fairer ratio when the rods and pistons are a
      large share);
    - ``flywheel_kgm2``: the design less ``shaft_inertia_kgm2`` (what the flywheel must add);
    - ``disc``: a :class:`DiscFlywheel` or None; ``points``: per point.
    """

    engine_name: str
    delta_target: float
    crankshaft_inertia_kgm2: float
    binding_rpm: float
    delta_achieved: float
    shaft_inertia_kgm2: float
    flywheel_kgm2: float
    textbook: TextbookFlywheel
    points: tuple
    disc: DiscFlywheel | None = None
    fidelity: str = "variable"
    settings: dict = field(default_factory=dict)
    friction: object = None  # as given to design_flywheel (for plots); not in to_dict
    binding_index: int = 0  # of the binding point in ``points``
    loads: tuple = ()  # each point's load object (for plots); not in to_dict

    @property
    def textbook_inertia_kgm2(self) -> float:
        return self.textbook.crankshaft_inertia_kgm2

    @property
    def textbook_ratio(self) -> float:
        """textbook ``[crankshaft]`` inertia / designed [-] (> 1: the textbook oversizes)."""
        return self.textbook_inertia_kgm2 / self.crankshaft_inertia_kgm2

    @property
    def textbook_total_ratio(self) -> float:
        """textbook J₀ / the design's total mean inertia (crankshaft + rods and pistons) [-]."""
        t = self.textbook
        mechanism = t.total_inertia_kgm2 - t.crankshaft_inertia_kgm2
        return t.total_inertia_kgm2 / (self.crankshaft_inertia_kgm2 + mechanism)

    def to_dict(self) -> dict:
        d = {
            "engine": self.engine_name,
            "delta_target": self.delta_target,
            "crankshaft_inertia_kgm2": self.crankshaft_inertia_kgm2,
            "textbook_inertia_kgm2": self.textbook_inertia_kgm2,
            "textbook_ratio": self.textbook_ratio,
            "textbook_total_ratio": self.textbook_total_ratio,
            "binding_rpm": self.binding_rpm,
            "delta_achieved": self.delta_achieved,
            "shaft_inertia_kgm2": self.shaft_inertia_kgm2,
            "flywheel_kgm2": self.flywheel_kgm2,
            "textbook": asdict(self.textbook),
            "fidelity": self.fidelity,
            "points": [dict(asdict(p), textbook=asdict(p.textbook)) for p in self.points],
            "disc": None if self.disc is None else asdict(self.disc),
        }
        d.update(self.settings)
        return d

    def report(self) -> str:
        """A comparison of the textbook and the designed flywheel, as text."""
        t = self.textbook
        lines = [
            f"{self.engine_name}: the smallest flywheel for δ ≤ target at {len(self.points)} operating point(s)",
            "",
            f"  {'rpm':>7} {'fuelling':>10} {'load':>12} {'δ target':>9} {'J for target':>13} {'δ (design)':>11} "
            f"{'J textbook':>11}",
        ]
        for i, p in enumerate(self.points):
            mark = "  ← binding" if i == self.binding_index else ""
            scale = f"{p.imep_scale:g}" if isinstance(p.imep_scale, (int, float)) else "per cyl."
            if p.fuel_scale is not None:  # solved for a speed-dependent load
                scale = (
                    f"×{p.fuel_scale:.3g}"
                    if isinstance(p.imep_scale, (int, float)) and p.imep_scale == 1
                    else f"{scale} ×{p.fuel_scale:.3g}"
                )
            need = f"{p.inertia_kgm2:13.4f}" if p.inertia_kgm2 > 0 else f"{'none':>13}"
            tb = p.textbook.crankshaft_inertia_kgm2
            tb = f"{tb:11.4f}" if tb > 0 else f"{'n/a':>11}"
            lines.append(
                f"  {p.rpm:7g} {scale:>10} {p.load:>12} {p.delta_target:9.4g} {need} {p.delta:11.5f} {tb}{mark}"
            )
        lines += [
            "",
            f"  designed [crankshaft] inertia_kgm2   {self.crankshaft_inertia_kgm2:10.4f} kg·m²  (binding at "
            f"{self.binding_rpm:g} rpm, δ = {self.delta_achieved:.5f})",
            f"  textbook (seed 004 §3.2.12) at {t.rpm:g} rpm: J₀ = L_excess/(δ·ω²) = {t.excess_work_J:.1f} J / "
            f"({t.delta:g}·{t.rpm / RPM_PER_RAD_S:.1f}²) = {t.total_inertia_kgm2:.4f} kg·m²",
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
                f"({t.total_inertia_kgm2 - t.crankshaft_inertia_kgm2:.4g} kg·m²)"
            )
        if t.delta > 0.2:
            lines.append(f"    (δ = {t.delta:g} is not small: the textbook's first-order theory does not hold)")
        mech = t.total_inertia_kgm2 - t.crankshaft_inertia_kgm2
        lines.append(
            f"    the seed's flywheel 0.85·J₀ = {t.flywheel_kgm2:.4f} kg·m², {t.mass_kg:.1f} kg as a rim of mean "
            f"diameter {t.mean_diameter_m:.3f} m; its 0.85 assumes the shaft, rods and pistons make "
            f"0.15·J₀ = {0.15 * t.total_inertia_kgm2:.4g} kg·m² (rods and pistons here: {mech:.4g})"
        )
        if self.shaft_inertia_kgm2:
            if self.flywheel_kgm2 > 0:
                r = t.flywheel_kgm2 / self.flywheel_kgm2
                lines.append(
                    f"  flywheel to add to a shaft of {self.shaft_inertia_kgm2:g} kg·m²: "
                    f"{self.flywheel_kgm2:.4f} kg·m² (the seed's 0.85·J₀ is {r:.3f} × it, {100 * (r - 1):+.1f} %)"
                )
            else:
                lines.append(
                    f"  a shaft of {self.shaft_inertia_kgm2:g} kg·m² alone meets the target: no flywheel is needed"
                )
        if self.disc is not None:
            d = self.disc
            lines.append(
                f"  lightest disc: D = {d.outer_diameter_m:.3f} m ({d.limited_by} limit), bore "
                f"{d.bore_m:.3f} m, width {d.width_m * 1e3:.1f} mm, {d.mass_kg:.1f} kg, rim speed "
                f"{d.rim_speed_m_s:.1f} m/s at {d.peak_rpm:.0f} rpm (the highest speed it must stand)"
            )
        return "\n".join(lines)

    def plot(self, engine, axes=None, rpm_range=None, n: int = 25):
        """Plot the design (needs the ``engine``): see :func:`rotor.plotting.plot_flywheel_design`."""
        from ..plotting import plot_flywheel_design

        return plot_flywheel_design(self, engine, axes=axes, rpm_range=rpm_range, n=n)


def _load_name(load):
    return "balanced" if load is None else type(load).__name__


def design_flywheel(
    engine,
    delta: float | None,
    points=None,
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
    friction=None,
    grid_deg: float = 0.25,
    rtol: float = 1e-10,
) -> FlywheelDesign:
    """The smallest flywheel keeping δ ≤ ``delta`` at every operating point.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`; its ``[crankshaft] inertia_kgm2`` is only the
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

    **Returns:** a :class:`FlywheelDesign`; ``.report()`` compares it with the textbook.

    **Raises:** :class:`rotor.EngineError` for a bad target or point, an operating point
    with no steady state, or limits no disc can meet.
    """
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
    ev = _Evaluator(engine, fidelity, friction, grid_deg)
    j_start = float(engine.crankshaft.inertia_kgm2)
    results = []
    for p in pts:
        target = default if p.delta is None else float(p.delta)
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
    point_results = []
    peak = float(engine.operating.rpm) if max_rpm is None else float(max_rpm)
    for p, J, steps, tb, target in results:
        try:  # the eager steady state: every check of rotor.steady_state applies to the design
            r = steady_state(
                _with_inertia(engine, J_design),
                p.rpm,
                p.load,
                fidelity=fidelity,
                friction=friction,
                imep_scale=p.imep_scale,
                grid_deg=grid_deg,
            )
        except NoSteadyStateError as e:
            raise EngineError(
                f"the designed inertia {J_design:.4g} kg·m² has no steady state at {p.rpm:g} rpm: {e}"
            ) from e
        if max_rpm is None:
            peak = max(peak, float(r.max_rpm))
        fuel = r.info.get("fuel_scale")
        point_results.append(
            PointResult(
                rpm=p.rpm,
                imep_scale=_jsonable(p.imep_scale),
                load=_load_name(p.load),
                delta_target=target,
                inertia_kgm2=J,
                delta=float(r.delta),
                peak_rpm=float(r.max_rpm),
                newton_steps=steps,
                textbook=tb,
                fuel_scale=None if fuel is None else float(fuel),
            )
        )
    tb_worst = max((r[3] for r in results), key=lambda t: t.crankshaft_inertia_kgm2)
    flywheel = J_design - float(shaft_inertia_kgm2)
    disc = None
    if (max_outer_diameter_m is not None or max_rim_speed_m_s is not None) and flywheel > 0:
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
        engine_name=engine.name,
        delta_target=results[i_bind][4],
        crankshaft_inertia_kgm2=J_design,
        binding_rpm=pts[i_bind].rpm,
        delta_achieved=point_results[i_bind].delta,
        shaft_inertia_kgm2=float(shaft_inertia_kgm2),
        flywheel_kgm2=flywheel,
        textbook=tb_worst,
        points=tuple(point_results),
        disc=disc,
        fidelity=fidelity,
        binding_index=i_bind,
        settings={"grid_deg": grid_deg, "diameter_strokes": diameter_strokes},
        friction=friction,
        loads=tuple(p.load for p in pts),
    )


def _number(name, v, lo, strict=True):
    try:
        x = float(v)
    except (TypeError, ValueError):
        x = float("nan")
    if not (math.isfinite(x) and (x > lo if strict else x >= lo)):
        raise EngineError(f"{name} = {v!r}: must be a number {'>' if strict else '≥'} {lo:g}")
    return x


def _check_design_args(shaft, diameter_strokes, grid_deg, max_rpm, disc, max_width_m, bore_m):
    _number("shaft_inertia_kgm2", shaft, 0.0, strict=False)
    _number("diameter_strokes", diameter_strokes, 0.0)
    _number("grid_deg", grid_deg, 0.0)
    if max_rpm is not None:
        _number("max_rpm", max_rpm, 0.0)
    if not disc and (max_width_m is not None or bore_m):
        raise EngineError(
            "a width limit or a bore shapes the lightest disc, which needs an outer-diameter or a "
            "rim-speed limit as well (max_outer_diameter_m or max_rim_speed_m_s)"
        )


def _point_inertia(engine, ev, p, target, j_start, diameter_strokes, rtol):
    """The [crankshaft] inertia with δ = target at one point (0 where none is needed), the
    Newton steps and the textbook there."""
    j_try = j_start
    for _ in range(6):  # the textbook diagram does not depend on the inertia; find a start with a steady state
        d0, excess = ev.state(j_try, p)
        if math.isfinite(d0):
            break
        j_try *= 10
    else:
        raise EngineError(
            f"no steady state at {p.rpm:g} rpm even with a {j_try / 10:g} kg·m² crankshaft: the engine "
            "cannot run at this point (check its fuelling and load)"
        )
    mech = ev.mechanism
    tb = _textbook(engine, target, p, excess, mech, diameter_strokes)
    # start from this point's own δ/J slope (δ ∝ 1/(J + mech))
    u0 = math.log(max((j_try + mech) * d0 / target - mech, 1e-3 * (j_try + mech)))
    u, ok, steps = ev.root(u0, math.log(target), p, rtol)
    J = math.exp(u)
    d_check = ev.state(J, p)[0] if ok else float("nan")
    if ok and abs(d_check / target - 1) < 1e-6:
        return J, steps, tb
    # why not: no flywheel needed (δ below the target with almost no crankshaft inertia), or a target too tight
    j_floor = 1e-6 * (j_try + mech)
    d_floor = ev.state(j_floor, p)[0]
    if math.isfinite(d_floor) and d_floor <= target:
        return 0.0, steps, tb
    raise EngineError(
        f"at {p.rpm:g} rpm Newton's method found no crankshaft inertia with δ = {target:g} (it stopped at "
        f"{J:.4g} kg·m², δ = {d_check:.4g}; with a {j_try:g} kg·m² crankshaft δ = {d0:.4g}): check the target "
        "(too tight for float64 below about 1e-8?), the tolerance rtol, and rotor.steady_state at this point"
    )


def _jsonable(x):
    a = np.asarray(x, dtype=float)
    return float(a) if a.ndim == 0 else a.tolist()
