"""Balancing: the free inertia forces and moments of a crank train, order by order
(Shishkov, "Dinamika dvigatelei", SUSU 2014, §3.2.10; Kolchin & Demidov, "Design of
automotive engines", and Popyk, the balancing of piston engines).

**Masses.** *Reciprocating*: each cylinder's piston group (and the rod's share at the
piston pin; a full rod is split statically by :meth:`rotor.Masses.two_mass_split`,
which keeps the rod's centre of mass and so its inertia force exactly; a slave cylinder
takes ``[masses] reciprocating_kg``), with the force m_rec·ω²·d²s/dα² along its own
cylinder axis, positive towards the head (−m·a of the piston, ``s`` from
:func:`rotor.engine_piston_motion`: exact kinematics with the pin offset and articulated
slaves, or the textbook λ series). *Rotating*: each cylinder's rotating mass (none for
a slave) at the crank pin, m_rot·R·ω² outwards along its throw, plus a slave rod's share
at the knuckle pin, which rides on the master rod (its force −m·a from its exact path).
*Counterweights* (``[[counterweights]]``): m·r·ω² outwards at their angle from their throw.

**Frame.** Forces lie in the plane normal to the crank axis. A direction there is an
angle from the *vertical* (the axis of an unbanked cylinder, towards its head) in the
direction of rotation; *horizontal* is 90° from vertical, where the crank pin moves at
its top. Vectors are complex numbers z = vertical + i·horizontal, so the direction φ is
e^{iφ}; throw k points at φ = θ − ``throw_angles_deg``[k] at the engine crank angle θ.

**Moments** are taken about the point of the crank axis midway between the first and the
last main journal (axial positions from :mod:`rotor.engine.shaft`); where the free force
is not zero the moment depends on that point. A moment is given as the vector
Σ (x − x_ref)·F [N·m]: its direction is the plane of the couple (a vertical moment
pitches the engine, a horizontal one yaws it); the moment vector proper is this turned
by 90° about the crank axis.

**Orders.** The inertia forces repeat every revolution whatever the strokes, so the
order k is k times the crank speed. Each sum is sampled at 256 crank angles over one
revolution and expanded by an FFT (:data:`GRID_POINTS`): exact to rounding for the λ
series and for the exact kinematics, whose harmonics fall like λ^k (aliasing from
order 256 − k is below 1e-60 for any real rod). Order k of a vector is
F_k(θ) = P·e^{ikθ} + Q·e^{−ikθ}: P turns forward with the crank, Q backward. It traces an
ellipse with semi-axes |P| + |Q| (the *free force* of that order, its largest magnitude
over the cycle) and ||P| − |Q||, its largest value in the direction (arg P + arg Q)/2.

**Balance shafts** (:attr:`Balance.balance_shafts`): a shaft at k·ω that turns forward
cancels P with an unbalance U = m·r = |P|/(kω)² [kg·m] pointing at arg(−P) at θ = 0; one
that turns backward cancels Q likewise. A forward or backward moment needs a pair of
such shafts a distance d apart, with opposite unbalances: U·d = |P_M|/(kω)² [kg·m²], the
rear shaft's unbalance pointing at arg(−P_M). The forward first order is what the
crankshaft's own counterweights can take.

Not here: the torque reaction about the crank axis (the overturning moment), which the
gas and inertia torques give (:func:`rotor.total_torque`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..engine.kinematics import rod_motion
from ..engine.mechanism import engine_piston_motion
from ..engine.model import Engine, engine_jit, require_engine
from ..engine.plausible import check_results_finite, check_speed_rpm, require_whole
from ..engine.shaft import journal_positions_m, throw_positions_m, web_positions_m
from ..errors import EngineError
from ..results import Result, json_safe
from ..units import RAD_S_PER_RPM

__all__ = [
    "Balance",
    "balance",
    "GRID_POINTS",
    "MAX_ORDER",
    "RELATIVE_TOLERANCE",
    "SOURCES",
    "SUMS",
]

GRID_POINTS = 256
"""Crank angles per revolution on which the forces are sampled for the FFT."""

MAX_ORDER = 64
"""The highest order :func:`balance` reports (a quarter of :data:`GRID_POINTS`)."""

RELATIVE_TOLERANCE = 1e-9
"""A condition holds when its value is below this share of the engine's scale
(:attr:`Balance.force_scale_N`, :attr:`Balance.moment_scale_Nm`)."""

SOURCES = ("reciprocating", "rotating", "counterweights")
"""The masses whose forces :class:`Balance` reports apart."""

SUMS = ("without_counterweights", "total")
"""The sums: reciprocating + rotating, and all three (what the engine shakes with)."""

_MODELS = ("exact", "series")
_SUMMARY_ORDERS = 12


def _angle_deg(z: np.ndarray, period: float = 360.0) -> np.ndarray:
    return np.mod(np.rad2deg(np.angle(z)), period)


def _ellipse(pq: np.ndarray, tiny: float) -> dict[str, np.ndarray]:
    """The ellipses of forward and backward components ``pq`` (K, 2); ``tiny``: what counts as zero."""
    p, q = pq[:, 0], pq[:, 1]
    a, b = np.abs(p), np.abs(q)
    small = np.minimum(a, b)
    circle = (small <= tiny) | (small <= RELATIVE_TOLERANCE * (a + b))
    direction = np.mod(np.rad2deg(np.angle(p) + np.angle(q)) / 2, 180.0)
    direction = np.where(180.0 - direction < 1e-9, 0.0, direction)  # 179.999… is 0
    return {
        "largest": a + b,
        "smallest": np.abs(a - b),
        "forward": a,
        "backward": b,
        "forward_angle_deg": np.where(a > tiny, _angle_deg(p), np.nan),
        "backward_angle_deg": np.where(b > tiny, _angle_deg(q), np.nan),
        "direction_deg": np.where(circle, np.nan, direction),
        "vertical": np.abs(p + np.conj(q)),
        "horizontal": np.abs(p - np.conj(q)),
    }


_CONDITIONS = (
    ("sum P_j1 = 0", "first-order force of the reciprocating masses", "force", 1, "reciprocating"),
    ("sum P_j2 = 0", "second-order force of the reciprocating masses", "force", 2, "reciprocating"),
    ("sum P_c = 0", "centrifugal force of the rotating masses", "force", 1, "rotating"),
    ("M_1 = 0", "first-order moment of the reciprocating masses", "moment", 1, "reciprocating"),
    ("M_2 = 0", "second-order moment of the reciprocating masses", "moment", 2, "reciprocating"),
    ("M_c = 0", "moment of the rotating masses' centrifugal forces", "moment", 1, "rotating"),
)
_CONDITIONS_CW = (
    ("sum P_1 = 0", "first-order force of all masses and the counterweights", "force", 1, "total"),
    ("M_1,all = 0", "first-order moment of all masses and the counterweights", "moment", 1, "total"),
)


def _conditions(spectra: dict, scales: dict, has_cw: bool) -> tuple[dict[str, Any], ...]:
    out = []
    for symbol, text, quantity, order, source in _CONDITIONS + (_CONDITIONS_CW if has_cw else ()):
        value = float(np.sum(np.abs(spectra[quantity][source][order - 1])))
        out.append(
            {
                "symbol": symbol,
                "description": text,
                "quantity": quantity,
                "order": order,
                "source": source,
                "value": value,
                "unit": "N" if quantity == "force" else "N*m",
                "holds": bool(value <= RELATIVE_TOLERANCE * scales[quantity]),
            }
        )
    return tuple(out)


def _shafts(spectra: dict, scales: dict, omega: float) -> tuple[dict[str, Any], ...]:
    out = []
    for k in (1, 2):
        speed2 = (k * omega) ** 2
        f, m = spectra["force"]["total"][k - 1], spectra["moment"]["total"][k - 1]
        for j, turning in enumerate(("forward", "backward")):
            need_f = abs(f[j]) > RELATIVE_TOLERANCE * scales["force"]
            need_m = abs(m[j]) > RELATIVE_TOLERANCE * scales["moment"]
            out.append(
                {
                    "order": k,
                    "turning": turning,
                    "force_unbalance_kgm": float(abs(f[j])) / speed2 if need_f else 0.0,
                    "force_angle_deg": float(_angle_deg(-f[j])) if need_f else float("nan"),
                    "moment_unbalance_kgm2": float(abs(m[j])) / speed2 if need_m else 0.0,
                    "moment_angle_deg": float(_angle_deg(-m[j])) if need_m else float("nan"),
                }
            )
    return tuple(out)


@dataclass(frozen=True, eq=False, repr=False)
class Balance(Result):
    """The free forces and moments of an engine's inertia by order, with and without its
    counterweights (:func:`balance`; conventions in :mod:`rotor.design.balance`).

    **Fields:** ``engine_name``; ``rpm`` [rev/min]; ``model`` (``"exact"`` or
    ``"series"`` kinematics); ``orders``: 1…K; ``force`` and ``moment``: for each of
    :data:`SOURCES` and :data:`SUMS`, a complex array (K, 2) of the forward and backward
    components P, Q of each order [N] and [N·m] (complex z = vertical + i·horizontal, at
    θ = 0); ``has_counterweights``; ``reference_m``: the moments' point on the crank axis,
    from main journal 1 [m]; ``force_scale_N``: ω²·Σ m·r of every mass [N];
    ``moment_scale_Nm``: that times the distance between the outer main journals [N·m];
    ``grid_points``: samples per revolution of the FFT; ``conditions``: the textbook's six conditions (and two more of all masses with the counterweights, where the engine has some)
    of a balanced engine (Shishkov (2014) §3.2.10: ΣP_j1 = 0, ΣP_j2 = 0, ΣP_c = 0 for the
    reciprocating masses' forces of orders 1 and 2 and the rotating masses' force, M_1 = 0,
    M_2 = 0, M_c = 0 for their moments) for the crank train without counterweights, and,
    with the file's counterweights, two more for the first order of all masses together:
    dicts with ``symbol``, ``description``, ``quantity``, ``order``, ``source``, ``value``
    (largest magnitude over the cycle [N] or [N·m]), ``unit``, ``holds`` (value ≤
    :data:`RELATIVE_TOLERANCE` of the scale); ``balance_shafts``: what shafts at orders 1
    and 2 would need to cancel what remains with the counterweights, a dict per order and
    direction (``turning``: ``"forward"`` with the crank or ``"backward"``) with
    ``force_unbalance_kgm`` (one shaft's m·r [kg·m]), ``force_angle_deg`` (where it points
    at θ = 0), ``moment_unbalance_kgm2`` (m·r times a pair's separation [kg·m²]),
    ``moment_angle_deg`` (the rear shaft's, at θ = 0); NaN angles where none is needed.
    """

    engine_name: str
    rpm: float
    model: str
    orders: np.ndarray
    force: dict[str, np.ndarray]
    moment: dict[str, np.ndarray]
    has_counterweights: bool
    reference_m: float
    force_scale_N: float
    moment_scale_Nm: float
    grid_points: int
    conditions: tuple[dict[str, Any], ...]
    balance_shafts: tuple[dict[str, Any], ...]

    @property
    def omega(self) -> float:
        """Crank speed [rad/s]."""
        return self.rpm * RAD_S_PER_RPM

    def _components(self, quantity: str, source: str) -> np.ndarray:
        table = {"force": self.force, "moment": self.moment}
        if quantity not in table:
            raise ValueError(f"quantity must be 'force' or 'moment', got {quantity!r}")
        if source not in table[quantity]:
            raise ValueError(f"source must be one of {(*SOURCES, *SUMS)}, got {source!r}")
        return table[quantity][source]

    def ellipse(self, quantity: str = "force", source: str = "total") -> dict[str, np.ndarray]:
        """Each order's ellipse of ``quantity`` (``"force"`` [N] or ``"moment"`` [N·m]) of
        ``source`` (one of :data:`SOURCES` or :data:`SUMS`), arrays over the orders:
        ``largest``, ``smallest`` (semi-axes), ``forward``, ``backward`` (|P|, |Q|),
        ``forward_angle_deg``, ``backward_angle_deg`` (their directions at θ = 0),
        ``direction_deg`` (of the largest value, 0…180; NaN for a circle), ``vertical``,
        ``horizontal`` (amplitudes of the two components; for a moment, the couple in the
        vertical and in the horizontal plane)."""
        scale = self.force_scale_N if quantity == "force" else self.moment_scale_Nm
        return _ellipse(self._components(quantity, source), RELATIVE_TOLERANCE * scale)

    def free_force_N(self, source: str = "total") -> np.ndarray:
        """The free force of each order: its largest magnitude over the cycle [N], of
        ``source`` (default ``"total"``: every mass and the file's counterweights)."""
        return self.ellipse("force", source)["largest"]

    def free_moment_Nm(self, source: str = "total") -> np.ndarray:
        """The free moment of each order: its largest magnitude over the cycle [N·m], of
        ``source`` (default ``"total"``)."""
        return self.ellipse("moment", source)["largest"]

    def ellipse_curve(
        self, quantity: str = "force", source: str = "total", order: int = 1, points: int = 181
    ) -> tuple[np.ndarray, np.ndarray]:
        """The ellipse of one ``order`` traced over a revolution at ``points`` crank angles:
        (horizontal, vertical) components [N or N·m] of ``quantity`` of ``source``."""
        i = list(self.orders).index(order)
        p, q = self._components(quantity, source)[i]
        theta = np.linspace(0.0, 2 * np.pi, points)
        z = p * np.exp(1j * order * theta) + q * np.exp(-1j * order * theta)
        return z.imag, z.real

    def _rows(self) -> list[dict[str, Any]]:
        rows = []
        for source in (*SUMS, *SOURCES):
            ef, em = self.ellipse("force", source), self.ellipse("moment", source)
            for i, k in enumerate(self.orders):
                row: dict[str, Any] = {"order": int(k), "source": source}
                for pre, e, unit in (("force", ef, "N"), ("moment", em, "Nm")):
                    for key in ("largest", "smallest", "forward", "backward", "vertical", "horizontal"):
                        row[f"{pre}_{key}_{unit}"] = float(e[key][i])
                    for key in ("forward_angle_deg", "backward_angle_deg", "direction_deg"):
                        row[f"{pre}_{key}"] = float(e[key][i])
                rows.append(row)
        return rows

    def to_pandas(self) -> Any:
        """One row per order and source (``total``, ``without_counterweights``,
        ``reciprocating``, ``rotating``, ``counterweights``): the ellipse of the force [N]
        and the moment [N·m] (:meth:`ellipse`; NaN where an angle is undefined)."""
        import pandas as pd

        return pd.DataFrame(self._rows())

    def to_json_dict(self) -> dict:
        """``orders``: for each order ``free_force_N`` and ``free_moment_Nm`` (largest over
        the cycle, every mass and the file's counterweights included) and the same without
        the counterweights; beside it ``detail`` (every source's ellipses, as
        :meth:`to_pandas`), ``conditions``, ``balance_shafts`` and the conventions."""
        ff, fm = self.free_force_N(), self.free_moment_Nm()
        f0, m0 = self.free_force_N("without_counterweights"), self.free_moment_Nm("without_counterweights")
        orders = [
            {
                "order": int(k),
                "free_force_N": float(ff[i]),
                "free_moment_Nm": float(fm[i]),
                "free_force_without_counterweights_N": float(f0[i]),
                "free_moment_without_counterweights_Nm": float(m0[i]),
            }
            for i, k in enumerate(self.orders)
        ]
        detail: dict[str, list] = {s: [] for s in (*SUMS, *SOURCES)}
        for row in self._rows():
            detail[row.pop("source")].append(row)
        return json_safe(
            {
                "engine": self.engine_name,
                "rpm": self.rpm,
                "kinematics": self.model,
                "orders": orders,
                "has_counterweights": self.has_counterweights,
                "conditions": list(self.conditions),
                "balance_shafts": list(self.balance_shafts),
                "detail": detail,
                "reference_m": self.reference_m,
                "force_scale_N": self.force_scale_N,
                "moment_scale_Nm": self.moment_scale_Nm,
                "relative_tolerance": RELATIVE_TOLERANCE,
                "grid_points": self.grid_points,
                "conventions": (
                    "order k = k x crank speed; free force/moment = largest magnitude of that order over the cycle; "
                    "angles from the unbanked cylinder axis (vertical) in the direction of rotation, at crank angle 0; "
                    "forward turns with the crank; moments sum (x - x_ref)*F about the crank axis's point midway "
                    "between the outer main journals (reference_m from journal 1)"
                ),
            }
        )

    def summary(self) -> str:
        """The free forces and moments by order (total, without counterweights, and each
        source), the conditions and the balance shafts, on one screen."""
        k_shown = min(len(self.orders), _SUMMARY_ORDERS)
        cw = "with its counterweights" if self.has_counterweights else "no counterweights in the file"
        lines = [
            f"{self.engine_name}: free inertia forces and moments at {self.rpm:g} rpm ({self.model} kinematics, {cw})",
            f"  moments about the crank axis midway between the outer main journals ({self.reference_m:.4f} m "
            "from journal 1)",
        ]
        for quantity, unit in (("force", "N"), ("moment", "N*m")):
            head = f"  free {quantity} [{unit}], largest over the cycle:"
            cols = ("total", "no cw", "recip", "rotating", "cw")
            lines.append(head)
            lines.append("  order" + "".join(c.rjust(12) for c in cols))
            values = [self.ellipse(quantity, s)["largest"] for s in ("total", "without_counterweights", *SOURCES)]
            for i in range(k_shown):
                lines.append(f"  {int(self.orders[i]):5d}" + "".join(f"{v[i]:12.1f}" for v in values))
        if k_shown < len(self.orders):
            lines.append(f"  orders {k_shown + 1}...{len(self.orders)}: see to_pandas()")
        extra = len(self.conditions) - len(_CONDITIONS)
        what = f"the {len(self.conditions)} conditions: the textbook's six (Shishkov (2014) 3.2.10)" + (
            f" and {'two' if extra == 2 else extra} of all masses with the counterweights" if extra else ""
        )
        lines.append(f"  {what}, each within 1e-9 of the engine's scale:")
        for c in self.conditions:
            state, value = ("holds", "0") if c["holds"] else ("FAILS", f"{c['value']:.4g}")
            lines.append(f"    {c['symbol']:<12} {state:<6} {value:>10} {c['unit']:<4} {c['description']}")
        lines.append("  balance shafts for what remains (unbalance m*r at k x crank speed; pair: m*r x separation):")
        for s in self.balance_shafts:
            f = f"{s['force_unbalance_kgm'] * 1e3:9.3f} kg*mm"
            if s["force_unbalance_kgm"] > 0:
                f += f" at {s['force_angle_deg']:5.1f} deg"
            m = f"{s['moment_unbalance_kgm2'] * 1e6:10.1f} kg*mm^2"
            if s["moment_unbalance_kgm2"] > 0:
                m += f" at {s['moment_angle_deg']:5.1f} deg"
            lines.append(f"    order {s['order']} {s['turning']:<8}  force {f};  couple {m}")
        return "\n".join(lines) + "\n"

    def plot(self, ax: Any = None, which: str = "orders") -> Any:
        """Plot ``which``: ``"orders"`` (bars of the free force and moment by order, with and
        without the counterweights) or ``"ellipses"`` (the force and moment ellipses of
        orders 1 and 2 with the counterweights); what is below :data:`RELATIVE_TOLERANCE`
        of the engine's scale is drawn as zero. ``ax``: two Axes or None (a new figure).
        **Returns:** the two Axes."""
        from ..plotting.balance import plot_balance_ellipses, plot_balance_orders

        title = f"{self.engine_name} at {self.rpm:g} rpm"
        if which == "orders":

            def free(source: str) -> dict[str, np.ndarray]:  # rounding noise drawn as zero
                out = {}
                for q, scale in (("force", self.force_scale_N), ("moment", self.moment_scale_Nm)):
                    v = self.ellipse(q, source)["largest"]
                    out[q] = np.where(v > RELATIVE_TOLERANCE * scale, v, 0.0)
                return out

            without = free("without_counterweights") if self.has_counterweights else None
            return plot_balance_orders(self.orders, free("total"), without, title, ax=ax)
        if which == "ellipses":
            curves: dict[str, dict[str, tuple[np.ndarray, np.ndarray]]] = {"force": {}, "moment": {}}
            for quantity in curves:
                scale = self.force_scale_N if quantity == "force" else self.moment_scale_Nm
                largest = self.ellipse(quantity)["largest"]
                for k in (1, 2):
                    if k <= len(self.orders) and largest[k - 1] > RELATIVE_TOLERANCE * scale:  # not rounding
                        curves[quantity][f"order {k}"] = self.ellipse_curve(quantity, "total", k)
            return plot_balance_ellipses(curves, title, ax=ax)
        raise ValueError(f"which must be 'orders' or 'ellipses', got {which!r}")


@engine_jit
def _motion(engine: Engine, theta: np.ndarray, model: str) -> tuple[Any, Any, Any]:
    """d²s/dα² of every piston, and every cylinder's mechanical angle α and rod angle β as
    if it were an ordinary mechanism (a master's is), shape (angles, cylinders); compiled
    once per engine layout (eager JAX would compile each operation instead, several times slower)."""
    g = engine.geometry
    alpha = engine.mechanical_angles(theta)
    beta = rod_motion(alpha, g.crank_radius_m, g.rod_length_m, g.pin_offset_m).beta
    return engine_piston_motion(engine, theta, model).d2s, alpha, beta


def _fft_orders(z: np.ndarray, orders: int) -> np.ndarray:
    """(orders, 2) complex: the forward and backward components of orders 1…K of the
    complex samples ``z`` over one revolution."""
    n = z.shape[0]
    spec = np.fft.fft(z) / n
    k = np.arange(1, orders + 1)
    return np.stack([spec[k], spec[n - k]], axis=-1)


def balance(engine: Engine, rpm: float | None = None, *, orders: int = 6, model: str = "exact") -> Balance:
    """The free inertia forces and moments of ``engine`` by order, with and without the
    counterweights of its file (Shishkov (2014) §3.2.10; conventions in
    :mod:`rotor.design.balance`).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine` (any layout: inline, V, flat, radial, articulated).
    - ``rpm``: crank speed [rev/min]; default the engine's ``[operating] rpm``. Every
      force grows as rpm².
    - ``orders``: the highest order reported, 1…64.
    - ``model``: ``"exact"`` piston kinematics (default) or the textbook λ ``"series"``
      (orders 1 and 2 only; slave pistons are always exact).

    **Returns:** a :class:`Balance`.

    **Raises:** :class:`rotor.EngineError` for a speed, order or model out of range.
    """
    require_engine(engine, "balance(engine)").check()
    rpm = float(engine.operating.rpm) if rpm is None else check_speed_rpm(rpm, "balance(rpm)")
    orders = require_whole(orders, "balance(orders)")
    if orders > MAX_ORDER:
        raise EngineError(f"balance(orders) = {orders}: at most {MAX_ORDER} (higher orders are below rounding)")
    if model not in _MODELS:
        raise EngineError(f"balance(model) = {model!r}: 'exact' or 'series' (the textbook lambda series)")
    k_max = max(orders, 2)  # the conditions and the shafts need orders 1 and 2
    omega = rpm * RAD_S_PER_RPM
    w2 = omega**2
    n = GRID_POINTS
    theta = 2 * np.pi * np.arange(n) / n

    g, masses, lay = engine.geometry, engine.masses, engine.layout
    R = float(g.crank_radius_m)
    slaves = engine.slave_index()
    m_rec_master = float(masses.two_mass_split(g.rod_length_m)[0])
    m_rot_master = float(masses.rotating_at_pin_kg(g.rod_length_m))
    cyl = range(engine.cylinders)
    m_rec = np.array([float(masses.reciprocating_kg) if i in slaves else m_rec_master for i in cyl])
    m_rot = np.array([0.0 if i in slaves else m_rot_master for i in cyl])
    banks = np.deg2rad(np.asarray(lay.banks_deg, dtype=np.float64))
    throws_rad = np.deg2rad(np.asarray(lay.throw_angles_deg, dtype=np.float64))
    throw_of = np.asarray(engine.throw_index)
    throw_rad = np.array([throws_rad[np.flatnonzero(throw_of == t)[0]] for t in range(engine.throw_count)])
    x_ref = float(journal_positions_m(engine)[-1]) / 2
    x_cyl = np.asarray(throw_positions_m(engine))[throw_of] - x_ref

    # reciprocating: along each cylinder axis, positive towards the head
    d2s, alphas, betas = (np.asarray(x) for x in _motion(engine, theta, model))
    f_rec = m_rec * w2 * d2s * np.exp(1j * banks)
    # rotating: outwards along the throw
    f_rot = m_rot * R * w2 * np.exp(1j * (theta[:, None] - throws_rad))
    spectra = {
        "reciprocating": (_fft_orders(f_rec.sum(-1), k_max), _fft_orders(f_rec @ x_cyl, k_max)),
        "rotating": (_fft_orders(f_rot.sum(-1), k_max), _fft_orders(f_rot @ x_cyl, k_max)),
    }
    scale = float(np.sum((m_rec + m_rot) * R))
    # a slave rod's share at the knuckle pin: its path in the master's frame, −m·a by FFT
    art = engine.articulated
    if art is not None and slaves:
        k = np.arange(1, k_max + 1)[:, None]
        r1, gamma, m_k = (
            float(art.knuckle_radius_m),
            np.deg2rad(float(art.knuckle_angle_deg)),
            float(art.rod_knuckle_kg),
        )
        for s, m in slaves.items():
            alpha, beta = alphas[:, m], betas[:, m]
            path = np.exp(1j * banks[m]) * (R * np.exp(1j * alpha) + r1 * np.exp(1j * (gamma - beta)))
            f_k = m_k * w2 * k**2 * _fft_orders(path, k_max)  # −m·a: a_k = −(kω)²·path_k
            f, mo = spectra["rotating"]
            spectra["rotating"] = (f + f_k, mo + f_k * x_cyl[s])
            scale += m_k * (R + r1)
    cw = engine.counterweights
    if cw is not None:
        webs = np.asarray(cw.webs) - 1
        mr = np.asarray(cw.mass_kg) * np.asarray(cw.radius_m)
        x_web = np.asarray(web_positions_m(engine))[webs] - x_ref
        direction = theta[:, None] - throw_rad[webs // 2] + np.deg2rad(np.asarray(cw.angle_deg))
        f_cw = mr * w2 * np.exp(1j * direction)
        spectra["counterweights"] = (_fft_orders(f_cw.sum(-1), k_max), _fft_orders(f_cw @ x_web, k_max))
        scale += float(np.sum(mr))
    else:
        zero = np.zeros((k_max, 2), dtype=complex)
        spectra["counterweights"] = (zero, zero)
    force = {s: spectra[s][0] for s in SOURCES}
    moment = {s: spectra[s][1] for s in SOURCES}
    for d in (force, moment):
        d["without_counterweights"] = d["reciprocating"] + d["rotating"]
        d["total"] = d["without_counterweights"] + d["counterweights"]
    length = float(journal_positions_m(engine)[-1])
    scales = {"force": scale * w2, "moment": scale * w2 * length}
    both = {"force": force, "moment": moment}
    check_results_finite(
        f"the balance of engine {engine.name!r} at {rpm:g} rpm",
        {f"{q}_{s}": np.abs(d[s]) for q, d in both.items() for s in d},
    )
    return Balance(
        engine_name=engine.name,
        rpm=rpm,
        model=model,
        orders=np.arange(1, orders + 1),
        force={s: v[:orders] for s, v in force.items()},
        moment={s: v[:orders] for s, v in moment.items()},
        has_counterweights=cw is not None,
        reference_m=x_ref,
        force_scale_N=scales["force"],
        moment_scale_Nm=scales["moment"],
        grid_points=n,
        conditions=_conditions(both, scales, cw is not None),
        balance_shafts=_shafts(both, scales, omega),
    )
