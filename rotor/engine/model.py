"""The engine description: equinox Modules that mirror the engine file table by table.

``engine.geometry.bore_m`` is ``[geometry] bore_m`` of the file, and so on. Every
numeric field is a float64 JAX array, so ``jax.grad`` works over any of them (use
``eqx.tree_at`` to replace one). Each module checks its own values when it is built
and :class:`Engine` checks how the tables fit together; a problem raises
:class:`rotor.EngineError` (a ``ValueError``) that names the key, and a value of the
wrong Python type (a string where a number belongs) a :class:`TypeError`.

Finite is not enough: every input must lie in the plausible range of a piston engine,
from a model engine to the largest ship diesels (:data:`rotor.engine.plausible.PLAUSIBLE`:
a bore of 1 mm … 2 m, a stroke of 1 mm … 5 m, masses up to 100 t, a crankshaft inertia
of 1e-12 … 1e8 kg·m², speeds of 0.1 … 100 000 rpm, pressures up to 1 GPa, a compression
ratio of 1.5 … 100, …), and what is computed from the inputs (the piston area, the
displacement, the clearance volume, the inertia of the rods and pistons, the inertia and
gas forces at the operating speed) must come out finite, or the error names the input
that made it overflow. ``eqx.tree_at`` skips these checks; :meth:`Engine.check` runs
them again, and every solver calls it on an engine with concrete fields. A field traced by
``jax.jit``, ``vmap`` or ``grad`` is checked by :func:`guard_engine`, which the public
functions call on the engine they are given: finite and within its plausible range, the
rod longer than the crank radius, or the program raises when it runs, naming the key.

Angles: ``throw_angles_deg[i]`` is the crank angle at which throw i points along an
unbanked cylinder axis (its TDC); ``bank_angles_deg[i]`` is the angle of cylinder i's
axis in the direction of rotation. Cylinder i therefore sees the mechanical crank angle
θ − (throw_i + bank_i). The engine's crank angle θ equals cylinder 1's cycle angle
when throw 1 and bank 1 are zero: θ = 0 is cylinder 1's TDC at the start of intake.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..checks import (
    TRACED,
    as_f64,
    called_from_outside,
    check_finite,
    check_positive,
    concrete,
    fmt,
    guard,
    has_tracer,
    tracing,
    where,
)
from ..cycles import array_module
from ..errors import EngineError
from ..programs import kept_program
from ..units import RAD_S_PER_RPM
from .friction import Friction
from .plausible import check_fields_plausible, checked_angle, finite_derived, guard_fields, number, what_it_is
from .pressure import NoPressure, PressureSource

__all__ = [
    "Geometry",
    "Masses",
    "Crankshaft",
    "Layout",
    "Operating",
    "Articulated",
    "Counterweights",
    "Torsion",
    "Engine",
    "require_engine",
    "guard_engine",
    "engine_jit",
    "unnamed",
]


def _tuple_of_ints(x):
    return tuple(int(v) for v in x)


def _alike(*xs: Any) -> tuple[Any, ...]:
    """``xs`` as NumPy arrays where none is a tracer (the derived figures of a concrete engine
    compile no program of their own), else as they are for JAX."""
    xp = array_module(*xs)
    return xs if xp is not np else tuple(np.asarray(x, dtype=np.float64) for x in xs)


class Geometry(eqx.Module):
    """``[geometry]``: cylinder and crank dimensions.

    **Fields:** ``bore_m`` [m]; ``stroke_m`` [m] (= 2R); ``rod_length_m``: connecting
    rod, centre to centre [m]; ``pin_offset_m``: desaxial offset k of the piston pin [m].
    """

    bore_m: jnp.ndarray = eqx.field(converter=number("geometry", "bore_m"))
    stroke_m: jnp.ndarray = eqx.field(converter=number("geometry", "stroke_m"))
    rod_length_m: jnp.ndarray = eqx.field(converter=number("geometry", "rod_length_m"))
    pin_offset_m: jnp.ndarray = eqx.field(converter=number("geometry", "pin_offset_m"), default=0.0)
    table: ClassVar[str] = "geometry"

    def __check_init__(self):
        for key in ("bore_m", "stroke_m", "rod_length_m"):
            check_positive(self.table, key, getattr(self, key))
        check_finite(self.table, "pin_offset_m", self.pin_offset_m)
        check_fields_plausible(self)
        S, L, k = concrete(self.stroke_m), concrete(self.rod_length_m), concrete(self.pin_offset_m)
        R = None if S is None else S / 2  # in NumPy: a check compiles nothing
        if R is not None and L is not None and k is not None and not L > R + abs(k):
            extra = f" plus the pin offset |k| = {abs(k):g} m" if k != 0 else ""
            raise EngineError(
                f"{where(self.table, 'rod_length_m')} = {fmt(L)}: the rod must be longer than the crank "
                f"radius R = stroke_m/2 = {fmt(R)} m{extra}, or the crank cannot turn"
            )

    @property
    def crank_radius_m(self):
        """R = stroke/2 [m]."""
        (stroke,) = _alike(self.stroke_m)
        return stroke / 2

    @property
    def rod_ratio(self):
        """λ = R/L [-]."""
        radius, length = _alike(self.crank_radius_m, self.rod_length_m)
        return radius / length

    @property
    def piston_area_m2(self):
        """π·bore²/4 [m²]."""
        (bore,) = _alike(self.bore_m)
        return np.pi * bore**2 / 4

    @property
    def displacement_m3(self):
        """Swept volume of one cylinder [m³]."""
        (stroke,) = _alike(self.stroke_m)
        return self.piston_area_m2 * stroke


class Masses(eqx.Module):
    """``[masses]``, per cylinder.

    Two-mass model (default): ``reciprocating_kg`` is the piston group plus the rod's
    share that moves with the piston; ``rotating_kg`` the rod's share at the crank pin
    plus the throw's unbalanced mass, at radius R.

    Full rod (give all three of ``rod_kg``, ``rod_cg_from_big_end_m`` [m],
    ``rod_inertia_kgm2`` [kg·m², about the rod's centre of mass]): the rod is modelled
    as a rigid body, and then ``reciprocating_kg`` is the piston group alone and
    ``rotating_kg`` the throw's unbalanced mass alone.

    ``rod_big_end_kg`` (optional, two-mass model only): m₂, the rod's share at the crank
    pin [kg], whose centrifugal force S₂ = −m₂·R·ω² loads the crank pin (Shishkov (2014)
    §3.2.4); the rest of ``rotating_kg`` is the throw's own unbalanced mass, which loads the
    main journals only. Without it, the whole of ``rotating_kg`` is taken as the rod's
    share; with a full rod m₂ follows from the rod (:meth:`big_end_kg`). A rotating mass at
    R adds only a constant to I(θ), so a file may count the big ends' inertia in
    ``[crankshaft] inertia_kgm2`` instead: ``rod_big_end_kg`` above ``rotating_kg`` says
    so, and the bearing loads and the balance then take m₂ as the rotating mass
    (:meth:`rotating_at_pin_kg`).
    """

    reciprocating_kg: jnp.ndarray = eqx.field(converter=number("masses", "reciprocating_kg"))
    rotating_kg: jnp.ndarray = eqx.field(converter=number("masses", "rotating_kg"), default=0.0)
    rod_kg: jnp.ndarray | None = eqx.field(converter=number("masses", "rod_kg", optional=True), default=None)
    rod_cg_from_big_end_m: jnp.ndarray | None = eqx.field(
        converter=number("masses", "rod_cg_from_big_end_m", optional=True), default=None
    )
    rod_inertia_kgm2: jnp.ndarray | None = eqx.field(
        converter=number("masses", "rod_inertia_kgm2", optional=True), default=None
    )
    rod_big_end_kg: jnp.ndarray | None = eqx.field(
        converter=number("masses", "rod_big_end_kg", optional=True), default=None
    )
    table: ClassVar[str] = "masses"

    def __check_init__(self):
        t = self.table
        check_positive(t, "reciprocating_kg", self.reciprocating_kg)
        check_positive(t, "rotating_kg", self.rotating_kg, allow_zero=True)
        rod = {k: getattr(self, k) for k in ("rod_kg", "rod_cg_from_big_end_m", "rod_inertia_kgm2")}
        given = [k for k, v in rod.items() if v is not None]
        if given and len(given) != 3:
            missing = [k for k in rod if rod[k] is None]
            raise EngineError(
                f"{where(t, missing[0])} is missing: a full rod needs rod_kg, rod_cg_from_big_end_m and "
                f"rod_inertia_kgm2 together (or none of them for the two-mass model)"
            )
        if given:
            check_positive(t, "rod_kg", self.rod_kg)
            check_positive(t, "rod_cg_from_big_end_m", self.rod_cg_from_big_end_m, allow_zero=True)
            check_positive(t, "rod_inertia_kgm2", self.rod_inertia_kgm2, allow_zero=True)
        if self.rod_big_end_kg is not None:
            if given:
                raise EngineError(
                    f"{where(t, 'rod_big_end_kg')}: with a full rod (rod_kg, rod_cg_from_big_end_m) the rod's share "
                    "at the crank pin follows from the rod; remove rod_big_end_kg"
                )
            check_positive(t, "rod_big_end_kg", self.rod_big_end_kg, allow_zero=True)
        check_fields_plausible(self)

    @property
    def full_rod(self) -> bool:
        return self.rod_kg is not None

    def two_mass_split(self, rod_length_m: ArrayLike) -> tuple[Array, Array]:
        """(reciprocating, rotating) masses [kg] of the equivalent two-mass model, for a rod
        ``rod_length_m`` [m] long.

        For a full rod, its mass is split statically between the pin (m·a/L) and the crank
        pin (m·(L − a)/L), a being the distance of its centre of mass from the big end.
        """
        if self.rod_kg is None or self.rod_cg_from_big_end_m is None:  # the two-mass model
            return self.reciprocating_kg, self.rotating_kg
        rec, rot, rod, cg, length = _alike(
            self.reciprocating_kg, self.rotating_kg, self.rod_kg, self.rod_cg_from_big_end_m, rod_length_m
        )
        a_over_l = cg / length
        return rec + rod * a_over_l, rot + rod * (1 - a_over_l)

    def big_end_kg(self, rod_length_m: ArrayLike) -> Array:
        """m₂, the rod's mass at the crank pin [kg] (its centrifugal force loads the crank pin),
        for a rod ``rod_length_m`` [m] long: ``rod_big_end_kg`` if given, the full rod's
        static share at the big end, or else the whole ``rotating_kg``."""
        if self.rod_kg is not None and self.rod_cg_from_big_end_m is not None:
            rod, cg, length = _alike(self.rod_kg, self.rod_cg_from_big_end_m, rod_length_m)
            return rod * (1 - cg / length)
        return self.rotating_kg if self.rod_big_end_kg is None else self.rod_big_end_kg

    def rotating_at_pin_kg(self, rod_length_m: ArrayLike) -> Array:
        """The whole rotating mass at the crank radius [kg] whose centrifugal force turns with
        the throw (for the bearing loads and the balance): the two-mass split's rotating
        mass, or m₂ where that is larger (the big ends' inertia counted in
        ``[crankshaft] inertia_kgm2``, see the class docstring); ``rod_length_m`` [m]."""
        rotating, big_end = _alike(self.two_mass_split(rod_length_m)[1], self.big_end_kg(rod_length_m))
        return array_module(rotating).maximum(rotating, big_end)


class Crankshaft(eqx.Module):
    """``[crankshaft]``: the crankshaft as a rigid body and as a beam on its main journals.

    **Fields:** ``inertia_kgm2``: the constant moment of inertia of the crankshaft,
    flywheel and everything rigidly attached [kg·m²] (not the rods and pistons).
    Optional, for the bearing loads and the balancing (:mod:`rotor.engine.shaft`):
    ``throws``: the crank throw of each cylinder, numbered 1… from the front (default:
    each cylinder its own throw, a slave rod its master's; a V engine with two rods on a
    pin names them, e.g. ``[1, 2, 3, 4, 1, 2, 3, 4]``); ``main_journals``: the number of
    main journals (default throws + 1, a journal between every two throws; fewer must
    share the throws evenly between the spans); ``journal_spacing_m``: the distance
    between neighbouring main journals [m] (default 1.25 bores per throw in a span, the
    cylinder spacing of Kolchin & Demidov's ratios).
    """

    inertia_kgm2: jnp.ndarray = eqx.field(converter=number("crankshaft", "inertia_kgm2"))
    throws: tuple | None = eqx.field(
        static=True, default=None, converter=lambda x: x if x is None else _tuple_of_ints(x)
    )
    main_journals: int | None = eqx.field(static=True, default=None)
    journal_spacing_m: jnp.ndarray | None = eqx.field(
        converter=number("crankshaft", "journal_spacing_m", optional=True), default=None
    )
    table: ClassVar[str] = "crankshaft"

    def __check_init__(self):
        if jnp.ndim(self.inertia_kgm2) != 0:  # a traced value under vmap is one item's number
            raise EngineError(
                f"{where(self.table, 'inertia_kgm2')}: one number [kg·m²] (crankshaft, flywheel and what is rigidly "
                f"attached), got an array of shape {jnp.shape(self.inertia_kgm2)}; for many inertias use "
                "rotor.steady_sweep(inertia_kgm2=...) or jax.vmap"
            )
        check_positive(self.table, "inertia_kgm2", self.inertia_kgm2)
        if self.main_journals is not None and (
            isinstance(self.main_journals, bool) or not isinstance(self.main_journals, (int, np.integer))
        ):
            raise TypeError(f"{where(self.table, 'main_journals')} = {self.main_journals!r}: expected a whole number")
        if self.journal_spacing_m is not None:
            check_positive(self.table, "journal_spacing_m", self.journal_spacing_m)
        check_fields_plausible(self)


class Counterweights(eqx.Module):
    """``[[counterweights]]``: the crank webs' counterweights, one entry each.

    **Fields** (one value per counterweight): ``webs``: the web that carries it, 1…2·throws
    (webs 2k − 1 and 2k flank throw k, the front one first); ``mass_kg`` [kg];
    ``radius_m``: its centre of mass from the crank axis [m]; ``angle_deg``: its direction
    from its throw's, in the direction of rotation [deg] (180, the default, is opposite the
    throw). Each is a rotating mass whose centrifugal force m·r·ω² turns with the shaft.
    """

    webs: tuple = eqx.field(static=True, converter=_tuple_of_ints)
    mass_kg: jnp.ndarray = eqx.field(converter=number("counterweights", "mass_kg"))
    radius_m: jnp.ndarray = eqx.field(converter=number("counterweights", "radius_m"))
    angle_deg: jnp.ndarray = eqx.field(converter=number("counterweights", "angle_deg"))
    table: ClassVar[str] = "counterweights"

    def __check_init__(self):
        n = len(self.webs)
        for key in ("mass_kg", "radius_m", "angle_deg"):
            v = getattr(self, key)
            if jnp.ndim(v) != 1 or v.shape[0] != n:
                raise EngineError(
                    f"[[counterweights]] {key}: needs one value per counterweight ({n}), got {np.size(v)}"
                )
        check_positive(self.table, "mass_kg", self.mass_kg, allow_zero=True)
        check_positive(self.table, "radius_m", self.radius_m, allow_zero=True)
        check_finite(self.table, "angle_deg", self.angle_deg)
        check_fields_plausible(self)


class Layout(eqx.Module):
    """``[layout]``: crank throws, cylinder banks and the firing order.

    **Fields:** ``throw_angles_deg`` [deg] (one per cylinder); ``bank_angles_deg`` [deg]
    (one per cylinder; zeros for an inline engine); ``firing_order``: cylinder numbers
    1…n in firing sequence (static).
    """

    throw_angles_deg: jnp.ndarray = eqx.field(converter=number("layout", "throw_angles_deg"))
    firing_order: tuple = eqx.field(static=True, converter=_tuple_of_ints)
    bank_angles_deg: jnp.ndarray | None = eqx.field(
        converter=number("layout", "bank_angles_deg", optional=True), default=None
    )
    table: ClassVar[str] = "layout"

    def __check_init__(self):
        check_finite(self.table, "throw_angles_deg", self.throw_angles_deg)
        if self.bank_angles_deg is not None:
            check_finite(self.table, "bank_angles_deg", self.bank_angles_deg)
        check_fields_plausible(self)

    @property
    def banks_deg(self):
        """Bank angles [deg], zeros when the file gives none."""
        if self.bank_angles_deg is None:
            return jnp.zeros_like(self.throw_angles_deg)
        return self.bank_angles_deg


class Operating(eqx.Module):
    """``[operating]``: ``rpm``, the operating speed [rev/min] (the one place rpm is stored)."""

    rpm: jnp.ndarray = eqx.field(converter=number("operating", "rpm"))
    table: ClassVar[str] = "operating"

    def __check_init__(self):
        check_positive(self.table, "rpm", self.rpm)
        check_fields_plausible(self)

    @property
    def omega(self):
        """Operating speed [rad/s]."""
        return self.rpm * RAD_S_PER_RPM


class Articulated(eqx.Module):
    """``[articulated]``: slave rods hinged on a master rod (V and radial engines;
    Lukanin 2009, Yamanin & Zharov, Lashko).

    **Fields:** ``slaves``: cylinder numbers driven by a slave rod; ``masters``: the
    master cylinder of each (same crank throw); ``knuckle_radius_m``: big-end centre to
    knuckle pin, r₁ [m]; ``knuckle_angle_deg``: the knuckle pin's angle from the master
    rod axis, towards the slave (usually the bank angle between them) [deg];
    ``rod_length_m``: slave rod, knuckle pin to piston pin [m]; ``rod_knuckle_kg``: the
    slave rod's share carried at the knuckle pin [kg] (its share at the piston pin is
    part of ``[masses] reciprocating_kg``).
    """

    slaves: tuple = eqx.field(static=True, converter=_tuple_of_ints)
    masters: tuple = eqx.field(static=True, converter=_tuple_of_ints)
    knuckle_radius_m: jnp.ndarray = eqx.field(converter=number("articulated", "knuckle_radius_m"))
    knuckle_angle_deg: jnp.ndarray = eqx.field(converter=number("articulated", "knuckle_angle_deg"))
    rod_length_m: jnp.ndarray = eqx.field(converter=number("articulated", "rod_length_m"))
    rod_knuckle_kg: jnp.ndarray = eqx.field(converter=number("articulated", "rod_knuckle_kg"), default=0.0)
    table: ClassVar[str] = "articulated"

    def __check_init__(self):
        t = self.table
        if len(self.slaves) != len(self.masters):
            raise EngineError(
                f"{where(t, 'masters')}: one master per slave is needed "
                f"({len(self.slaves)} slaves, {len(self.masters)} masters)"
            )
        check_positive(t, "knuckle_radius_m", self.knuckle_radius_m, allow_zero=True)
        check_finite(t, "knuckle_angle_deg", self.knuckle_angle_deg)
        check_positive(t, "rod_length_m", self.rod_length_m)
        check_positive(t, "rod_knuckle_kg", self.rod_knuckle_kg, allow_zero=True)
        check_fields_plausible(self)


def _tuple_of_strs(x):
    if isinstance(x, (str, bytes)):
        raise TypeError(f"[torsion] names = {x!r:.40}: expected a list of strings, one per mass")
    out = tuple(x)
    for v in out:
        if not isinstance(v, str):
            raise TypeError(f"[torsion] names: expected strings, got {type(v).__name__} {v!r:.40}")
    return out


class Torsion(eqx.Module):
    """``[torsion]``: the crankshaft as a chain of masses on torsional springs (optional;
    the rigid one-mass model is the default everywhere, :mod:`rotor.torsion` uses this).

    **Fields:**

    - ``inertias_kgm2``: the *constant* inertia of each mass, from the front [kg·m²]: the
      damper or pulley, gear train, the crank throws without their rods and pistons, the
      flywheel, …; they sum to ``[crankshaft] inertia_kgm2`` (the engine file checks it),
      and rotor adds each cylinder's mechanism, I_cyl(θ), to its throw's mass itself.
    - ``stiffnesses_Nm_per_rad``: each shaft section's stiffness, between masses i and
      i + 1 [N·m/rad] (one fewer than the masses).
    - ``throw_masses``: the mass number (1-based, from the front) of each crank throw, in
      throw order (static).
    - ``names``: a name per mass (static; optional).
    - ``load_mass``: the mass number (1-based) where the load acts (static; default the last).
    - ``absolute_damping_Nms_per_rad``: viscous damping of each mass to the ground
      [N·m·s/rad] (optional, one per mass).
    - ``relative_damping_Nms_per_rad``: viscous damping in each shaft section [N·m·s/rad]
      (optional, one per section).
    - ``modal_damping_ratio``: one ratio ζ [-] for every elastic mode, or one per elastic
      mode (optional).
    """

    inertias_kgm2: jnp.ndarray = eqx.field(converter=number("torsion", "inertias_kgm2"))
    stiffnesses_Nm_per_rad: jnp.ndarray = eqx.field(converter=number("torsion", "stiffnesses_Nm_per_rad"))
    throw_masses: tuple = eqx.field(static=True, converter=_tuple_of_ints)
    names: tuple = eqx.field(static=True, default=(), converter=_tuple_of_strs)
    load_mass: int | None = eqx.field(static=True, default=None)
    absolute_damping_Nms_per_rad: jnp.ndarray | None = eqx.field(
        converter=number("torsion", "absolute_damping_Nms_per_rad", optional=True), default=None
    )
    relative_damping_Nms_per_rad: jnp.ndarray | None = eqx.field(
        converter=number("torsion", "relative_damping_Nms_per_rad", optional=True), default=None
    )
    modal_damping_ratio: jnp.ndarray | None = eqx.field(
        converter=number("torsion", "modal_damping_ratio", optional=True), default=None
    )
    table: ClassVar[str] = "torsion"

    def __check_init__(self):
        t = self.table
        J, k = self.inertias_kgm2, self.stiffnesses_Nm_per_rad
        if jnp.ndim(J) != 1 or J.shape[0] < 2:
            raise EngineError(f"{where(t, 'inertias_kgm2')}: needs a list of two or more inertias, one per mass")
        n = J.shape[0]
        if jnp.ndim(k) != 1 or k.shape[0] != n - 1:
            raise EngineError(
                f"{where(t, 'stiffnesses_Nm_per_rad')}: needs one stiffness per shaft section, {n - 1} for {n} "
                f"masses, got {np.size(k)}"
            )
        check_positive(t, "inertias_kgm2", J)
        check_positive(t, "stiffnesses_Nm_per_rad", k)
        for key, size, what in (
            ("absolute_damping_Nms_per_rad", n, "mass"),
            ("relative_damping_Nms_per_rad", n - 1, "shaft section"),
        ):
            v = getattr(self, key)
            if v is None:
                continue
            if jnp.ndim(v) != 1 or v.shape[0] != size:
                raise EngineError(f"{where(t, key)}: needs one value per {what} ({size}), got {np.size(v)}")
            check_positive(t, key, v, allow_zero=True)
        z = self.modal_damping_ratio
        if z is not None:
            if not (jnp.ndim(z) == 0 or (jnp.ndim(z) == 1 and z.shape[0] == n - 1)):
                raise EngineError(
                    f"{where(t, 'modal_damping_ratio')}: needs one ratio for every mode or one per elastic mode "
                    f"({n - 1}), got {np.size(z)}"
                )
            check_positive(t, "modal_damping_ratio", z, allow_zero=True)
        if self.names and len(self.names) != n:
            raise EngineError(f"{where(t, 'names')}: needs one name per mass ({n}), got {len(self.names)}")
        if not self.throw_masses:
            raise EngineError(f"{where(t, 'throw_masses')}: give the mass number (1…{n}) of each crank throw")
        for m in self.throw_masses:
            if not 1 <= m <= n:
                raise EngineError(
                    f"{where(t, 'throw_masses')} = {list(self.throw_masses)}: mass {m} does not exist (1…{n})"
                )
        if len(set(self.throw_masses)) != len(self.throw_masses):
            raise EngineError(
                f"{where(t, 'throw_masses')} = {list(self.throw_masses)}: each crank throw needs its own mass"
            )
        lm = self.load_mass
        if lm is not None:
            if isinstance(lm, bool) or not isinstance(lm, (int, np.integer)):
                raise TypeError(f"{where(t, 'load_mass')} = {lm!r}: expected a whole number (a mass number 1…{n})")
            if not 1 <= lm <= n:
                raise EngineError(f"{where(t, 'load_mass')} = {lm}: mass {lm} does not exist (1…{n})")
        check_fields_plausible(self)

    @property
    def size(self) -> int:
        """The number of masses."""
        return int(self.inertias_kgm2.shape[0])


def _firing_tdc_deg(xp, tdc_deg, order, strokes):
    """Engine angle [deg] of each cylinder's firing TDC, walking the firing order.

    Each next cylinder fires at the first of its TDCs after the previous firing (a
    four-stroke cylinder passes TDC every 360°, only one of them fires). Returns the angles
    (indexed by cylinder) and the angle span of the walk, which must stay below one cycle.
    """
    cycle = 360.0 * strokes / 2
    n = len(order)
    start = order.index(1)
    walk = order[start:] + order[:start]
    first = walk[0] - 1
    tdc1 = tdc_deg[first] + (360.0 if strokes == 4 else 0.0)
    angles = [None] * n
    angles[first] = tdc1
    prev = tdc1
    for c in walk[1:]:
        gap = xp.mod(tdc_deg[c - 1] - prev, 360.0)
        if strokes == 4:
            gap = xp.where(gap < 1e-9, 360.0, gap)
        prev = prev + gap
        angles[c - 1] = prev
    return angles, prev - tdc1, cycle


MAX_CYLINDERS = 64
"""The most cylinders an engine may have (the largest built have 28 or fewer)."""


def _recheck(part: eqx.Module) -> None:
    """Run ``part``'s field converters (the type checks) and every ``__check_init__`` of its
    class hierarchy again, as equinox does when it is built."""
    for f in dataclasses.fields(part):
        convert = f.metadata.get("converter")
        value = getattr(part, f.name)
        if convert is not None and not isinstance(value, jax.core.Tracer):
            convert(value)
    for cls in type(part).__mro__:
        check = cls.__dict__.get("__check_init__")
        if check is not None:
            check(part)


def _peak_pressure_input(pressure: PressureSource) -> float | None:
    """The largest pressure [Pa] among the concrete inputs of a pressure source."""
    values = []
    for f in dataclasses.fields(pressure):
        if f.name.endswith("_pa"):
            v = concrete(getattr(pressure, f.name))
            if v is None:
                return None
            values.append(float(np.max(v)) if v.size else 0.0)
    return max(values) if values else None


def _number_text(x: Any) -> str:
    """A field's value as text: numbers as numbers (a long array's first values and its
    length), a traced value as its shape and type (``f64[4]``), anything else as its repr."""
    if isinstance(x, jax.core.Tracer):
        return f"{np.dtype(x.dtype).name}{list(x.shape)} (traced)"
    if isinstance(x, (jax.Array, np.ndarray, np.generic)):
        a = np.asarray(x)
        if a.ndim == 0:
            return f"{a.item():.6g}" if a.dtype.kind == "f" else repr(a.item())
        flat = [f"{v:.6g}" if a.dtype.kind == "f" else repr(v) for v in a.ravel()[:8].tolist()]
        more = f", … ({a.size} values)" if a.size > 8 else ""
        return "[" + ", ".join(flat) + more + "]"
    return repr(x)


def engine_text(x: Any, indent: str = "") -> str:
    """``x`` (an engine or one of its tables) as readable text with its numbers, one field a line."""
    if not (dataclasses.is_dataclass(x) and isinstance(x, eqx.Module)):
        return _number_text(x)
    inner = indent + "  "
    fields = [f for f in dataclasses.fields(x) if not f.name.startswith("_")]
    lines = [f"{inner}{f.name}={engine_text(getattr(x, f.name), inner)}," for f in fields]
    return f"{type(x).__name__}(\n" + "\n".join(lines) + f"\n{indent})"


class Engine(eqx.Module):
    """An engine: the whole engine file as one pytree.

    **Fields:** ``name``, ``strokes`` (2 or 4), ``cylinders`` (static); ``geometry``,
    ``masses``, ``crankshaft``, ``layout``, ``pressure``, ``operating`` and, optionally,
    ``articulated``, ``friction``, ``counterweights`` and ``torsion`` — one per table of
    the file.
    """

    name: str = eqx.field(static=True)
    strokes: int = eqx.field(static=True)
    cylinders: int = eqx.field(static=True)
    geometry: Geometry
    masses: Masses
    crankshaft: Crankshaft
    layout: Layout
    pressure: PressureSource = eqx.field(default_factory=NoPressure)
    operating: Operating = eqx.field(default_factory=lambda: Operating(rpm=as_f64(1000.0)))
    articulated: Articulated | None = None
    friction: Friction | None = None
    counterweights: Counterweights | None = None
    torsion: Torsion | None = None

    def __repr__(self) -> str:
        return engine_text(self)

    def __check_init__(self):
        self._check_types()
        if self.strokes not in (2, 4):
            raise EngineError(f"strokes = {self.strokes!r}: must be 2 or 4")
        if not (isinstance(self.cylinders, int) and self.cylinders >= 1):
            raise EngineError(f"cylinders = {self.cylinders!r}: must be a whole number, 1 or more")
        if self.cylinders > MAX_CYLINDERS:
            raise EngineError(
                f"cylinders = {self.cylinders}: more than the {MAX_CYLINDERS} of any piston engine built "
                "(the largest radials and ship diesels have 28 or fewer)"
            )
        n = self.cylinders
        lay = self.layout
        for key, arr in (("throw_angles_deg", lay.throw_angles_deg), ("bank_angles_deg", lay.bank_angles_deg)):
            if arr is not None and (jnp.ndim(arr) != 1 or arr.shape[0] != n):
                raise EngineError(f"{where('layout', key)}: needs one angle per cylinder ({n}), got {np.size(arr)}")
        fo = lay.firing_order
        if len(fo) != n or sorted(fo) != list(range(1, n + 1)):
            raise EngineError(
                f"{where('layout', 'firing_order')} = {list(fo)}: must list each cylinder 1…{n} exactly once"
            )
        throws, banks = concrete(self.layout.throw_angles_deg), concrete(self.layout.banks_deg)
        tdc = None if throws is None or banks is None else throws + banks  # tdc_angles_deg, in NumPy
        if tdc is not None:
            _, span, cycle = _firing_tdc_deg(np, tdc, fo, self.strokes)
            if span >= cycle - 1e-9 and n > 1:
                raise EngineError(
                    f"{where('layout', 'firing_order')} = {'-'.join(map(str, fo))}: cannot fire in this order "
                    f"with throw angles {fmt(concrete(lay.throw_angles_deg))}° and bank angles "
                    f"{fmt(concrete(lay.banks_deg))}°: the firings do not fit into one {cycle:g}° cycle"
                )
        self.pressure.validate_for(self.strokes)
        if self.masses.full_rod:
            a, L = concrete(self.masses.rod_cg_from_big_end_m), concrete(self.geometry.rod_length_m)
            if a is not None and L is not None and a > L:
                raise EngineError(
                    f"{where('masses', 'rod_cg_from_big_end_m')} = {fmt(a)}: the rod's centre of mass must lie "
                    f"on the rod, within rod_length_m = {fmt(L)} m of the big end"
                )
        if self.articulated is not None:
            self._check_articulated()
        self._check_shaft()
        self._check_torsion()
        self._check_derived()

    def _check_types(self):
        if not isinstance(self.name, str):
            raise TypeError(f"Engine(name = {self.name!r}): expected a string, got {type(self.name).__name__}")
        for key in ("strokes", "cylinders"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise TypeError(f"Engine({key} = {v!r}): expected a whole number, got {type(v).__name__}")
        for key, cls, optional in _TABLE_TYPES:
            v = getattr(self, key)
            if not (isinstance(v, cls) or (optional and v is None)):
                name = "a rotor." + cls.__name__ + (" or None" if optional else "")
                raise TypeError(f"Engine({key} = ...): expected {name}, got {type(v).__name__} {v!r:.40}")

    def _check_derived(self):
        """Quantities computed from the inputs must be finite and positive where they must:
        a finite but absurd input (a bore of 1e300 m) overflows here and is named."""
        g, m = self.geometry, self.masses
        b, S, L = concrete(g.bore_m), concrete(g.stroke_m), concrete(g.rod_length_m)
        if b is None or S is None or L is None:
            return
        bore = f"[geometry] bore_m = {fmt(b)}"
        with np.errstate(all="ignore"):
            area = np.pi * b**2 / 4
            finite_derived("the piston area", area, "m²", bore)
            finite_derived("the displacement", area * S * self.cylinders, "m³", f"{bore}, stroke_m = {fmt(S)}")
            R = S / 2
            masses = [
                None if x is None else concrete(x)
                for x in (m.reciprocating_kg, m.rotating_kg, m.rod_kg, m.rod_inertia_kgm2)
            ]
            if any(x is None for x in masses[:2]):
                return
            rod = 0.0 if masses[2] is None else masses[2] * (1 + R / L) ** 2 * R**2
            rod_j = 0.0 if masses[3] is None else masses[3] * (R / L) ** 2
            scale = (masses[0] * (1 + R / L) ** 2 + masses[1]) * R**2 + rod + rod_j
            finite_derived(
                "the rods' and pistons' inertia m·R²",
                scale * self.cylinders,
                "kg·m²",
                f"[masses] reciprocating_kg = {fmt(masses[0])}, stroke_m = {fmt(S)}",
                positive=False,
            )
            J = concrete(self.crankshaft.inertia_kgm2)
            if J is not None:
                finite_derived(
                    "the reduced inertia I(θ)",
                    J + scale * self.cylinders,
                    "kg·m²",
                    f"[crankshaft] inertia_kgm2 = {fmt(J)}",
                )
            rpm = concrete(self.operating.rpm)
            if rpm is not None:
                omega = rpm * RAD_S_PER_RPM
                force = masses[0] * R * (1 + R / L) * omega**2
                finite_derived(
                    "the reciprocating inertia torque at the operating speed",
                    force * R,
                    "N·m",
                    f"[operating] rpm = {fmt(rpm)}, [masses] reciprocating_kg = {fmt(masses[0])}",
                    positive=False,
                )
            p_max = _peak_pressure_input(self.pressure)
            if p_max is not None:
                finite_derived(
                    "the peak gas force p·A",
                    p_max * area,
                    "N",
                    f"{bore} with pressures up to {p_max:g} Pa",
                    positive=False,
                )
            ratio = getattr(self.pressure, "compression_ratio", None)
            eps = None if ratio is None else concrete(ratio)
            if eps is not None:
                finite_derived(
                    "the clearance volume V_h/(ε − 1)",
                    area * S / (eps - 1),
                    "m³",
                    f"[pressure] compression_ratio = {fmt(eps)}",
                )

    def check(self) -> Engine:
        """Check the whole engine again, every table and how they fit, as when it was built;
        returns the engine.

        ``eqx.tree_at`` replaces a field without running the tables' checks, so a zero
        inertia or a NaN bore can be put into an engine that way; the solvers
        (:func:`rotor.crank_train`, and through it :func:`rotor.steady_state`,
        :func:`rotor.simulate` and the flywheel design) call this on every engine whose
        fields are concrete numbers. Traced fields (inside ``jax.jit``) are checked when the
        program runs instead (:func:`guard_engine`).

        **Raises:** :class:`rotor.EngineError` naming the key and the problem, or a
        :class:`TypeError` for a field that is not a number (or not a table).
        """
        self._check_types()
        for part in (self.geometry, self.masses, self.crankshaft, self.layout, self.pressure, self.operating):
            _recheck(part)
        for optional_part in (self.articulated, self.friction, self.counterweights, self.torsion):
            if optional_part is not None:
                _recheck(optional_part)
        type(self).__check_init__(self)
        return self

    def _check_articulated(self):
        art, n = self.articulated, self.cylinders
        for key, cyls in (("slaves", art.slaves), ("masters", art.masters)):
            bad = [c for c in cyls if not 1 <= c <= n]
            if bad:
                raise EngineError(f"{where('articulated', key)}: cylinder {bad[0]} does not exist (1…{n})")
        if len(set(art.slaves)) != len(art.slaves) or set(art.slaves) & set(art.masters):
            raise EngineError(
                f"{where('articulated', 'slaves')} = {list(art.slaves)}: each slave must be listed once and "
                "cannot itself be a master"
            )
        throws = concrete(self.layout.throw_angles_deg)
        if throws is not None:
            for s, m in zip(art.slaves, art.masters):
                if not np.isclose(throws[s - 1], throws[m - 1]):
                    raise EngineError(
                        f"{where('articulated', 'masters')}: slave cylinder {s} must share the crank throw of its "
                        f"master {m} (throw angles {throws[s - 1]:g}° and {throws[m - 1]:g}°)"
                    )
        r1, l1 = concrete(art.knuckle_radius_m), concrete(art.rod_length_m)
        R = concrete(self.geometry.crank_radius_m)
        if r1 is not None and R is not None and l1 is not None and not l1 > R + r1:
            raise EngineError(
                f"{where('articulated', 'rod_length_m')} = {fmt(l1)}: the slave rod must be longer than the crank "
                f"radius plus the knuckle radius ({fmt(R + r1)} m)"
            )

    def _check_shaft(self):
        """The crankshaft's throws, main journals and counterweights fit the cylinders."""
        n, cs = self.cylinders, self.crankshaft
        if cs.throws is not None:
            t = list(cs.throws)
            if len(t) != n:
                raise EngineError(
                    f"{where('crankshaft', 'throws')}: needs one throw number per cylinder ({n}), got {len(t)}"
                )
            used = sorted(set(t))
            if used != list(range(1, len(used) + 1)):
                raise EngineError(
                    f"{where('crankshaft', 'throws')} = {t}: number the throws 1, 2, … from the front without gaps"
                )
            throws = concrete(self.layout.throw_angles_deg)
            if throws is not None:
                for k in used:
                    cyl = [i for i in range(n) if t[i] == k]
                    if not np.allclose(np.mod(throws[cyl] - throws[cyl[0]] + 180, 360) - 180, 0):
                        raise EngineError(
                            f"{where('crankshaft', 'throws')}: cylinders {', '.join(str(i + 1) for i in cyl)} share "
                            f"throw {k} but have different throw angles ({fmt(throws[cyl])}°)"
                        )
            for s_, m_ in self.slave_index().items():
                if t[s_] != t[m_]:
                    raise EngineError(
                        f"{where('crankshaft', 'throws')}: slave cylinder {s_ + 1} must be on the throw of its master "
                        f"{m_ + 1}"
                    )
        nt = self.throw_count
        if cs.main_journals is not None:
            j = int(cs.main_journals)
            fits = [d + 1 for d in range(1, nt + 1) if nt % d == 0]
            if j not in fits:
                raise EngineError(
                    f"{where('crankshaft', 'main_journals')} = {j}: {nt} throw{'s' if nt > 1 else ''} cannot be shared "
                    f"evenly between {j - 1} span{'s' if j != 2 else ''}; use {', '.join(map(str, fits))} journals"
                )
        cw = self.counterweights
        if cw is not None:
            for i, w in enumerate(cw.webs, 1):
                if not 1 <= w <= 2 * nt:
                    raise EngineError(
                        f"[[counterweights]] {i}: web {w} does not exist: the crankshaft has {nt} "
                        f"throw{'s' if nt > 1 else ''}, webs 1…{2 * nt} (2k − 1 and 2k flank throw k)"
                    )

    def _check_torsion(self):
        """The ``[torsion]`` chain has a mass for every crank throw."""
        t = self.torsion
        if t is None:
            return
        nt = self.throw_count
        if len(t.throw_masses) != nt:
            raise EngineError(
                f"{where('torsion', 'throw_masses')} = {list(t.throw_masses)}: needs the mass number of each of the "
                f"{nt} crank throw{'s' if nt > 1 else ''}, got {len(t.throw_masses)}"
            )

    @property
    def throw_index(self) -> tuple[int, ...]:
        """The crank throw of each cylinder, 0-based (``[crankshaft] throws`` minus one; by
        default each cylinder its own throw and a slave rod its master's)."""
        if self.crankshaft.throws is not None:
            return tuple(k - 1 for k in self.crankshaft.throws)
        slaves = self.slave_index()
        masters = [i for i in range(self.cylinders) if i not in slaves]
        own = {c: k for k, c in enumerate(masters)}
        return tuple(own[slaves.get(i, i)] for i in range(self.cylinders))

    @property
    def throw_count(self) -> int:
        """The number of crank throws."""
        return max(self.throw_index) + 1

    # ------------------------------------------------------------------ derived angles
    @property
    def cycle_rad(self) -> float:
        """Length of one working cycle [rad]: 4π (four-stroke) or 2π (two-stroke)."""
        return 2 * np.pi * self.strokes / 2

    @property
    def tdc_angles_deg(self):
        """Engine crank angle at which each cylinder's piston is at TDC [deg] (mod 360)."""
        throws, banks = _alike(self.layout.throw_angles_deg, self.layout.banks_deg)
        return throws + banks

    @property
    def firing_angles_rad(self):
        """Engine crank angle of each cylinder's firing TDC [rad], cylinder 1 first.

        From the throw and bank angles and the firing order; cylinder 1 fires at 2π
        (four-stroke, where θ = 0 is its TDC at the start of intake) or at 0 (two-stroke).
        """
        tdc = self.tdc_angles_deg
        xp = array_module(tdc)
        angles, _, _ = _firing_tdc_deg(xp, tdc, self.layout.firing_order, self.strokes)
        return xp.deg2rad(xp.stack([xp.asarray(a, dtype=xp.float64) for a in angles]))

    def mechanical_angles(self, theta: ArrayLike) -> Float[Array, "... cylinders"]:
        """Each cylinder's crank angle from its own axis [rad], shape ``theta.shape + (cylinders,)``.

        **Arguments:** ``theta``: engine crank angle [rad].
        """
        tdc = self.tdc_angles_deg
        xp = array_module(theta, tdc)
        angle = xp.asarray(theta, dtype=xp.float64)
        return angle[..., None] - xp.deg2rad(tdc)

    def cycle_angles(self, theta: ArrayLike) -> Float[Array, "... cylinders"]:
        """Each cylinder's cycle angle (0 = TDC before intake) [rad], in [0, cycle), shape
        ``theta.shape + (cylinders,)``.

        **Arguments:** ``theta``: engine crank angle [rad].
        """
        fire = self.firing_angles_rad
        xp = array_module(theta, fire)
        angle = xp.asarray(theta, dtype=xp.float64)
        firing_cycle_angle = np.pi * 2 if self.strokes == 4 else 0.0
        return xp.mod(angle[..., None] - fire + firing_cycle_angle, self.cycle_rad)

    def slave_index(self) -> dict:
        """{slave cylinder index: master cylinder index}, 0-based."""
        if self.articulated is None:
            return {}
        return {s - 1: m - 1 for s, m in zip(self.articulated.slaves, self.articulated.masters)}

    def replace(self, **changes: object) -> Engine:
        """A copy with some whole tables replaced, e.g. ``engine.replace(pressure=NoPressure())``
        (``changes``: field name → new table or value, units as in the file)."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        fields.update(changes)
        return Engine(**fields)


def unnamed(engine: Any) -> Any:
    """``engine`` with an empty name where it is an :class:`Engine`, else ``engine`` itself.
    The name is a static field: a compiled function given the engine would be compiled again
    for every name, though no computation reads it."""
    if not (isinstance(engine, Engine) and engine.name):
        return engine
    # the fields of an engine already checked, copied as they are: Engine(...) would check
    # them all again (about 0.9 ms, on every call of a compiled function)
    copy = object.__new__(Engine)
    for field in dataclasses.fields(Engine):
        object.__setattr__(copy, field.name, getattr(engine, field.name))
    object.__setattr__(copy, "name", "")
    return copy


_ARGUMENT_UNITS = {"theta": "rad", "omega": "rad/s"}
"""The numeric arguments :func:`engine_jit` checks by name, and their units."""


def engine_jit(fn: Any) -> Any:
    """``eqx.filter_jit`` for a function whose first argument is an :class:`Engine`,
    compiled once for engines of the same structure whatever their names (:func:`unnamed`).
    The function must not read the name.

    Called from outside rotor (:func:`rotor.checks.called_from_outside`), the function's
    ``theta`` [rad] and ``omega`` [rad/s] are checked first (real and finite:
    :func:`rotor.engine.plausible.checked_angle`) and a traced engine's fields when the
    program runs (:func:`guard_engine`); rotor's own callers pass checked values."""
    jitted = kept_program()(eqx.filter_jit(fn))
    positions = {
        name: i for i, name in enumerate(inspect.signature(fn).parameters) if name in _ARGUMENT_UNITS and i > 0
    }

    def checked(engine: Any, args: tuple, kwargs: dict) -> tuple[Any, tuple, dict]:
        engine = require_engine(engine, f"{fn.__name__}(engine)")
        if tracing():
            engine = guard_engine(engine)
        given, kwargs = list(args), dict(kwargs)
        for name, i in positions.items():
            if i - 1 < len(given):
                given[i - 1] = checked_angle(fn.__name__, name, given[i - 1], _ARGUMENT_UNITS[name])
            elif name in kwargs:
                kwargs[name] = checked_angle(fn.__name__, name, kwargs[name], _ARGUMENT_UNITS[name])
        return engine, tuple(given), kwargs

    @functools.wraps(fn)
    def call(engine: Any, *args: Any, **kwargs: Any) -> Any:
        if called_from_outside():
            engine, args, kwargs = checked(engine, args, kwargs)
        return jitted(unnamed(engine), *args, **kwargs)

    call.lower = lambda engine, *args, **kwargs: jitted.lower(unnamed(engine), *args, **kwargs)  # type: ignore[attr-defined]
    return call


_TABLE_TYPES = (
    ("geometry", Geometry, False),
    ("masses", Masses, False),
    ("crankshaft", Crankshaft, False),
    ("layout", Layout, False),
    ("pressure", PressureSource, False),
    ("operating", Operating, False),
    ("articulated", Articulated, True),
    ("friction", Friction, True),
    ("counterweights", Counterweights, True),
    ("torsion", Torsion, True),
)


def guard_engine(engine: Engine, tables: tuple[str, ...] | None = None, checks: Any = None) -> Engine:
    """``engine`` with its traced fields checked when the program runs (``eqx.error_if``):
    each finite and within its plausible range (:func:`rotor.engine.plausible.guard_fields`)
    and the rod longer than the crank radius plus the pin offset, or a one-line error naming
    the key. ``tables``: the tables to check (default all; a prepared engine's table inputs
    are compared with the values it was prepared from instead); ``checks``: a
    :class:`rotor.checks.TracedChecks` to record the checks in, for the caller to make with
    its others. The engine itself where no field is traced (:meth:`Engine.check` judges
    concrete ones)."""
    if not has_tracer(engine):
        return engine
    parts = [
        f.name
        for f in dataclasses.fields(engine)
        if (tables is None or f.name in tables)
        and isinstance(getattr(engine, f.name), eqx.Module)
        and has_tracer(getattr(engine, f.name))
    ]
    guarded = [guard_fields(getattr(engine, name), checks) for name in parts]
    engine = eqx.tree_at(lambda e: [getattr(e, name) for name in parts], engine, guarded)
    g = engine.geometry
    if (tables is None or "geometry" in tables) and has_tracer(g):
        reach = jnp.asarray(g.stroke_m) / 2 + jnp.abs(jnp.asarray(g.pin_offset_m))
        rod = guard(
            g.rod_length_m,
            ~(jnp.asarray(g.rod_length_m) > reach),
            "[geometry] rod_length_m: the rod must be longer than the crank radius stroke_m/2 plus the pin offset |k|, "
            f"or the crank cannot turn; {TRACED}",
            checks,
        )
        engine = eqx.tree_at(lambda e: e.geometry.rod_length_m, engine, rod)
    return engine


def require_engine(engine: object, call: str) -> Engine:
    """``engine`` if it is a :class:`rotor.Engine`, else a :class:`TypeError` naming ``call``
    (the function and argument, e.g. ``"engine_summary(engine)"``)."""
    if not isinstance(engine, Engine):
        hint = " (load it first: rotor.load_engine(...))" if isinstance(engine, (str, bytes)) else ""
        raise TypeError(f"{call}: expected a rotor.Engine{hint}, got {what_it_is(engine)}")
    return engine
