"""Cylinder pressure sources: a tabulated trace, a single-zone Wiebe cycle, a motored
cycle and none.

Every source is an ``eqx.Module``; calling it, ``source(phi, geometry, strokes)``, gives
the absolute cylinder pressure [Pa] at the cycle angle ``phi`` [rad] of that cylinder. For a
four-stroke engine the cycle angle runs over 0…4π with 0 = TDC at the start of intake
and 2π (360°) = firing TDC; for a two-stroke engine over 0…2π with 0 = firing TDC.

Tables are interpolated with a periodic monotone cubic (PCHIP, Fritsch–Carlson
slopes with Brodlie's weights): it passes through every point, is continuously
differentiable including across the end of the cycle, and never overshoots, so a
step in the table (the drop at 540° when the exhaust opens in
the 4ChN15/20.5 table of Shishkov, "Dinamika dvigatelei", SUSU 2014) does not ring.
"""

from __future__ import annotations

import abc
from typing import TYPE_CHECKING, ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..checks import TRACED, called_from_outside, check_finite, check_positive, concrete, fmt, guard, is_tracer, where
from ..errors import EngineError
from .kinematics import piston_motion
from .plausible import check_fields_plausible, checked_angle, number, require_number

__all__ = [
    "PressureSource",
    "PressureTable",
    "WiebeCycle",
    "MotoredCycle",
    "NoPressure",
    "periodic_pchip",
    "cylinder_volume_m3",
]

STANDARD_CRANKCASE_PA = 101325.0
_WIEBE_A = 6.908  # ln(1000): 99.9 % of the charge burnt at the end of the duration


# --------------------------------------------------------------------------- interpolation
def _pchip_slopes(x, y, period):
    """Periodic PCHIP slopes at the knots ``x`` (strictly increasing, within one period)."""
    xe = jnp.concatenate([x[-1:] - period, x, x[:1] + period])
    ye = jnp.concatenate([y[-1:], y, y[:1]])
    h = jnp.diff(xe)
    d = jnp.diff(ye) / h
    hl, hr = h[:-1], h[1:]
    dl, dr = d[:-1], d[1:]
    same_sign = dl * dr > 0
    w1 = 2 * hr + hl
    w2 = hr + 2 * hl
    dl_safe = jnp.where(same_sign, dl, 1.0)
    dr_safe = jnp.where(same_sign, dr, 1.0)
    m = (w1 + w2) / (w1 / dl_safe + w2 / dr_safe)
    return jnp.where(same_sign, m, 0.0)


def periodic_pchip(xq: ArrayLike, x: ArrayLike, y: ArrayLike, period: float) -> Array:
    """Evaluate the periodic monotone cubic through (x, y) at ``xq``.

    **Arguments:**
    - ``xq``: query points (any shape, any real value: wrapped into one period).
    - ``x``: knots, strictly increasing, ``x[0] <= xq mod period < x[0] + period``.
    - ``y``: values at the knots. ``period``: the period, same unit as ``x``.

    **Returns:** interpolated values, shape of ``xq``. Differentiable in ``xq`` and ``y``.

    **Raises:** a :class:`TypeError` for values that are not real numbers, a
    :class:`rotor.EngineError` for a NaN or an infinity, knots that do not increase within
    one period or a period not above 0, naming the argument; traced values are checked
    when the program runs.
    """
    if called_from_outside():  # rotor's own pressure tables were checked when they were built
        xq, x, y = (
            checked_angle("periodic_pchip", name, v, "x's unit") for name, v in (("xq", xq), ("x", x), ("y", y))
        )
        p = require_number(period, "periodic_pchip(period)")
        if not (np.isfinite(p) and p > 0):
            raise EngineError(f"periodic_pchip(period) = {period!r}: must be a positive, finite number")
        knots = jnp.asarray(x, dtype=jnp.float64)
        increasing = (knots.ndim == 1) & (knots.shape[0] >= 2)
        message = "periodic_pchip(x): the knots must increase strictly, within one period of the first"
        if increasing:
            steps = jnp.concatenate([jnp.diff(knots), (knots[:1] + p) - knots[-1:]])
            ok = jnp.all(steps > 0)
            if is_tracer(ok):
                x = guard(x, ~ok, f"{message}; {TRACED}")
            elif not bool(ok):
                raise EngineError(message)
        else:
            raise EngineError(f"{message}: give two knots or more, in one list")
    return _periodic_pchip(xq, x, y, period)


@eqx.filter_jit  # one compiled program per shape when called outside a jit
def _periodic_pchip(xq: ArrayLike, x: ArrayLike, y: ArrayLike, period: float) -> Array:
    x = jnp.asarray(x, dtype=jnp.float64)
    y = jnp.asarray(y, dtype=jnp.float64)
    xq = jnp.asarray(xq, dtype=jnp.float64)
    m = _pchip_slopes(x, y, period)
    xk = jnp.concatenate([x, x[:1] + period])
    yk = jnp.concatenate([y, y[:1]])
    mk = jnp.concatenate([m, m[:1]])
    u = jnp.mod(xq - x[0], period) + x[0]
    i = jnp.clip(jnp.searchsorted(xk, u, side="right") - 1, 0, x.shape[0] - 1)
    x0, x1 = xk[i], xk[i + 1]
    h = x1 - x0
    t = (u - x0) / h
    t2, t3 = t * t, t * t * t
    h00 = 2 * t3 - 3 * t2 + 1
    h10 = t3 - 2 * t2 + t
    h01 = -2 * t3 + 3 * t2
    h11 = t3 - t2
    return h00 * yk[i] + h10 * h * mk[i] + h01 * yk[i + 1] + h11 * h * mk[i + 1]


# --------------------------------------------------------------------------- geometry
def cylinder_volume_m3(phi, geometry, compression_ratio):
    """Cylinder volume V(φ) = V_c + A·s(φ) [m³] for a compression ratio ε.

    **Arguments:** ``phi`` [rad]; ``geometry``: a :class:`rotor.Geometry`;
    ``compression_ratio``: ε [-] (V_c = V_h/(ε − 1)).
    """
    g = geometry
    area = g.piston_area_m2
    vh = area * g.stroke_m
    s = piston_motion(phi, g.crank_radius_m, g.rod_length_m, g.pin_offset_m).s
    return vh / (compression_ratio - 1.0) + area * s


def _smoothstep(u):
    """C² step from 0 (u ≤ 0) to 1 (u ≥ 1)."""
    u = jnp.clip(u, 0.0, 1.0)
    return u**3 * (10 - 15 * u + 6 * u**2)


# --------------------------------------------------------------------------- sources
class PressureSource(eqx.Module):
    """What every cylinder pressure source is: an abstract ``eqx.Module``.

    Concrete sources (:class:`PressureTable`, :class:`WiebeCycle`, :class:`MotoredCycle`,
    :class:`NoPressure`) are final; each has a ``kind`` (its ``[pressure] kind`` in the
    engine file), a ``crankcase_pa`` field [Pa], and says whether its charge can be
    scaled as a whole (``charge_scalable``, see :meth:`scale_charge`).
    """

    kind: eqx.AbstractClassVar[str]
    charge_scalable: eqx.AbstractClassVar[bool]
    table: ClassVar[str] = "pressure"
    if TYPE_CHECKING:  # every concrete source has this field (not declared here: it has a default)

        @property
        def crankcase_pa(self) -> jnp.ndarray: ...

    @abc.abstractmethod
    def __call__(self, phi: ArrayLike, geometry: object, strokes: int = 4) -> Float[Array, ...]:
        """Absolute cylinder pressure [Pa] at the cycle angles ``phi`` [rad] (any shape) of a
        cylinder with ``geometry`` (a :class:`rotor.Geometry`) in a ``strokes``-stroke engine."""

    @abc.abstractmethod
    def validate_for(self, strokes: int) -> None:
        """Cross-checks that need the engine's cycle: ``strokes`` (2 or 4); raises
        :class:`rotor.EngineError`."""

    @abc.abstractmethod
    def motored(self, strokes: int = 4) -> PressureSource:
        """The trace of the same cylinder without combustion (a misfire) in a
        ``strokes``-stroke engine."""

    @abc.abstractmethod
    def scale_charge(self, sigma: ArrayLike) -> PressureSource:
        """The source with its whole charge scaled by ``sigma`` [-] (a throttle or a boost):
        intake pressure and IMEP × σ. Only where ``charge_scalable``; otherwise raises
        :class:`rotor.EngineError` naming the source kind. Differentiable in ``sigma``."""


def _not_scalable(source: PressureSource) -> EngineError:
    return EngineError(
        f"[pressure] kind = {source.kind!r} cannot scale its charge: only a Wiebe cycle (kind = 'wiebe', "
        "intake_pa and imep_pa scaled together) can"
    )


class NoPressure(PressureSource):
    """No gas force: the cylinder pressure equals the crankcase pressure.

    **Fields:** ``crankcase_pa`` [Pa].
    """

    crankcase_pa: jnp.ndarray = eqx.field(converter=number("pressure", "crankcase_pa"), default=STANDARD_CRANKCASE_PA)
    kind: ClassVar[str] = "none"
    charge_scalable: ClassVar[bool] = False

    def __check_init__(self) -> None:
        check_positive(self.table, "crankcase_pa", self.crankcase_pa, allow_zero=True)
        check_fields_plausible(self)

    def __call__(self, phi: ArrayLike, geometry: object, strokes: int = 4) -> Float[Array, ...]:
        """The crankcase pressure [Pa] at every cycle angle ``phi`` [rad]."""
        return jnp.broadcast_to(self.crankcase_pa, jnp.shape(phi)).astype(jnp.float64)

    def validate_for(self, strokes: int) -> None:
        """Nothing to check: no pressure fits any cycle (``strokes`` 2 or 4)."""

    def motored(self, strokes: int = 4) -> NoPressure:
        """Itself: without combustion nothing changes (``strokes`` 2 or 4)."""
        return self

    def scale_charge(self, sigma: ArrayLike) -> PressureSource:
        """Raises :class:`rotor.EngineError`: there is no charge to scale by ``sigma`` [-]."""
        raise _not_scalable(self)


class PressureTable(PressureSource):
    """A tabulated cylinder pressure trace over one cycle.

    **Fields:**
    - ``angle_deg``: cycle angles [deg], strictly increasing, within 0…720 (four-stroke)
      or 0…360 (two-stroke), the full cycle itself excluded (it is 0° again); the
      table must cover the whole cycle.
    - ``pressure_pa``: absolute cylinder pressure at those angles [Pa].
    - ``crankcase_pa``: crankcase pressure [Pa].
    """

    angle_deg: jnp.ndarray = eqx.field(converter=number("pressure", "angle_deg"))
    pressure_pa: jnp.ndarray = eqx.field(converter=number("pressure", "pressure_pa"))
    crankcase_pa: jnp.ndarray = eqx.field(converter=number("pressure", "crankcase_pa"), default=STANDARD_CRANKCASE_PA)
    kind: ClassVar[str] = "table"
    charge_scalable: ClassVar[bool] = False

    def __check_init__(self) -> None:
        t = self.table
        a, p = concrete(self.angle_deg), concrete(self.pressure_pa)
        if a is not None and p is not None:
            if a.ndim != 1 or p.ndim != 1 or a.shape != p.shape:
                raise EngineError(
                    f"{where(t, 'angle_deg')} and {where(t, 'pressure_pa')} must be lists of the same length "
                    f"(got {a.size} angles and {p.size} pressures)"
                )
            if a.size < 4:
                raise EngineError(f"{where(t, 'angle_deg')}: a pressure table needs at least 4 points, got {a.size}")
            check_finite(t, "angle_deg", a)
            check_positive(t, "pressure_pa", p)
            steps = np.diff(a)
            if np.any(steps <= 0):
                i = int(np.argmax(steps <= 0))
                raise EngineError(
                    f"{where(t, 'angle_deg')}: angles must increase, but point {i + 2} ({a[i + 1]:g}°) "
                    f"does not come after point {i + 1} ({a[i]:g}°)"
                )
        check_positive(t, "crankcase_pa", self.crankcase_pa, allow_zero=True)
        check_fields_plausible(self)

    def validate_for(self, strokes: int) -> None:
        """The table must lie within and cover the ``strokes``-stroke cycle."""
        a = concrete(self.angle_deg)
        if a is None:
            return
        t = self.table
        cycle = 360.0 * strokes / 2
        if a[0] < 0 or a[-1] >= cycle:
            raise EngineError(
                f"{where(t, 'angle_deg')}: angles run from {a[0]:g}° to {a[-1]:g}°, outside the "
                f"{strokes}-stroke cycle 0…{cycle:g}° (the table is periodic: {cycle:g}° is 0° again, leave it out)"
            )
        wrap = a[0] + cycle - a[-1]
        typical = float(np.median(np.diff(a)))
        if wrap > 3 * typical + 1e-9:
            raise EngineError(
                f"{where(t, 'angle_deg')}: the table does not cover the cycle: it runs from {a[0]:g}° to "
                f"{a[-1]:g}°, leaving {wrap:g}° of the {cycle:g}° cycle without points; "
                f"give points over the whole cycle 0…{cycle:g}°"
            )

    def __call__(self, phi: ArrayLike, geometry: object, strokes: int = 4) -> Float[Array, ...]:
        """The interpolated pressure [Pa] at cycle angles ``phi`` [rad] (``geometry`` unused)."""
        period = 2 * jnp.pi * strokes / 2
        return periodic_pchip(phi, jnp.deg2rad(self.angle_deg), self.pressure_pa, period)

    def motored(self, strokes: int = 4) -> PressureTable:
        """The table's motored trace: its compression stroke mirrored about firing TDC.

        Over the 180° after firing TDC (360° four-stroke, 0° two-stroke) the pressure is
        the table's value as far before TDC, p(2·φ_TDC − φ): the reversible polytrope of a
        cylinder that did not fire. The rest of the cycle is kept.
        """
        cycle = 360.0 * strokes / 2
        tdc = 360.0 if strokes == 4 else 0.0
        after = jnp.mod(self.angle_deg - tdc, cycle)
        mirror = (after > 0) & (after <= 180.0)
        reflected = jnp.deg2rad(jnp.mod(2 * tdc - self.angle_deg, cycle))
        p = jnp.where(mirror, self(reflected, None, strokes), self.pressure_pa)
        return PressureTable(self.angle_deg, p, self.crankcase_pa)

    def scale_charge(self, sigma: ArrayLike) -> PressureSource:
        """Raises :class:`rotor.EngineError`: a measured trace has no charge to scale by ``sigma`` [-]."""
        raise _not_scalable(self)


class _SingleZone(PressureSource):
    """Gas exchange and polytropic compression/expansion shared by the parametric cycles
    (abstract: :class:`WiebeCycle` and :class:`MotoredCycle` are the concrete ones)."""

    compression_ratio: jnp.ndarray = eqx.field(converter=number("pressure", "compression_ratio"))
    intake_pa: jnp.ndarray = eqx.field(converter=number("pressure", "intake_pa"))
    exhaust_pa: jnp.ndarray = eqx.field(converter=number("pressure", "exhaust_pa"))
    compression_exponent: jnp.ndarray = eqx.field(converter=number("pressure", "compression_exponent"), default=1.35)
    exhaust_open_deg: jnp.ndarray = eqx.field(converter=number("pressure", "exhaust_open_deg"), default=500.0)
    blowdown_deg: jnp.ndarray = eqx.field(converter=number("pressure", "blowdown_deg"), default=60.0)
    overlap_deg: jnp.ndarray = eqx.field(converter=number("pressure", "overlap_deg"), default=20.0)
    crankcase_pa: jnp.ndarray = eqx.field(converter=number("pressure", "crankcase_pa"), default=STANDARD_CRANKCASE_PA)

    def _expansion(self) -> jnp.ndarray:
        """The polytropic exponent after firing TDC [-]."""
        return self.compression_exponent

    def _check_single_zone(self, exponents: tuple[str, ...] = ("compression_exponent",)) -> None:
        t = self.table
        for key in ("intake_pa", "exhaust_pa", "blowdown_deg", "overlap_deg"):
            check_positive(t, key, getattr(self, key))
        check_positive(t, "crankcase_pa", self.crankcase_pa, allow_zero=True)
        check_finite(t, "exhaust_open_deg", self.exhaust_open_deg)
        eps = concrete(self.compression_ratio)
        if eps is not None and not eps > 1:
            raise EngineError(f"{where(t, 'compression_ratio')} = {fmt(eps)}: must be greater than 1")
        for key in exponents:
            n = concrete(getattr(self, key))
            if n is not None and not (1.0 <= n <= 2.0):
                raise EngineError(f"{where(t, key)} = {fmt(n)}: a polytropic exponent must lie in 1…2")
        evo, bd, ov = (concrete(getattr(self, k)) for k in ("exhaust_open_deg", "blowdown_deg", "overlap_deg"))
        if evo is not None and bd is not None and ov is not None:
            if not (360.0 < evo < 720.0 - ov / 2 - bd):
                raise EngineError(
                    f"{where(t, 'exhaust_open_deg')} = {fmt(evo)}: the exhaust must open after firing TDC (360°) "
                    f"and finish its blowdown ({fmt(bd)}°) before the valve overlap at {720 - ov / 2:g}°"
                )

    def validate_for(self, strokes: int) -> None:
        """A single-zone cycle is four-stroke: ``strokes`` must be 4."""
        if strokes != 4:
            raise EngineError(
                f"[pressure] kind = {self.kind!r} is implemented for four-stroke engines only; "
                'give a two-stroke engine a pressure table (kind = "table")'
            )

    # p(φ) is affine in the heat released: p = p0(φ) + heat·p1(φ)
    def _closed_parts(self, phi, geometry, burn):
        """Closed-cycle pressure (no gas exchange) at φ ∈ [π, 3π] as the affine pair (p0, p1)."""
        eps = self.compression_ratio
        nc = self.compression_exponent
        ne = self._expansion()
        V = lambda x: cylinder_volume_m3(x, geometry, eps)  # noqa: E731
        v = V(phi)
        v_bdc = V(jnp.pi)
        v_tdc = V(2 * jnp.pi)
        p_comp = self.intake_pa * (v_bdc / v) ** nc
        p_tdc0 = self.intake_pa * (v_bdc / v_tdc) ** nc
        p0 = jnp.where(phi <= 2 * jnp.pi, p_comp, p_tdc0 * (v_tdc / v) ** ne)
        if burn is None:
            return p0, jnp.zeros_like(p0)
        # heat part: d(p V^n)/dφ = (n − 1) V^(n−1) dQ/dφ, piecewise n = nc before TDC, ne after
        i_c = burn.integral(jnp.minimum(phi, 2 * jnp.pi), V, nc, lower=None)
        i_c_tdc = burn.integral(jnp.asarray(2 * jnp.pi), V, nc, lower=None)
        i_e = burn.integral(jnp.maximum(phi, 2 * jnp.pi), V, ne, lower=2 * jnp.pi)
        p1_before = (nc - 1) * i_c / v**nc
        p1_tdc = (nc - 1) * i_c_tdc / v_tdc**nc
        p1_after = p1_tdc * (v_tdc / v) ** ne + (ne - 1) * i_e / v**ne
        p1 = jnp.where(phi <= 2 * jnp.pi, p1_before, p1_after)
        return p0, p1

    def _parts(self, phi, geometry, burn):
        """Full-cycle pressure as the affine pair (p0, p1) at cycle angles φ [rad]."""
        phi = jnp.mod(jnp.asarray(phi, dtype=jnp.float64), 4 * jnp.pi)
        closed_phi = jnp.clip(phi, jnp.pi, 3 * jnp.pi)
        p0c, p1c = self._closed_parts(closed_phi, geometry, burn)
        deg = jnp.rad2deg(phi)
        # blowdown: closed cycle → exhaust pressure after the exhaust valve opens
        sb = _smoothstep((deg - self.exhaust_open_deg) / self.blowdown_deg)
        p0 = (1 - sb) * p0c + sb * self.exhaust_pa
        p1 = (1 - sb) * p1c
        # overlap around 720°/0°: exhaust → intake pressure
        ov_start = 720.0 - self.overlap_deg / 2
        wrapped = jnp.where(deg < 360.0, deg + 720.0, deg)
        so = _smoothstep((wrapped - ov_start) / self.overlap_deg)
        p_gx = (1 - so) * self.exhaust_pa + so * self.intake_pa
        in_intake = deg <= 180.0
        in_exhaust = deg >= 540.0
        gas_exchange = jnp.where(in_intake & (deg > self.overlap_deg / 2), self.intake_pa, p_gx)
        use_gx = in_intake | (in_exhaust & (deg >= self.exhaust_open_deg + self.blowdown_deg))
        p0 = jnp.where(use_gx, gas_exchange, p0)
        p1 = jnp.where(use_gx, 0.0, p1)
        return p0, p1

    def _imep_parts(self, geometry, burn, n=2880):
        """IMEP [Pa] of p0 and of p1 by the trapezoid rule on n points of the cycle."""
        phi = jnp.linspace(0.0, 4 * jnp.pi, n + 1)[:-1]
        p0, p1 = self._parts(phi, geometry, burn)
        dv = (
            geometry.piston_area_m2
            * piston_motion(phi, geometry.crank_radius_m, geometry.rod_length_m, geometry.pin_offset_m).ds
        )
        vh = geometry.piston_area_m2 * geometry.stroke_m
        w = 4 * jnp.pi / n
        return jnp.sum(p0 * dv) * w / vh, jnp.sum(p1 * dv) * w / vh


class _WiebeBurn(eqx.Module):
    """Wiebe burnt fraction x(φ) = 1 − exp(−a·((φ − φ_s)/Δφ)^(m+1))."""

    start: jnp.ndarray
    duration: jnp.ndarray
    m: jnp.ndarray
    panels: int = eqx.field(static=True, default=96)
    nodes: int = eqx.field(static=True, default=6)

    def integral(self, phi, V, n, lower):
        """∫ V(ψ)^(n−1) dx(ψ) from max(φ_s, lower) to φ, in s with ψ = φ_s + Δφ·s³.

        dx = a·(m+1)·u^m·e^(−a·u^(m+1)) du with u = (ψ − φ_s)/Δφ = s³ turns into the smooth
        3a·(m+1)·s^(3m+2)·e^(−a·s^(3m+3)) ds (u^m alone is singular at the start of the burn
        for a fractional m). The panels of a composite Gauss–Legendre rule on [s_lo, S]
        (a·S^(3m+3) = 40: e^(−40) of the charge is left) are summed once and each φ adds the
        part of its own panel, so a point costs ``nodes`` evaluations. Within 1e-9 of the heat
        released (``tests/engine/test_pressure.py`` checks it against an adaptive quadrature)."""
        k = 3.0 * (self.m + 1)

        def s_of(x):  # cube root with a finite derivative before the burn (no inf·0)
            u = (x - self.start) / self.duration
            return jnp.where(u > 0, jnp.cbrt(jnp.where(u > 0, u, 1.0)), 0.0)

        def f(s):
            return (
                3
                * _WIEBE_A
                * (self.m + 1)
                * s ** (k - 1)
                * jnp.exp(-_WIEBE_A * s**k)
                * V(self.start + self.duration * s**3) ** (n - 1)
            )

        xg, wg = np.polynomial.legendre.leggauss(self.nodes)
        s_lo = jnp.zeros(()) if lower is None else s_of(jnp.maximum(self.start, lower))
        s_hi = jnp.maximum((40.0 / _WIEBE_A) ** (1.0 / k), s_lo)
        h = (s_hi - s_lo) / self.panels
        left = s_lo + h * jnp.arange(self.panels)
        whole = jnp.sum(f(left[:, None] + h * (xg + 1) / 2) * wg, axis=1) * h / 2
        cum = jnp.concatenate([jnp.zeros(1), jnp.cumsum(whole)])
        s = jnp.clip(s_of(phi), s_lo, s_hi)
        j = jnp.clip(jnp.floor((s - s_lo) / h), 0, self.panels - 1).astype(jnp.int32)
        a = s_lo + h * j
        half = (s - a)[..., None] / 2
        part = jnp.sum(f(a[..., None] + half * (xg + 1)) * wg, axis=-1) * half[..., 0]
        return cum[j] + part


class WiebeCycle(_SingleZone):
    """Single-zone four-stroke cycle with Wiebe heat release, scaled to a target IMEP.

    Intake at ``intake_pa`` (0…180°), polytropic compression from BDC with
    ``compression_exponent``, heat release x(φ) = 1 − exp(−6.908·((φ − start)/duration)^(m+1))
    with m = ``form_factor``, polytropic expansion with ``expansion_exponent``, a smooth
    blowdown to ``exhaust_pa`` from ``exhaust_open_deg`` over ``blowdown_deg``, exhaust,
    and a smooth return to intake pressure over ``overlap_deg`` around 720°/0°. The heat
    released is whatever makes the cycle's IMEP equal ``imep_pa`` (the pressure is affine
    in it, so this is exact).

    **Fields** (angles in cycle degrees, pressures absolute [Pa]): ``compression_ratio`` [-],
    ``intake_pa``, ``exhaust_pa``, ``imep_pa``, ``start_deg``, ``duration_deg``,
    ``form_factor`` [-], ``compression_exponent`` [-], ``expansion_exponent`` [-] (from
    firing TDC on; before TDC the compression exponent applies),
    ``exhaust_open_deg``, ``blowdown_deg``, ``overlap_deg``, ``crankcase_pa``.
    """

    imep_pa: jnp.ndarray = eqx.field(converter=number("pressure", "imep_pa"), kw_only=True)
    expansion_exponent: jnp.ndarray = eqx.field(
        converter=number("pressure", "expansion_exponent"), kw_only=True, default=1.30
    )
    start_deg: jnp.ndarray = eqx.field(converter=number("pressure", "start_deg"), kw_only=True)
    duration_deg: jnp.ndarray = eqx.field(converter=number("pressure", "duration_deg"), kw_only=True)
    form_factor: jnp.ndarray = eqx.field(converter=number("pressure", "form_factor"), kw_only=True, default=2.0)
    kind: ClassVar[str] = "wiebe"
    charge_scalable: ClassVar[bool] = True

    def __check_init__(self) -> None:
        self._check_single_zone(("compression_exponent", "expansion_exponent"))
        t = self.table
        check_positive(t, "imep_pa", self.imep_pa)
        check_positive(t, "duration_deg", self.duration_deg)
        check_positive(t, "form_factor", self.form_factor, allow_zero=True)
        s = concrete(self.start_deg)
        if s is not None and not (180.0 < s < 540.0):
            raise EngineError(f"{where(t, 'start_deg')} = {fmt(s)}: combustion must start between 180° and 540°")
        check_fields_plausible(self)

    def _expansion(self) -> jnp.ndarray:
        return self.expansion_exponent

    def _burn(self) -> _WiebeBurn:
        return _WiebeBurn(jnp.deg2rad(self.start_deg), jnp.deg2rad(self.duration_deg), self.form_factor)

    def heat_scale(self, geometry: object) -> Array:
        """The heat-release scale [Pa·m³ per unit of the Wiebe integral] that gives ``imep_pa``
        in a cylinder of ``geometry`` (a :class:`rotor.Geometry`, lengths in m)."""
        i0, i1 = self._imep_parts(geometry, self._burn())
        return (self.imep_pa - i0) / i1

    def pressure_parts(self, phi: ArrayLike, geometry: object) -> tuple[Float[Array, ...], Float[Array, ...]]:
        """The pressure as the affine pair (p0, p1) [Pa, Pa per unit heat scale] at cycle
        angles ``phi`` [rad] in a cylinder of ``geometry``: p = p0 + :meth:`heat_scale`·p1."""
        return self._parts(phi, geometry, self._burn())

    def __call__(self, phi: ArrayLike, geometry: object, strokes: int = 4) -> Float[Array, ...]:
        """The cycle's pressure [Pa] at cycle angles ``phi`` [rad] in a cylinder of ``geometry``."""
        return _fired_pressure(self, jnp.asarray(phi, dtype=float), geometry)

    def motored(self, strokes: int = 4) -> MotoredCycle:
        """The same engine with the fuel cut: the trace of a misfiring cylinder."""
        return MotoredCycle(**{f: getattr(self, f) for f in _SINGLE_ZONE_FIELDS})

    def scale_charge(self, sigma: ArrayLike) -> WiebeCycle:
        """The cycle with its whole charge scaled by ``sigma`` [-]: ``intake_pa`` and
        ``imep_pa`` × σ (a throttled spark-ignition engine). Differentiable in ``sigma``."""
        return eqx.tree_at(lambda p: (p.intake_pa, p.imep_pa), self, (self.intake_pa * sigma, self.imep_pa * sigma))


class MotoredCycle(_SingleZone):
    """Four-stroke cycle without combustion: the trace of a motored or misfiring cylinder.

    The closed part is a reversible polytrope with ``compression_exponent`` both ways
    (symmetric about TDC); the cycle's negative work comes from the gas exchange.

    **Fields:** as :class:`WiebeCycle` without the heat-release keys and without
    ``expansion_exponent`` (a burnt-gas property).
    """

    kind: ClassVar[str] = "motored"
    charge_scalable: ClassVar[bool] = False

    def __check_init__(self) -> None:
        self._check_single_zone()
        check_fields_plausible(self)

    def __call__(self, phi: ArrayLike, geometry: object, strokes: int = 4) -> Float[Array, ...]:
        """The motored pressure [Pa] at cycle angles ``phi`` [rad] in a cylinder of ``geometry``."""
        return _motored_pressure(self, jnp.asarray(phi, dtype=float), geometry)

    def motored(self, strokes: int = 4) -> MotoredCycle:
        """Itself: a motored cycle has no combustion to cut (``strokes`` must be 4)."""
        return self

    def scale_charge(self, sigma: ArrayLike) -> PressureSource:
        """Raises :class:`rotor.EngineError`: only a Wiebe cycle scales its charge (``sigma`` [-])."""
        raise _not_scalable(self)


_SINGLE_ZONE_FIELDS = (
    "compression_ratio",
    "intake_pa",
    "exhaust_pa",
    "compression_exponent",
    "exhaust_open_deg",
    "blowdown_deg",
    "overlap_deg",
    "crankcase_pa",
)

PRESSURE_KINDS = {cls.kind: cls for cls in (PressureTable, WiebeCycle, MotoredCycle, NoPressure)}


# One compiled program per shape of ``phi`` for a call outside a compiled function (inside
# one, they are traced inline): evaluated op by op, a single-zone cycle would compile each of
# its few hundred operations on its own at every new shape.
@eqx.filter_jit
def _fired_pressure(cycle: WiebeCycle, phi: Array, geometry: object) -> Float[Array, ...]:
    p0, p1 = cycle.pressure_parts(phi, geometry)
    return p0 + cycle.heat_scale(geometry) * p1


@eqx.filter_jit
def _motored_pressure(cycle: MotoredCycle, phi: Array, geometry: object) -> Float[Array, ...]:
    return cycle._parts(phi, geometry, None)[0]
