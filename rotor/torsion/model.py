"""The crankshaft as a chain of rigid masses on torsional springs and dampers.

A :class:`TorsionalChain` is n masses (the damper or pulley, the gear train, the crank
throws, the flywheel, the load) joined by n − 1 shaft sections, numbered from the
front. Its equations of motion are

    M·θ'' + C·θ' + K·θ = T(t),

θ the absolute angles of the masses [rad], M = diag(J) [kg·m²], K the tridiagonal
stiffness matrix of the shafts [N·m/rad] and C the damping matrix [N·m·s/rad]: absolute
damping c_i at mass i (to the ground: a viscous damper's housing, the bearings) plus
relative damping d_i in shaft i (between masses i and i + 1). Modal damping ratios, if
given, are applied in the modal analysis (:func:`rotor.torsional_modes`), where the
mass-normalised modes are known.

**From an engine.** An engine file's optional ``[torsion]`` table (:class:`rotor.Torsion`)
gives the chain's *constant* inertias — the crankshaft's own throws, the damper, the gear
train, the flywheel — with the mass that carries each crank throw. Each throw's mass also
carries the mechanisms of its cylinders (rods and pistons), whose reduced inertia
I_cyl(θ) rotor computes itself (:func:`rotor.cylinder_inertia`): :func:`torsional_chain`
adds their cycle mean to the throw masses (the linear modal analysis), and
:func:`mass_inertias` gives the whole inertia of each mass at a crank angle (the forced
response). The constant inertias of the table sum to ``[crankshaft] inertia_kgm2``, so
that a chain of very stiff shafts is the rigid one-mass model.

**From geometry.** :meth:`TorsionalChain.from_shafts` takes plain shaft sections,
k = G·π·(D⁴ − d⁴)/(32·L); :func:`crank_throw_stiffness` a crank throw by Carter's
empirical formula (B. C. Carter, "An empirical formula for crankshaft stiffness in
torsion", *Engineering* 126, 1928, p. 36; as quoted in W. Ker Wilson, *Practical
Solution of Torsional Vibration Problems*, vol. 1, 3rd ed., Chapman & Hall 1956, and
in J. P. Den Hartog, *Mechanical Vibrations*, 4th ed., McGraw-Hill 1956, §5.3).

All numbers are SI: inertia [kg·m²], stiffness [N·m/rad], damping [N·m·s/rad],
lengths [m], shear modulus [Pa]. Mass indices are 0-based in Python (``throw_masses``,
``load_mass``) and 1-based in the engine file (the mass numbers a person counts).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..checks import check_finite, check_positive, concrete, fmt
from ..cycles import array_module
from ..engine.inertia import cylinder_inertia
from ..engine.model import Engine, engine_jit, require_engine
from ..engine.plausible import number, what_it_is
from ..errors import EngineError

__all__ = [
    "TorsionalChain",
    "torsional_chain",
    "mass_inertias",
    "throw_inertias",
    "cylinder_masses",
    "mean_mass_inertias",
    "shaft_stiffness",
    "crank_throw_stiffness",
    "STEEL_SHEAR_MODULUS_PA",
]

STEEL_SHEAR_MODULUS_PA = 80e9
"""Shear modulus of steel [Pa] (forged crankshaft steels: 79…82 GPa; nodular cast iron
about 65 GPa)."""

_MEAN_POINTS = 256  # crank-angle points per revolution for the cycle mean of I_cyl(θ)


def _call(key: str) -> str:
    return f"TorsionalChain({key})"


def _index_tuple(value: Any, key: str) -> tuple[int, ...]:
    if value is None:
        return ()
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence | np.ndarray):
        raise TypeError(f"{_call(key)}: expected a sequence of whole numbers, got {what_it_is(value)}")
    out = []
    for v in value:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
            raise TypeError(f"{_call(key)}: expected whole numbers, got {what_it_is(v)}")
        out.append(int(v))
    return tuple(out)


class TorsionalChain(eqx.Module):
    """A chain of n rigid masses on n − 1 torsional springs, numbered from the front.

    **Fields:**

    - ``inertias_kgm2``: the masses' moments of inertia J_i [kg·m²], shape (n,), n ≥ 2.
    - ``stiffnesses_Nm_per_rad``: the shafts' torsional stiffnesses k_i between masses i and
      i + 1 [N·m/rad], shape (n − 1,).
    - ``absolute_damping_Nms_per_rad``: viscous damping of each mass to the ground
      [N·m·s/rad], shape (n,), or ``None`` (none).
    - ``relative_damping_Nms_per_rad``: viscous damping in each shaft, between its two
      masses [N·m·s/rad], shape (n − 1,), or ``None``.
    - ``modal_damping_ratio``: ``None``, one ratio ζ [-] for every elastic mode, or one
      per elastic mode (n − 1 values, lowest mode first); applied in the modal analysis,
      on top of the absolute and relative damping.
    - ``names``: a name for each mass (static; default ``"mass 1"`` … ``"mass n"``).
    - ``throw_masses``: the 0-based index of the mass that carries each crank throw, in
      throw order (static; empty for a chain that is not an engine's).
    - ``load_mass``: the 0-based index of the mass where the load acts (static; default
      the last, usually the flywheel or the brake).

    Build it from numbers, ``TorsionalChain(inertias_kgm2=[…], stiffnesses_Nm_per_rad=[…])``,
    from shaft geometry (:meth:`from_shafts`) or from an engine (:func:`torsional_chain`).
    The values are checked when it is built (finite, positive inertias and stiffnesses,
    lengths that fit, indices inside the chain); a problem raises :class:`rotor.EngineError`
    naming the field. Numeric fields are float64 JAX arrays, so ``jax.grad`` works over
    them.
    """

    inertias_kgm2: Float[Array, " n"] = eqx.field(converter=number("", _call("inertias_kgm2")))
    stiffnesses_Nm_per_rad: Float[Array, " n-1"] = eqx.field(converter=number("", _call("stiffnesses_Nm_per_rad")))
    absolute_damping_Nms_per_rad: Float[Array, " n"] | None = eqx.field(
        converter=number("", _call("absolute_damping_Nms_per_rad"), optional=True), default=None
    )
    relative_damping_Nms_per_rad: Float[Array, " n-1"] | None = eqx.field(
        converter=number("", _call("relative_damping_Nms_per_rad"), optional=True), default=None
    )
    modal_damping_ratio: Array | None = eqx.field(
        converter=number("", _call("modal_damping_ratio"), optional=True), default=None
    )
    names: tuple[str, ...] = eqx.field(static=True, default=())
    throw_masses: tuple[int, ...] = eqx.field(static=True, default=())
    load_mass: int = eqx.field(static=True, default=-1)

    def __init__(
        self,
        inertias_kgm2: ArrayLike,
        stiffnesses_Nm_per_rad: ArrayLike,
        absolute_damping_Nms_per_rad: ArrayLike | None = None,
        relative_damping_Nms_per_rad: ArrayLike | None = None,
        modal_damping_ratio: ArrayLike | None = None,
        names: Sequence[str] | None = None,
        throw_masses: Sequence[int] | None = None,
        load_mass: int | None = None,
    ):
        """Build and check a chain; arguments as the fields of the class (units there).
        ``names`` defaults to ``"mass 1"`` …, ``load_mass`` to the last mass."""
        self.inertias_kgm2 = inertias_kgm2  # type: ignore[assignment]
        self.stiffnesses_Nm_per_rad = stiffnesses_Nm_per_rad  # type: ignore[assignment]
        self.absolute_damping_Nms_per_rad = absolute_damping_Nms_per_rad  # type: ignore[assignment]
        self.relative_damping_Nms_per_rad = relative_damping_Nms_per_rad  # type: ignore[assignment]
        self.modal_damping_ratio = modal_damping_ratio  # type: ignore[assignment]
        try:
            shape = np.shape(inertias_kgm2)
        except (TypeError, ValueError):
            shape = ()
        n = int(shape[0]) if len(shape) == 1 else 0
        if names is None:
            names = tuple(f"mass {i + 1}" for i in range(n))
        if isinstance(names, (str, bytes)) or not isinstance(names, Sequence):
            raise TypeError(f"{_call('names')}: expected a sequence of strings, got {what_it_is(names)}")
        for nm in names:
            if not isinstance(nm, str):
                raise TypeError(f"{_call('names')}: expected strings, got {what_it_is(nm)}")
        self.names = tuple(names)
        self.throw_masses = _index_tuple(throw_masses, "throw_masses")
        if load_mass is None:
            load_mass = n - 1
        if isinstance(load_mass, (bool, np.bool_)) or not isinstance(load_mass, (int, np.integer)):
            raise TypeError(
                f"{_call('load_mass')}: expected a whole number (a 0-based mass index), got {what_it_is(load_mass)}"
            )
        self.load_mass = int(load_mass)

    def __check_init__(self):
        J, k = self.inertias_kgm2, self.stiffnesses_Nm_per_rad
        if jnp.ndim(J) != 1 or J.shape[0] < 2:
            raise EngineError(
                f"{_call('inertias_kgm2')} = {fmt(concrete(J)) if concrete(J) is not None else '…'}: needs a list of "
                "two or more inertias (one per mass) [kg·m²]"
            )
        n = J.shape[0]
        if jnp.ndim(k) != 1 or k.shape[0] != n - 1:
            raise EngineError(
                f"{_call('stiffnesses_Nm_per_rad')}: needs one stiffness per shaft, n − 1 = {n - 1} for {n} masses, "
                f"got {np.size(k)}"
            )
        check_positive("", _call("inertias_kgm2"), J)
        check_positive("", _call("stiffnesses_Nm_per_rad"), k)
        for key, size in (("absolute_damping_Nms_per_rad", n), ("relative_damping_Nms_per_rad", n - 1)):
            v = getattr(self, key)
            if v is None:
                continue
            if jnp.ndim(v) != 1 or v.shape[0] != size:
                what = "mass" if size == n else "shaft"
                raise EngineError(f"{_call(key)}: needs one value per {what} ({size}), got {np.size(v)}")
            check_positive("", _call(key), v, allow_zero=True)
        z = self.modal_damping_ratio
        if z is not None:
            if not (jnp.ndim(z) == 0 or (jnp.ndim(z) == 1 and z.shape[0] == n - 1)):
                raise EngineError(
                    f"{_call('modal_damping_ratio')}: needs one ratio for all modes or one per elastic mode "
                    f"({n - 1}), got {np.size(z)}"
                )
            check_positive("", _call("modal_damping_ratio"), z, allow_zero=True)
            zc = concrete(z)
            if zc is not None and np.any(zc >= 1):
                raise EngineError(
                    f"{_call('modal_damping_ratio')} = {fmt(zc)}: a modal damping ratio must be below 1 (critical "
                    "damping); torsional modes have 0.01…0.1"
                )
        if len(self.names) != n:
            raise EngineError(f"{_call('names')}: needs one name per mass ({n}), got {len(self.names)}")
        for i in self.throw_masses:
            if not 0 <= i < n:
                raise EngineError(
                    f"{_call('throw_masses')} = {list(self.throw_masses)}: mass index {i} lies outside the chain "
                    f"(0…{n - 1}, 0-based)"
                )
        if len(set(self.throw_masses)) != len(self.throw_masses):
            raise EngineError(
                f"{_call('throw_masses')} = {list(self.throw_masses)}: each crank throw needs its own mass "
                "(two cylinders on one throw share it through the engine's [crankshaft] throws)"
            )
        if not 0 <= self.load_mass < n:
            raise EngineError(
                f"{_call('load_mass')} = {self.load_mass}: mass index outside the chain (0…{n - 1}, 0-based)"
            )
        check_finite("", _call("inertias_kgm2"), J)

    # ------------------------------------------------------------------ sizes
    @property
    def size(self) -> int:
        """The number of masses n."""
        return int(self.inertias_kgm2.shape[0])

    @property
    def total_inertia_kgm2(self) -> Array:
        """ΣJ_i [kg·m²]: the inertia of the chain turning as one rigid body."""
        return jnp.sum(self.inertias_kgm2)

    # ------------------------------------------------------------------ matrices
    def stiffness_matrix(self) -> Float[Array, "n n"]:
        """K [N·m/rad], (n, n): tridiagonal, symmetric, singular (the free chain turns
        freely as one body)."""
        return _chain_matrix(self.stiffnesses_Nm_per_rad, self.size)

    def mass_matrix(self) -> Float[Array, "n n"]:
        """M = diag(J) [kg·m²], (n, n)."""
        xp = array_module(self.inertias_kgm2)
        return xp.diag(xp.asarray(self.inertias_kgm2))

    def damping_matrix(self) -> Float[Array, "n n"]:
        """C [N·m·s/rad], (n, n): diag(absolute damping) plus the shafts' relative damping
        in K's pattern. Modal damping is not in it: :func:`rotor.torsional_modes` adds it
        in modal coordinates."""
        n = self.size
        absolute = self.absolute_damping_Nms_per_rad
        xp = array_module(absolute, self.relative_damping_Nms_per_rad)
        C = xp.zeros((n, n))
        if absolute is not None:
            C = C + xp.diag(xp.asarray(absolute))
        if self.relative_damping_Nms_per_rad is not None:
            C = C + _chain_matrix(self.relative_damping_Nms_per_rad, n)
        return C

    @property
    def has_damping(self) -> bool:
        """Whether any damping (absolute, relative or modal) is given."""
        return any(
            v is not None
            for v in (self.absolute_damping_Nms_per_rad, self.relative_damping_Nms_per_rad, self.modal_damping_ratio)
        )

    def with_inertias(self, inertias_kgm2: ArrayLike) -> TorsionalChain:
        """The same chain with other inertias [kg·m²], shape (n,) (e.g. the throws' inertia
        at one crank angle); not checked again, so that it works on traced values."""
        return eqx.tree_at(lambda c: c.inertias_kgm2, self, jnp.asarray(inertias_kgm2, dtype=jnp.float64))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_shafts(
        cls,
        inertias_kgm2: ArrayLike,
        lengths_m: ArrayLike,
        outer_diameters_m: ArrayLike,
        inner_diameters_m: ArrayLike = 0.0,
        shear_modulus_pa: ArrayLike = STEEL_SHEAR_MODULUS_PA,
        **fields: Any,
    ) -> TorsionalChain:
        """A chain whose shafts are plain round (or hollow) sections.

        **Arguments:**

        - ``inertias_kgm2``: the masses' inertias [kg·m²], shape (n,).
        - ``lengths_m``: each shaft's length L [m], shape (n − 1,).
        - ``outer_diameters_m``: each shaft's outer diameter D [m], a number or shape (n − 1,).
        - ``inner_diameters_m``: each bore d [m] (0: solid; default).
        - ``shear_modulus_pa``: G [Pa] (default steel, 80 GPa), a number or per shaft.
        - ``fields``: any other field of the class (``names``, ``throw_masses``, damping…).

        **Returns:** the chain with k = G·π·(D⁴ − d⁴)/(32·L) (:func:`shaft_stiffness`).
        """
        k = shaft_stiffness(lengths_m, outer_diameters_m, inner_diameters_m, shear_modulus_pa)
        return cls(inertias_kgm2=inertias_kgm2, stiffnesses_Nm_per_rad=k, **fields)


def _chain_matrix(k: Array, n: int) -> Array:
    """The (n, n) matrix of springs (or dashpots) k between neighbours (NumPy for a concrete
    ``k``: no program of its own)."""
    xp = array_module(k)
    k = xp.broadcast_to(xp.asarray(k, dtype=xp.float64), (n - 1,))
    zero = xp.zeros(1)
    diag = xp.concatenate([k, zero]) + xp.concatenate([zero, k])
    return xp.diag(diag) - xp.diag(k, 1) - xp.diag(k, -1)


# ---------------------------------------------------------------------- stiffness from geometry
def _positive_array(value: ArrayLike, call: str, *, allow_zero: bool = False) -> np.ndarray:
    a = concrete(number("", call)(value))
    if a is None:
        raise TypeError(f"{call}: expected numbers, got a traced value")
    check_positive("", call, a, allow_zero=allow_zero)
    return a


def shaft_stiffness(
    lengths_m: ArrayLike,
    outer_diameters_m: ArrayLike,
    inner_diameters_m: ArrayLike = 0.0,
    shear_modulus_pa: ArrayLike = STEEL_SHEAR_MODULUS_PA,
) -> Array:
    """Torsional stiffness of round shaft sections, k = G·π·(D⁴ − d⁴)/(32·L) [N·m/rad].

    **Arguments:** ``lengths_m``: L [m]; ``outer_diameters_m``: D [m];
    ``inner_diameters_m``: the bore d [m] (0 for a solid shaft); ``shear_modulus_pa``: G
    [Pa] (default steel, 80 GPa). Numbers or arrays that broadcast together.

    **Returns:** k [N·m/rad], the broadcast shape.
    """
    L = _positive_array(lengths_m, "shaft_stiffness(lengths_m)")
    D = _positive_array(outer_diameters_m, "shaft_stiffness(outer_diameters_m)")
    d = _positive_array(inner_diameters_m, "shaft_stiffness(inner_diameters_m)", allow_zero=True)
    G = _positive_array(shear_modulus_pa, "shaft_stiffness(shear_modulus_pa)")
    if np.any(np.broadcast_to(d, np.broadcast(D, d).shape) >= np.broadcast_to(D, np.broadcast(D, d).shape)):
        raise EngineError(
            f"shaft_stiffness(inner_diameters_m) = {fmt(d)}: a bore must be smaller than the shaft's "
            f"outer diameter ({fmt(D)} m)"
        )
    return jnp.asarray(G * np.pi * (D**4 - d**4) / (32 * L))


def crank_throw_stiffness(
    *,
    journal_diameter_m: float,
    journal_length_m: float,
    pin_diameter_m: float,
    pin_length_m: float,
    web_thickness_m: float,
    web_width_m: float,
    crank_radius_m: float,
    journal_bore_m: float = 0.0,
    pin_bore_m: float = 0.0,
    shear_modulus_pa: float = STEEL_SHEAR_MODULUS_PA,
) -> float:
    """Torsional stiffness of one crank throw (journal to journal) by Carter's formula
    [N·m/rad].

    Carter (1928) gives the length of plain journal-sized shaft that twists as much as one
    throw (two half journals, two webs and the crank pin):

        L_e = (l_j + 0.8·h) + 0.75·l_p·(D_j⁴ − d_j⁴)/(D_p⁴ − d_p⁴) + 1.5·R·(D_j⁴ − d_j⁴)/(h·b³),

    and k = G·π·(D_j⁴ − d_j⁴)/(32·L_e). Sources: B. C. Carter, "An empirical formula for
    crankshaft stiffness in torsion", *Engineering* 126 (1928); W. Ker Wilson, *Practical
    Solution of Torsional Vibration Problems*, vol. 1 (1956), ch. on crankshaft stiffness;
    Den Hartog, *Mechanical Vibrations* (1956), §5.3. Carter's formula is empirical, within
    about 10 % of measured throws of conventional proportions; prefer a measured or FE
    stiffness where there is one.

    **Arguments** (all keyword-only) [m, Pa]: ``journal_diameter_m`` D_j;
    ``journal_length_m`` l_j, the main journal length per throw (the two half journals
    together); ``pin_diameter_m`` D_p; ``pin_length_m`` l_p; ``web_thickness_m`` h (axial);
    ``web_width_m`` b (across the web); ``crank_radius_m`` R (half the stroke);
    ``journal_bore_m`` d_j and ``pin_bore_m`` d_p (0: solid); ``shear_modulus_pa`` G.

    **Returns:** k [N·m/rad], a float.
    """
    call = "crank_throw_stiffness"
    Dj = float(_positive_array(journal_diameter_m, f"{call}(journal_diameter_m)"))
    lj = float(_positive_array(journal_length_m, f"{call}(journal_length_m)", allow_zero=True))
    Dp = float(_positive_array(pin_diameter_m, f"{call}(pin_diameter_m)"))
    lp = float(_positive_array(pin_length_m, f"{call}(pin_length_m)", allow_zero=True))
    h = float(_positive_array(web_thickness_m, f"{call}(web_thickness_m)"))
    b = float(_positive_array(web_width_m, f"{call}(web_width_m)"))
    R = float(_positive_array(crank_radius_m, f"{call}(crank_radius_m)"))
    dj = float(_positive_array(journal_bore_m, f"{call}(journal_bore_m)", allow_zero=True))
    dp = float(_positive_array(pin_bore_m, f"{call}(pin_bore_m)", allow_zero=True))
    G = float(_positive_array(shear_modulus_pa, f"{call}(shear_modulus_pa)"))
    for bore, outer, key in ((dj, Dj, "journal_bore_m"), (dp, Dp, "pin_bore_m")):
        if bore >= outer:
            raise EngineError(f"{call}({key}) = {bore:g}: a bore must be smaller than its diameter ({outer:g} m)")
    pj = Dj**4 - dj**4
    Le = (lj + 0.8 * h) + 0.75 * lp * pj / (Dp**4 - dp**4) + 1.5 * R * pj / (h * b**3)
    return G * np.pi * pj / (32 * Le)


# ---------------------------------------------------------------------- from an engine
def _table(engine: Engine, call: str) -> Any:
    require_engine(engine, call)
    t = getattr(engine, "torsion", None)
    if t is None:
        raise EngineError(
            f"{call}: engine {engine.name!r} has no [torsion] table; add one to its file (the chain's inertias, "
            "stiffnesses and the mass of each crank throw, see docs/api/torsion.md) or build a rotor.TorsionalChain"
        )
    return t


def cylinder_masses(engine: Engine) -> tuple[int, ...]:
    """The 0-based chain mass that carries each cylinder's mechanism (its throw's mass),
    cylinder 1 first, from ``engine``'s ``[torsion] throw_masses`` and ``[crankshaft] throws``."""
    t = _table(engine, "cylinder_masses(engine)")
    throw_masses = tuple(m - 1 for m in t.throw_masses)
    return tuple(throw_masses[k] for k in engine.throw_index)


def throw_inertias(engine: Engine, theta: ArrayLike) -> Float[Array, "... n"]:
    """The rods' and pistons' reduced inertia on each mass of ``engine``'s chain at engine
    crank angle ``theta`` [rad]: I_cyl(θ) of the cylinders on each throw [kg·m²], zero on
    the masses that carry no throw. Shape ``theta.shape + (n,)``.

    Evaluated at one common crank angle: the chain's twist (a few milliradians) changes
    each throw's own angle by far less than the inertia's variation needs to be felt."""
    _table(engine, "throw_inertias(engine)")
    return _throw_inertias(engine, array_module(theta).asarray(theta, dtype=np.float64))


@engine_jit
def _throw_inertias(engine: Engine, theta: Array) -> Array:
    """:func:`throw_inertias`, compiled once per engine layout and grid shape (op by op, the
    inertia's many small kernels cost seconds to dispatch the first time)."""
    n = int(engine.torsion.inertias_kgm2.shape[0])  # type: ignore[union-attr]
    ci = cylinder_inertia(engine, theta)  # (..., cylinders)
    onto = np.zeros((engine.cylinders, n))
    onto[np.arange(engine.cylinders), np.asarray(cylinder_masses(engine))] = 1.0
    return ci @ jnp.asarray(onto)


def mass_inertias(engine: Engine, theta: ArrayLike) -> Float[Array, "... n"]:
    """The whole inertia of each mass of ``engine``'s chain at crank angle ``theta`` [rad]:
    the ``[torsion]`` table's constant inertia plus the mechanisms on its throw,
    :func:`throw_inertias` [kg·m²], shape ``theta.shape + (n,)``. Their sum is the rigid
    model's I(θ) when the table is consistent with ``[crankshaft] inertia_kgm2``."""
    t = _table(engine, "mass_inertias(engine)")
    extra = throw_inertias(engine, theta)
    xp = array_module(t.inertias_kgm2, extra)
    return xp.asarray(t.inertias_kgm2) + xp.asarray(extra)


def torsional_chain(engine: Engine) -> TorsionalChain:
    """The torsional chain of ``engine`` (a :class:`rotor.Engine` with a ``[torsion]``
    table), for the linear analysis: each throw's mass carries its mechanisms' cycle-mean
    inertia (the mean of I_cyl over a revolution, :func:`rotor.cylinder_inertia`) on top
    of the table's constant inertia.

    **Returns:** a :class:`TorsionalChain` with the table's names, damping, throw masses
    and load mass (0-based).

    **Raises:** :class:`rotor.EngineError` if the engine has no ``[torsion]`` table.
    """
    t = _table(engine, "torsional_chain(engine)")
    theta = np.linspace(0.0, 2 * np.pi, _MEAN_POINTS, endpoint=False)
    extra = throw_inertias(engine, theta)
    xp = array_module(t.inertias_kgm2, extra)
    mean_extra = xp.mean(xp.asarray(extra), axis=0)
    n = int(np.size(t.inertias_kgm2))
    names = tuple(t.names) if t.names else tuple(_default_names(n, tuple(m - 1 for m in t.throw_masses)))
    return TorsionalChain(
        inertias_kgm2=xp.asarray(t.inertias_kgm2) + mean_extra,
        stiffnesses_Nm_per_rad=t.stiffnesses_Nm_per_rad,
        absolute_damping_Nms_per_rad=t.absolute_damping_Nms_per_rad,
        relative_damping_Nms_per_rad=t.relative_damping_Nms_per_rad,
        modal_damping_ratio=t.modal_damping_ratio,
        names=names,
        throw_masses=tuple(m - 1 for m in t.throw_masses),
        load_mass=(n - 1) if t.load_mass is None else t.load_mass - 1,
    )


def _default_names(n: int, throws: tuple[int, ...]) -> list[str]:
    names = [f"mass {i + 1}" for i in range(n)]
    for k, m in enumerate(throws):
        names[m] = f"throw {k + 1}"
    return names


def mean_mass_inertias(engine: Engine) -> Float[Array, " n"]:
    """The cycle mean of :func:`mass_inertias` [kg·m²], shape (n,): the inertias of
    :func:`torsional_chain`."""
    return torsional_chain(engine).inertias_kgm2
