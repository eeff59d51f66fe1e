"""Loads on the crankshaft and the speed governor, as equinox Modules.

A load is a torque against the rotation, M_load(ω, t) [N·m], with ω the crank speed
[rad/s] and t the time since the start of the run [s]. All fields are float64 arrays,
so ``jax.grad`` and ``jax.vmap`` work over any of them.

- :class:`ConstantLoad` — M = torque_Nm (a dynamometer holding torque; neutral in speed).
- :class:`PolynomialLoad` — M = a + b·ω + c·ω².
- :class:`PropellerLoad` — M = torque_Nm·(ω/ω_rated)² (propeller law, fan, vehicle drag).
- :class:`TableLoad` — M linear in rpm between tabulated points, constant beyond them.
- :class:`LoadStep` — one load changing to another at a time, at once or over a ramp.

:class:`Governor` is not a load: it scales the fuelling (the combustion part of every
cylinder's gas torque) by a PI law on the speed error.

:func:`parse_load` turns the command line's ``--load SPEC`` into one of these.
"""

from __future__ import annotations

import abc
from typing import Any, ClassVar, cast

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..checks import TRACED, as_f64, check_finite, check_positive, concrete, guard, guard_number, has_tracer, is_tracer
from ..errors import EngineError
from ..units import RPM_PER_RAD_S
from .load_help import LOAD_HELP

__all__ = [
    "Load",
    "ConstantLoad",
    "PolynomialLoad",
    "PropellerLoad",
    "TableLoad",
    "LoadStep",
    "Governor",
    "parse_load",
    "guard_load",
    "guard_governor",
]

#: (a, b, c) of a load a + b·ω + c·ω², None for a coefficient that is zero
Coefficients = tuple[ArrayLike | None, ArrayLike | None, ArrayLike | None]


class Load(eqx.Module):
    """What every load is (abstract): a torque ``torque(omega, t)`` [N·m] against the rotation.

    Concrete loads are final ``eqx.Module`` classes. ``time_dependent``: whether the
    torque changes with time at a given speed (a steady state needs it False).
    """

    time_dependent: eqx.AbstractClassVar[bool]

    @abc.abstractmethod
    def torque(self, omega: ArrayLike, t: ArrayLike) -> Float[Array, ...]:
        """The load torque [N·m] at crank speed ``omega`` [rad/s] and time ``t`` [s]."""

    @abc.abstractmethod
    def polynomial(self) -> Coefficients | None:
        """(a, b, c) when the load is a + b·ω + c·ω² with constant coefficients
        ([N·m], [N·m·s/rad], [N·m·s²/rad²]; None for a zero one), else None."""


class ConstantLoad(Load):
    """A constant torque against the rotation.

    **Fields:** ``torque_Nm`` [N·m] (negative: a torque driving the crankshaft, e.g. a starter).
    """

    torque_Nm: jnp.ndarray = eqx.field(converter=as_f64)
    time_dependent: ClassVar[bool] = False

    def __check_init__(self) -> None:
        check_finite("load", "torque_Nm", self.torque_Nm)

    def torque(self, omega: ArrayLike, t: ArrayLike) -> Float[Array, ...]:
        """``torque_Nm`` [N·m] at every speed ``omega`` [rad/s] and time ``t`` [s]."""
        return self.torque_Nm + 0.0 * jnp.asarray(omega)

    def polynomial(self) -> Coefficients:
        """(torque_Nm, None, None) [N·m]."""
        return self.torque_Nm, None, None


class PolynomialLoad(Load):
    """M = a + b·ω + c·ω² [N·m], ω in rad/s.

    **Fields:** ``a`` [N·m], ``b`` [N·m·s/rad], ``c`` [N·m·s²/rad²].
    """

    a: jnp.ndarray = eqx.field(converter=as_f64)
    b: jnp.ndarray = eqx.field(converter=as_f64, default=0.0)
    c: jnp.ndarray = eqx.field(converter=as_f64, default=0.0)
    time_dependent: ClassVar[bool] = False

    def __check_init__(self) -> None:
        for k in ("a", "b", "c"):
            check_finite("load", k, getattr(self, k))

    def torque(self, omega: ArrayLike, t: ArrayLike) -> Float[Array, ...]:
        """a + b·ω + c·ω² [N·m] at speed ``omega`` [rad/s] (any time ``t`` [s])."""
        omega = jnp.asarray(omega)
        return self.a + self.b * omega + self.c * omega**2

    def polynomial(self) -> Coefficients:
        """(a, b, c) [N·m, N·m·s/rad, N·m·s²/rad²]."""
        return self.a, self.b, self.c


class PropellerLoad(Load):
    """Propeller law M = torque_Nm·(n/rpm)².

    **Fields:** ``torque_Nm``: torque at the rated speed [N·m]; ``rpm``: the rated speed [rpm].
    """

    torque_Nm: jnp.ndarray = eqx.field(converter=as_f64)
    rpm: jnp.ndarray = eqx.field(converter=as_f64)
    time_dependent: ClassVar[bool] = False

    def __check_init__(self) -> None:
        check_finite("load", "torque_Nm", self.torque_Nm)
        check_positive("load", "rpm", self.rpm)

    @property
    def c(self) -> Array:
        """The coefficient c of M = c·ω² [N·m·s²/rad²]."""
        return self.torque_Nm / (self.rpm / RPM_PER_RAD_S) ** 2

    def torque(self, omega: ArrayLike, t: ArrayLike) -> Float[Array, ...]:
        """c·ω² [N·m] at speed ``omega`` [rad/s] (any time ``t`` [s])."""
        return self.c * jnp.asarray(omega) ** 2

    def polynomial(self) -> Coefficients:
        """(None, None, c) [N·m·s²/rad²]."""
        return None, None, self.c


class TableLoad(Load):
    """Torque tabulated against speed, linear in between, constant beyond the ends.

    **Fields:** ``rpm``: increasing speeds [rpm]; ``torque_Nm``: torque at each [N·m].
    """

    rpm: jnp.ndarray = eqx.field(converter=as_f64)
    torque_Nm: jnp.ndarray = eqx.field(converter=as_f64)
    time_dependent: ClassVar[bool] = False

    def __check_init__(self) -> None:
        r, m = concrete(self.rpm), concrete(self.torque_Nm)
        if r is None or m is None:
            return
        if r.ndim != 1 or r.shape != m.shape or r.size < 2:
            raise EngineError("a load table needs rpm and torque_Nm lists of the same length, 2 points or more")
        check_finite("load", "rpm", r)
        check_finite("load", "torque_Nm", m)
        if np.any(np.diff(r) <= 0):
            raise EngineError(f"load table: rpm must increase, got {r.tolist()}")

    def torque(self, omega: ArrayLike, t: ArrayLike) -> Float[Array, ...]:
        """The tabulated torque [N·m] at speed ``omega`` [rad/s] (any time ``t`` [s])."""
        return jnp.interp(jnp.asarray(omega) * RPM_PER_RAD_S, self.rpm, self.torque_Nm)

    def polynomial(self) -> None:
        """None: a table is not a polynomial."""
        return None


class LoadStep(Load):
    """``before`` until ``time_s``, then ``after`` (a linear ramp over ``ramp_s`` if > 0).

    **Fields:** ``before``, ``after``: loads; ``time_s``: when the change starts [s];
    ``ramp_s``: how long it takes [s] (0: a step).
    """

    before: Load
    after: Load
    time_s: jnp.ndarray = eqx.field(converter=as_f64)
    ramp_s: jnp.ndarray = eqx.field(converter=as_f64, default=0.0)
    time_dependent: ClassVar[bool] = True

    def __check_init__(self) -> None:
        check_positive("load", "time_s", self.time_s, allow_zero=True)
        check_positive("load", "ramp_s", self.ramp_s, allow_zero=True)

    def fraction(self, t: ArrayLike) -> Float[Array, ...]:
        """How far the change has gone at time ``t`` [s]: 0 … 1 [-]."""
        ramp = jnp.maximum(self.ramp_s, 1e-300)
        return jnp.where(self.ramp_s > 0, jnp.clip((t - self.time_s) / ramp, 0.0, 1.0), (t >= self.time_s) * 1.0)

    def torque(self, omega: ArrayLike, t: ArrayLike) -> Float[Array, ...]:
        """``before`` blended into ``after`` [N·m] at speed ``omega`` [rad/s] and time ``t`` [s]."""
        f = self.fraction(t)
        return (1 - f) * self.before.torque(omega, t) + f * self.after.torque(omega, t)

    def polynomial(self) -> None:
        """None: the load changes in time."""
        return None


class Governor(eqx.Module):
    """PI speed governor scaling the fuelling.

    fuel = clip(fuel_start + kp·e + ki·∫e dt, fuel_min, fuel_max), e = (ω_set − ω)/ω_set.
    The fuel scale multiplies the combustion part of every cylinder's gas torque (fired
    minus motored), so fuel = 1 is the engine file's operating point and 0 is motoring.

    **Fields:** ``rpm``: set speed [rpm]; ``kp``: proportional gain [1 per unit speed
    error]; ``ki``: integral gain [1/s per unit speed error]; ``fuel_start``,
    ``fuel_min``, ``fuel_max``: fuel scale at the start and its limits [-].
    """

    rpm: jnp.ndarray = eqx.field(converter=as_f64)
    kp: jnp.ndarray = eqx.field(converter=as_f64, default=5.0)
    ki: jnp.ndarray = eqx.field(converter=as_f64, default=10.0)
    fuel_start: jnp.ndarray = eqx.field(converter=as_f64, default=1.0)
    fuel_min: jnp.ndarray = eqx.field(converter=as_f64, default=0.0)
    fuel_max: jnp.ndarray = eqx.field(converter=as_f64, default=2.0)

    def __check_init__(self) -> None:
        check_positive("governor", "rpm", self.rpm)
        for k in ("kp", "ki", "fuel_start", "fuel_min", "fuel_max"):
            check_positive("governor", k, getattr(self, k), allow_zero=True)
        lo, hi = concrete(self.fuel_min), concrete(self.fuel_max)
        if lo is not None and hi is not None and not lo < hi:
            raise EngineError(f"governor: fuel_min ({lo:g}) must be below fuel_max ({hi:g})")

    @property
    def omega(self) -> Array:
        """The set speed [rad/s]."""
        return self.rpm / RPM_PER_RAD_S

    def error(self, omega: ArrayLike) -> Float[Array, ...]:
        """Relative speed error (ω_set − ω)/ω_set [-] at speed ``omega`` [rad/s]."""
        return (self.omega - omega) / self.omega

    def fuel(self, omega: ArrayLike, integral: ArrayLike) -> Float[Array, ...]:
        """Fuel scale [-] at speed ``omega`` [rad/s] and integrated error ``integral`` [s]."""
        u = self.fuel_start + self.kp * self.error(omega) + self.ki * integral
        return jnp.clip(u, self.fuel_min, self.fuel_max)


def _guarded(module: eqx.Module, rules: dict[str, tuple[float, bool]], table: str, checks: Any) -> eqx.Module:
    """``module`` with each traced field of ``rules`` (name → (lower bound, strictly above
    it)) checked when the program runs (recorded in ``checks`` where given): finite and
    within the bound, the message naming ``[table] field`` as the concrete check does."""
    names = [k for k in rules if is_tracer(getattr(module, k))]
    if not names:
        return module
    checked = [
        guard_number(getattr(module, k), f"[{table}] {k}", rules[k][0], above=rules[k][1], checks=checks) for k in names
    ]
    return eqx.tree_at(lambda m: [getattr(m, k) for k in names], module, checked)


_FINITE = (-np.inf, False)
_POSITIVE = (0.0, True)
_NOT_NEGATIVE = (0.0, False)


def guard_load(load: Load | None, checks: Any = None) -> Load | None:
    """``load`` with its traced fields checked when the program runs (``eqx.error_if``; with
    ``checks``, a :class:`rotor.checks.TracedChecks`, recorded there), as its class checks
    concrete ones when it is built: a torque finite, a speed positive, a time not negative,
    a table's speeds increasing. The same load where nothing is traced."""
    if load is None or not has_tracer(load):
        return load
    if isinstance(load, ConstantLoad):
        return cast(Load, _guarded(load, {"torque_Nm": _FINITE}, "load", checks))
    if isinstance(load, PolynomialLoad):
        return cast(Load, _guarded(load, {"a": _FINITE, "b": _FINITE, "c": _FINITE}, "load", checks))
    if isinstance(load, PropellerLoad):
        return cast(Load, _guarded(load, {"torque_Nm": _FINITE, "rpm": _POSITIVE}, "load", checks))
    if isinstance(load, TableLoad):
        load = cast(TableLoad, _guarded(load, {"rpm": _FINITE, "torque_Nm": _FINITE}, "load", checks))
        rpm = guard(load.rpm, ~jnp.all(jnp.diff(load.rpm) > 0), f"load table: rpm must increase; {TRACED}", checks)
        return eqx.tree_at(lambda m: m.rpm, load, rpm)
    if isinstance(load, LoadStep):
        load = cast(LoadStep, _guarded(load, {"time_s": _NOT_NEGATIVE, "ramp_s": _NOT_NEGATIVE}, "load", checks))
        parts = [guard_load(load.before, checks), guard_load(load.after, checks)]
        return eqx.tree_at(lambda m: [m.before, m.after], load, parts)
    return load  # a load class of the caller's own: its own checks


def guard_governor(governor: Governor | None) -> Governor | None:
    """``governor`` with its traced fields checked when the program runs, as
    :class:`Governor` checks concrete ones (a positive set speed, gains and fuel scales
    not negative, ``fuel_min`` below ``fuel_max``). The same governor where nothing is traced."""
    if governor is None or not has_tracer(governor):
        return governor
    rules = {"rpm": _POSITIVE} | dict.fromkeys(("kp", "ki", "fuel_start", "fuel_min", "fuel_max"), _NOT_NEGATIVE)
    governor = cast(Governor, _guarded(governor, rules, "governor", None))
    fuel_max = guard(
        governor.fuel_max,
        ~(jnp.asarray(governor.fuel_min) < jnp.asarray(governor.fuel_max)),
        f"governor: fuel_min must be below fuel_max; {TRACED}",
    )
    return eqx.tree_at(lambda g: g.fuel_max, governor, fuel_max)


def _numbers(text: str, n: int, spec: str) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) != n or not all(np.isfinite(vals)):
        raise EngineError(f"load={spec!r}: expected {n} number{'s' if n > 1 else ''} after the colon", argument="load")
    return vals


def parse_load(spec: str) -> Load | None:
    """A load from its command-line spec ``spec`` (see ``rotor simulate --help`` and
    :data:`LOAD_HELP`; torques in N·m, speeds in rpm, times in s); None for ``"none"``."""
    s = spec.strip()
    kind, _, rest = s.partition(":")
    kind = kind.lower()
    try:
        if s.lower() == "none":
            return None
        if not rest:
            try:
                return ConstantLoad(as_f64(float(s)))
            except ValueError:
                raise EngineError(f"load={spec!r}: not understood; {LOAD_HELP}", argument="load") from None
        if kind == "constant":
            return ConstantLoad(*map(as_f64, _numbers(rest, 1, spec)))
        if kind == "poly":
            return PolynomialLoad(*map(as_f64, _numbers(rest, 3, spec)))
        if kind == "propeller":
            return PropellerLoad(*map(as_f64, _numbers(rest, 2, spec)))
        if kind == "step":
            vals = [float(v) for v in rest.split(",")] if rest.count(",") in (2, 3) else _numbers(rest, 3, spec)
            ramp = vals[3] if len(vals) == 4 else 0.0
            before, after, time_s, ramp_s = (as_f64(v) for v in (vals[0], vals[1], vals[2], ramp))
            return LoadStep(ConstantLoad(before), ConstantLoad(after), time_s, ramp_s)
        if kind == "table":
            pairs = [p.split("=") for p in rest.split(",")]
            if any(len(p) != 2 for p in pairs):
                raise EngineError(f"load={spec!r}: a table is RPM=TORQUE_NM pairs separated by commas", argument="load")
            rpm, tq = zip(*[(float(a), float(b)) for a, b in pairs])
            return TableLoad(as_f64(list(rpm)), as_f64(list(tq)))
    except ValueError as e:
        if isinstance(e, EngineError):
            raise
        raise EngineError(f"load={spec!r}: {e}; {LOAD_HELP}", argument="load") from None
    raise EngineError(f"load={spec!r}: unknown kind {kind!r}; {LOAD_HELP}", argument="load")
