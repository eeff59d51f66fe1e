"""Free torsional vibration: natural frequencies and mode shapes of a chain.

**The eigenproblem** (``method="eigen"``, the default). The undamped chain
M·θ'' + K·θ = 0 has the modes K·φ = ω²·M·φ. With M = diag(J) this is the symmetric
problem A·ψ = ω²·ψ, A = M^(−1/2)·K·M^(−1/2), φ = M^(−1/2)·ψ, solved by
``jnp.linalg.eigh`` (:func:`natural_frequencies`: jit-able and differentiable in the
chain's numbers). A free chain always has the rigid-body mode ω = 0 (the whole shaft
turning); it is left out: ``natural_frequencies_hz`` lists the n − 1 elastic modes,
ascending.

**Damped modes.** With absolute, relative or modal damping the state-space matrix
[[0, I], [−M⁻¹K, −M⁻¹C]] has the eigenvalues λ = −ζ·ωₙ ± i·ω_d; each elastic mode is
paired with the oscillatory eigenvalue closest to its undamped frequency and reports
ω_d/2π and ζ = −Re λ/|λ| (``None`` for a mode that damping makes aperiodic). Modal
damping ratios ζ_j enter as C_modal = M·Φ·diag(2·ζ_j·ω_j/m_j)·Φᵀ·M
(:func:`modal_damping_matrix`), m_j = φ_jᵀ·M·φ_j.

**Holzer's method** (``method="holzer"``, :func:`holzer_frequencies`), the textbook
check (H. Holzer, *Die Berechnung der Drehschwingungen*, Springer, Berlin 1921; the
transfer-matrix form as in V. A. Lashko's book on the matrix methods of the torsional
vibration of power plants with internal combustion engines, *Matrix methods in
calculations of torsional vibrations of power plants with ICE*): at a trial ω the front
mass turns by θ₁ = 1 with no torque on it, and each mass and shaft passes the amplitude
and torque on, T_i = T_{i−1} + ω²·J_i·θ_i, θ_{i+1} = θ_i − T_i/k_i; ω is a natural
frequency when the torque left beyond the last mass, the residual R(ω²) = T_n, is zero
(:func:`holzer_residual`). R is a polynomial of degree n in ω² whose roots are the
eigenvalues (0 and the n − 1 elastic ones, all simple in a chain). The roots are found
without the eigensolution: each is bracketed by bisection on the Sturm count (the number
of negative pivots of K − ω²·M in its LDLᵀ factorisation equals, by Sylvester's law of
inertia, the number of natural frequencies below ω), and then refined by bisection on
the sign of R(ω²)/ω² (the residual without its rigid-body root) to the last bit of ω²,
all modes at once. It agrees with the eigenproblem to about 1e-12 relative on the chains
of the tests; the Holzer amplitudes at the roots are the mode shapes
(:func:`holzer_shapes`).

**An engine's chain** (:func:`rotor.torsional_chain`) has the mechanisms' cycle-mean
inertia on its throw masses; the reciprocating masses make each throw's inertia vary
with the crank angle (orders 2, 4, … of a cylinder), so the natural frequencies
"breathe" over the cycle. :func:`torsional_modes` reports, for an engine, each mode's
lowest and highest frequency over one revolution (the eigenproblem solved with the
inertias of every mass at each crank angle of a 1° grid): ``frequency_min_hz`` and
``frequency_max_hz``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ..cycles import array_module
from ..engine.model import Engine
from ..engine.plausible import check_speed_rpm, require_whole, what_it_is
from ..errors import EngineError, SolverError
from ..programs import kept_program
from ..results import Result, json_safe
from .model import TorsionalChain, mass_inertias, torsional_chain

__all__ = [
    "TorsionalModes",
    "torsional_modes",
    "natural_frequencies",
    "natural_frequencies_of",
    "frequency_spread",
    "check_mode_size",
    "spread_points",
    "EXACT_SPREAD_MASSES",
    "MAX_MODE_MASSES",
    "mode_shapes",
    "modal_damping_matrix",
    "holzer_residual",
    "holzer_frequencies",
    "holzer_shapes",
    "chain_of",
]

_METHODS = ("eigen", "holzer")


# ---------------------------------------------------------------------- the eigenproblem (JAX)
def _eigh(inertias: Array, stiffness_matrix: Array) -> tuple[Array, Array]:
    """Eigenvalues ω² [rad²/s²] ascending and mass-normalised modes (columns) of K, diag(J)."""
    s = 1.0 / jnp.sqrt(inertias)
    A = stiffness_matrix * s[:, None] * s[None, :]
    A = 0.5 * (A + A.T)
    lam, psi = jnp.linalg.eigh(A)
    return lam, psi * s[:, None]


def _natural_frequencies_hz(inertias: Array, stiffnesses: Array) -> Array:
    n = inertias.shape[-1]
    diag = jnp.zeros(n).at[:-1].add(stiffnesses).at[1:].add(stiffnesses)
    K = jnp.diag(diag) - jnp.diag(stiffnesses, 1) - jnp.diag(stiffnesses, -1)
    lam, _ = _eigh(inertias, K)
    return jnp.sqrt(jnp.clip(lam[1:], 0.0)) / (2 * jnp.pi)


def _modal(inertias: Array, stiffnesses: Array) -> tuple[Array, Array]:
    n = inertias.shape[-1]
    diag = jnp.zeros(n).at[:-1].add(stiffnesses).at[1:].add(stiffnesses)
    K = jnp.diag(diag) - jnp.diag(stiffnesses, 1) - jnp.diag(stiffnesses, -1)
    lam, phi = _eigh(inertias, K)
    return jnp.sqrt(jnp.clip(lam[1:], 0.0)) / (2 * jnp.pi), phi.T[1:]


_modal_jit = kept_program()(jax.jit(_modal))
_eigh_jit = kept_program()(jax.jit(_eigh))  # one compiled call, not a dozen eager operations

natural_frequencies_of = kept_program()(jax.jit(_natural_frequencies_hz))
"""``natural_frequencies_of(inertias_kgm2, stiffnesses_Nm_per_rad)``: the elastic natural
frequencies [Hz] of the chain with these inertias [kg·m², (n,)] and stiffnesses
[N·m/rad, (n − 1,)], compiled once per chain size; vmap it over inertias (the crank-angle
grid) or stiffnesses (a design sweep)."""


def natural_frequencies(chain: TorsionalChain) -> Float[Array, " n-1"]:
    """The undamped natural frequencies of ``chain`` [Hz], ascending, without the rigid-body
    mode, by the symmetric eigenproblem (JAX: jit-able and differentiable with respect to
    the inertias and stiffnesses).

    **Arguments:** ``chain``: a :class:`rotor.TorsionalChain`.
    """
    return natural_frequencies_of(chain.inertias_kgm2, chain.stiffnesses_Nm_per_rad)


def _normalise_shapes(phi: np.ndarray) -> np.ndarray:
    """Modes as rows, scaled to max |φ| = 1 with that largest amplitude positive (where two
    are equally large, the front one)."""
    phi = np.asarray(phi, dtype=np.float64)
    a = np.abs(phi)
    big = np.argmax(a >= (1 - 1e-9) * a.max(axis=1, keepdims=True), axis=1)
    peak = phi[np.arange(len(phi)), big][:, None]
    return phi / peak


def mode_shapes(chain: TorsionalChain) -> np.ndarray:
    """The elastic mode shapes of ``chain``, one row per mode (lowest first), one column per
    mass [-]: scaled so that the largest amplitude is +1.

    **Arguments:** ``chain``: a :class:`rotor.TorsionalChain`.
    """
    _, phi = _eigh_jit(chain.inertias_kgm2, chain.stiffness_matrix())
    return _normalise_shapes(np.asarray(phi).T[1:])


def modal_damping_matrix(chain: TorsionalChain) -> Float[Array, "n n"]:
    """The damping matrix [N·m·s/rad], (n, n), that gives every elastic mode of ``chain`` its
    ``modal_damping_ratio`` ζ_j: C = M·Φ·diag(2·ζ_j·ω_j)·Φᵀ·M with Φ mass-normalised (the
    rigid-body mode undamped). Zeros when the chain has no modal damping. Add it to
    :meth:`rotor.TorsionalChain.damping_matrix` for the whole damping of the chain.

    **Arguments:** ``chain``: a :class:`rotor.TorsionalChain`.
    """
    n = chain.size
    if chain.modal_damping_ratio is None:
        return array_module(chain.inertias_kgm2).zeros((n, n))
    return _modal_damping(chain.inertias_kgm2, chain.stiffness_matrix(), chain.modal_damping_ratio)


@kept_program()
@jax.jit  # one compiled call, not a dozen eager operations
def _modal_damping(inertias: Array, stiffness_matrix: Array, zeta: ArrayLike) -> Array:
    n = inertias.shape[0]
    lam, phi = _eigh(inertias, stiffness_matrix)
    omega = jnp.sqrt(jnp.clip(lam[1:], 0.0))
    c = jnp.concatenate([jnp.zeros(1), 2 * jnp.broadcast_to(zeta, (n - 1,)) * omega])
    MPhi = inertias[:, None] * phi
    return (MPhi * c[None, :]) @ MPhi.T


def _damped_modal(chain: TorsionalChain, undamped_hz: np.ndarray, shapes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Damped natural frequencies [Hz] and damping ratios [-] of each elastic mode (NaN where
    a mode is aperiodic) in modal coordinates: the damping's diagonal φᵀCφ on each mode's
    mass-normalised shape φ (``shapes``, (modes, n)), its coupling of the modes left out
    (exact for proportional damping). Costs (masses × modes): for long chains, whose
    state-space eigenproblem of 2n × 2n would take minutes."""
    n = chain.size
    wn = 2 * np.pi * np.asarray(undamped_hz, dtype=np.float64)
    c = np.zeros(wn.size)
    if chain.absolute_damping_Nms_per_rad is not None:
        c += (shapes**2) @ np.broadcast_to(np.asarray(chain.absolute_damping_Nms_per_rad, dtype=np.float64), (n,))
    if chain.relative_damping_Nms_per_rad is not None:
        rel = np.broadcast_to(np.asarray(chain.relative_damping_Nms_per_rad, dtype=np.float64), (n - 1,))
        c += (np.diff(shapes, axis=1) ** 2) @ rel
    zeta = c / (2 * wn)
    if chain.modal_damping_ratio is not None:
        zeta = zeta + np.broadcast_to(np.asarray(chain.modal_damping_ratio, dtype=np.float64), wn.shape)
    fd = np.where(zeta < 1, undamped_hz * np.sqrt(np.clip(1 - zeta**2, 0.0, None)), np.nan)
    return fd, np.where(zeta < 1, zeta, np.nan)


def _damped(chain: TorsionalChain, undamped_hz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Damped natural frequencies [Hz] and damping ratios [-] of each elastic mode (NaN where
    a mode is aperiodic), from the state-space eigenvalues."""
    import scipy.linalg

    n = chain.size
    J = np.asarray(chain.inertias_kgm2)
    K = np.asarray(chain.stiffness_matrix())
    C = np.asarray(chain.damping_matrix()) + np.asarray(modal_damping_matrix(chain))
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -K / J[:, None]
    A[n:, n:] = -C / J[:, None]
    lam = scipy.linalg.eigvals(A)
    scale = 2 * np.pi * float(np.max(undamped_hz))
    osc = lam[lam.imag > 1e-9 * scale]
    osc = osc[np.argsort(np.abs(osc))]
    fd = np.full(n - 1, np.nan)
    zeta = np.full(n - 1, np.nan)
    wn = 2 * np.pi * undamped_hz
    free = list(range(len(osc)))
    for j in np.argsort(wn):
        if not free:
            break
        best = min(free, key=lambda i: abs(abs(osc[i]) - wn[j]))
        free.remove(best)
        fd[j] = osc[best].imag / (2 * np.pi)
        zeta[j] = -osc[best].real / abs(osc[best])
    return fd, zeta


# ---------------------------------------------------------------------- Holzer
def holzer_residual(chain: TorsionalChain, frequency_hz: ArrayLike) -> np.ndarray:
    """Holzer's residual torque of ``chain`` at the trial frequencies ``frequency_hz`` [Hz]
    (any shape): the torque left beyond the last mass [N·m] when the front mass vibrates
    with an amplitude of 1 rad and no torque acts on it. Zero at 0 Hz and at each natural
    frequency (:mod:`rotor.torsion.modes`)."""
    f = np.asarray(frequency_hz, dtype=np.float64)
    residual, _ = _holzer(
        np.asarray(chain.inertias_kgm2), np.asarray(chain.stiffnesses_Nm_per_rad), (2 * np.pi * f) ** 2
    )
    return residual


def _holzer(J: np.ndarray, k: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residual torque and amplitudes (…, n) of the Holzer table at ω² = ``lam``."""
    lam = np.asarray(lam, dtype=np.float64)
    theta = np.empty(lam.shape + (len(J),))
    theta[..., 0] = 1.0
    torque = np.zeros_like(lam)
    for i in range(len(J)):
        torque = torque + lam * J[i] * theta[..., i]
        if i < len(k):
            theta[..., i + 1] = theta[..., i] - torque / k[i]
    return torque, theta


def holzer_shapes(chain: TorsionalChain, frequencies_hz: ArrayLike) -> np.ndarray:
    """The amplitudes of the Holzer table of ``chain`` at its natural frequencies
    ``frequencies_hz`` [Hz] (from :func:`holzer_frequencies`): the mode shapes, one row per
    frequency, scaled so that the largest amplitude is +1.

    A Holzer table is stable only where the amplitudes it passes on grow: an error in ω²
    takes over where the mode dies away. So the table is run from the front and from the
    back, and joined at the shaft where the two runs agree best on the ratio of its two
    masses' amplitudes (the forward run holds from the front up to the mode's swing, the
    backward run from the back down to it)."""
    J = np.asarray(chain.inertias_kgm2, dtype=np.float64)
    k = np.asarray(chain.stiffnesses_Nm_per_rad, dtype=np.float64)
    lam = np.atleast_1d((2 * np.pi * np.asarray(frequencies_hz, dtype=np.float64)) ** 2)
    _, forward = _holzer(J, k, lam)
    _, backward = _holzer(J[::-1], k[::-1], lam)
    backward = backward[:, ::-1]
    out = np.empty_like(forward)
    with np.errstate(all="ignore"):
        rf = forward[:, 1:] / forward[:, :-1]
        rb = backward[:, 1:] / backward[:, :-1]
        mismatch = np.abs(rf - rb) / (np.abs(rf) + np.abs(rb))
    mismatch = np.where(np.isfinite(mismatch), mismatch, np.inf)
    for j in range(len(lam)):
        p = int(np.argmin(mismatch[j]))  # join across shaft p: masses ≤ p forward, > p backward
        out[j, : p + 1] = forward[j, : p + 1] / forward[j, p]
        out[j, p + 1 :] = backward[j, p + 1 :] / backward[j, p]
    return _normalise_shapes(out)


def _sturm_count(J: np.ndarray, k: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """How many eigenvalues of (K, M) lie below each ω² in ``lam``: the negative pivots of
    the tridiagonal K − ω²·M (Sylvester's law of inertia)."""
    n = len(J)
    diag = np.zeros(n)
    diag[:-1] += k
    diag[1:] += k
    tiny = np.finfo(np.float64).tiny
    count = np.zeros(lam.shape, dtype=np.int64)
    u = diag[0] - lam * J[0]
    for i in range(n):
        if i:
            u = np.where(u == 0, tiny, u)
            u = diag[i] - lam * J[i] - k[i - 1] ** 2 / u
        count += u < 0
    return count


def holzer_frequencies(chain: TorsionalChain) -> np.ndarray:
    """The undamped natural frequencies of ``chain`` [Hz], ascending, without the rigid-body
    mode, by Holzer's transfer-matrix method (roots of :func:`holzer_residual`, each
    bracketed by Sturm-count bisection and refined by bisection on the residual's sign; see
    :mod:`rotor.torsion.modes`). Independent of the eigensolver.

    **Arguments:** ``chain``: a :class:`rotor.TorsionalChain`.

    **Raises:** :class:`rotor.SolverError` if a root cannot be bracketed (a chain whose
    numbers overflow the Holzer table).
    """
    J = np.asarray(chain.inertias_kgm2, dtype=np.float64)
    k = np.asarray(chain.stiffnesses_Nm_per_rad, dtype=np.float64)
    n = len(J)
    # Gershgorin bound on the eigenvalues of M⁻¹K
    row = np.zeros(n)
    row[:-1] += 2 * k
    row[1:] += 2 * k
    hi = np.full(n - 1, 1.01 * float(np.max(row / J)))
    lo = np.zeros(n - 1)
    want = np.arange(1, n)  # eigenvalue index (0 is the rigid-body mode)
    for _ in range(400):
        c_lo = np.where(lo > 0, _sturm_count(J, k, lo), 1)
        c_hi = _sturm_count(J, k, hi)
        done = (c_lo == want) & (c_hi == want + 1)
        if np.all(done):
            break
        mid = 0.5 * (lo + hi)
        c_mid = _sturm_count(J, k, mid)
        above = c_mid >= want + 1
        hi = np.where(done, hi, np.where(above, mid, hi))
        lo = np.where(done, lo, np.where(above, lo, mid))
    else:
        raise SolverError("holzer_frequencies: could not bracket every natural frequency (Sturm bisection)")
    total = float(np.sum(J))

    def deflated(x: np.ndarray) -> np.ndarray:
        """R(ω²)/ω²: the residual without its rigid-body root (ΣJ at ω² = 0)."""
        with np.errstate(all="ignore"):
            r = _holzer(J, k, x)[0] / np.where(x == 0, 1.0, x)
        return np.where(x == 0, total, r)

    ra, rb = deflated(lo), deflated(hi)
    bad = ~(np.isfinite(ra) & np.isfinite(rb)) | (ra * rb > 0)
    if np.any(bad):
        j = int(np.flatnonzero(bad)[0])
        raise SolverError(
            f"holzer_frequencies: the residual does not change sign around mode {j + 1} "
            f"({np.sqrt(lo[j]) / 2 / np.pi:.6g}…{np.sqrt(hi[j]) / 2 / np.pi:.6g} Hz): the Holzer table overflows"
        )
    # bisection on the residual's sign, every mode at once, to the last bit of ω²
    eps = np.finfo(np.float64).eps
    for _ in range(2100):
        if np.all(hi - lo <= 2 * eps * hi):
            break
        mid = 0.5 * (lo + hi)
        rm = deflated(mid)
        left = np.sign(rm) == np.sign(ra)
        lo, ra = np.where(left, mid, lo), np.where(left, rm, ra)
        hi = np.where(left, hi, mid)
    return np.sqrt(0.5 * (lo + hi)) / (2 * np.pi)


# ---------------------------------------------------------------------- the result
@dataclass(frozen=True, eq=False, repr=False)
class TorsionalModes(Result):
    """The free torsional vibration of a chain (:func:`rotor.torsional_modes`).

    **Attributes** (modes are the n − 1 elastic ones, lowest first; masses from the front):

    - ``name``: the engine's name or ``"chain"``; ``method``: ``"eigen"`` or ``"holzer"``.
    - ``mass_names`` (n,); ``inertias_kgm2`` (n,) [kg·m²], the throws with their
      mechanisms' cycle mean for an engine; ``stiffnesses_Nm_per_rad`` (n − 1,) [N·m/rad].
    - ``natural_frequencies_hz`` (n − 1,) [Hz]: undamped, without the rigid-body mode.
    - ``mode_shapes`` (n − 1, n) [-]: one row per mode, scaled so that the largest amplitude
      is +1.
    - ``participation`` (n − 1, n) [-]: each mass's share of the mode's kinetic energy,
      J_i·φ_i²/Σ J·φ² (which masses swing in the mode; each row sums to 1).
    - ``strain_energy_share`` (n − 1, n − 1) [-]: each shaft's share of the mode's strain
      energy, k_i·(φ_{i+1} − φ_i)²/Σ (where the mode twists the shaft: its nodes).
    - ``modal_inertias_kgm2`` (n − 1,) [kg·m²]: φᵀ·M·φ with these shapes.
    - ``damped_frequencies_hz``, ``damping_ratios`` (n − 1,) [Hz, -], or ``None`` without
      damping; NaN (``null`` in JSON) for a mode that damping makes aperiodic.
    - ``frequency_min_hz``, ``frequency_max_hz`` (n − 1,) [Hz]: for an engine, each
      mode's lowest and highest frequency as the mechanisms' inertia varies over a
      revolution; ``None`` for a bare chain.
    - ``throw_masses`` (0-based), ``load_mass`` (0-based).
    - ``rpm`` [rev/min] or ``None``; ``resonant_orders`` (n − 1,) [-]: the engine order
      each mode resonates with at ``rpm``, f·60/rpm (``None`` without ``rpm``).
    """

    name: str
    method: str
    mass_names: tuple[str, ...]
    inertias_kgm2: np.ndarray
    stiffnesses_Nm_per_rad: np.ndarray
    natural_frequencies_hz: np.ndarray
    mode_shapes: np.ndarray
    participation: np.ndarray
    strain_energy_share: np.ndarray
    modal_inertias_kgm2: np.ndarray
    damped_frequencies_hz: np.ndarray | None
    damping_ratios: np.ndarray | None
    frequency_min_hz: np.ndarray | None
    frequency_max_hz: np.ndarray | None
    throw_masses: tuple[int, ...]
    load_mass: int
    rpm: float | None

    @property
    def resonant_orders(self) -> np.ndarray | None:
        """f·60/rpm for each mode [-], or ``None`` without ``rpm``."""
        if self.rpm is None:
            return None
        return self.natural_frequencies_hz * 60.0 / self.rpm

    @property
    def mode_count(self) -> int:
        """The number of elastic modes, n − 1."""
        return int(len(self.natural_frequencies_hz))

    def nodes(self, mode: int) -> list[int]:
        """The shafts (0-based) in which mode ``mode`` (1-based) has a node: the amplitude
        changes sign along them."""
        phi = self.mode_shapes[require_whole(mode, "TorsionalModes.nodes(mode)") - 1]
        return [i for i in range(len(phi) - 1) if phi[i] * phi[i + 1] < 0 or (phi[i + 1] == 0 and i + 2 < len(phi))]

    def summary(self) -> str:
        n = len(self.mass_names)
        lines = [
            f"Torsional modes of {self.name}: {n} masses, {self.mode_count} elastic modes ({self.method})",
        ]
        head = f"  {'mode':>4} {'f [Hz]':>10} {'nodes in shaft':>15}"
        if self.damped_frequencies_hz is not None:
            head += f" {'f_d [Hz]':>10} {'zeta':>7}"
        if self.frequency_min_hz is not None:
            head += f" {'f over cycle [Hz]':>21}"
        if self.rpm is not None:
            head += f" {'order':>6}"
        head += "  most energy in"
        lines.append(head)
        shown = min(self.mode_count, 40)
        for j in range(shown):
            nodes = ",".join(str(i + 1) for i in self.nodes(j + 1)) or "-"
            row = f"  {j + 1:>4} {self.natural_frequencies_hz[j]:10.2f} {nodes:>15}"
            if self.damped_frequencies_hz is not None and self.damping_ratios is not None:
                fd, z = self.damped_frequencies_hz[j], self.damping_ratios[j]
                row += f" {fd:10.2f} {z:7.4f}" if np.isfinite(fd) else f" {'aperiodic':>10} {'':>7}"
            if self.frequency_min_hz is not None and self.frequency_max_hz is not None:
                row += f" {self.frequency_min_hz[j]:10.2f}…{self.frequency_max_hz[j]:<10.2f}"
            orders = self.resonant_orders
            if orders is not None:
                row += f" {orders[j]:6.2f}"
            row += f"  {self.mass_names[int(np.argmax(self.participation[j]))]}"
            lines.append(row)
        if shown < self.mode_count:
            lines.append(f"  … {self.mode_count - shown} more modes (to_pandas() lists them all)")
        total = float(np.sum(self.inertias_kgm2))
        lines.append(f"  total inertia {total:.5g} kg·m²; shafts numbered from the front (shaft i joins masses i, i+1)")
        if self.rpm is not None:
            lines.append(f"  order = the engine order that excites each mode at {self.rpm:g} rpm (f·60/rpm)")
        if self.frequency_min_hz is not None:
            lines.append("  f over cycle: lowest…highest frequency as the rods' and pistons' inertia varies with θ")
        return "\n".join(lines)

    def to_pandas(self) -> Any:
        """One row per mode and mass: ``mode``, ``frequency_hz``, ``mass``, ``mass_name``,
        ``amplitude`` [-], ``participation`` [-] (and the damped and over-cycle columns where
        known)."""
        import pandas as pd

        n = len(self.mass_names)
        rows = []
        for j in range(self.mode_count):
            for i in range(n):
                row: dict[str, Any] = {
                    "mode": j + 1,
                    "frequency_hz": float(self.natural_frequencies_hz[j]),
                    "mass": i + 1,
                    "mass_name": self.mass_names[i],
                    "inertia_kgm2": float(self.inertias_kgm2[i]),
                    "amplitude": float(self.mode_shapes[j, i]),
                    "participation": float(self.participation[j, i]),
                }
                if self.damped_frequencies_hz is not None and self.damping_ratios is not None:
                    row["damped_frequency_hz"] = float(self.damped_frequencies_hz[j])
                    row["damping_ratio"] = float(self.damping_ratios[j])
                if self.frequency_min_hz is not None and self.frequency_max_hz is not None:
                    row["frequency_min_hz"] = float(self.frequency_min_hz[j])
                    row["frequency_max_hz"] = float(self.frequency_max_hz[j])
                rows.append(row)
        return pd.DataFrame(rows)

    def to_json_dict(self) -> dict:
        """The fields as plain JSON (``null`` for what is not known)."""
        return json_safe(
            {
                "name": self.name,
                "method": self.method,
                "mass_names": list(self.mass_names),
                "inertias_kgm2": self.inertias_kgm2,
                "stiffnesses_Nm_per_rad": self.stiffnesses_Nm_per_rad,
                "natural_frequencies_hz": self.natural_frequencies_hz,
                "mode_shapes": self.mode_shapes,
                "participation": self.participation,
                "strain_energy_share": self.strain_energy_share,
                "modal_inertias_kgm2": self.modal_inertias_kgm2,
                "damped_frequencies_hz": self.damped_frequencies_hz,
                "damping_ratios": self.damping_ratios,
                "frequency_min_hz": self.frequency_min_hz,
                "frequency_max_hz": self.frequency_max_hz,
                "throw_masses": list(self.throw_masses),
                "load_mass": self.load_mass,
                "rpm": self.rpm,
                "resonant_orders": self.resonant_orders,
            }
        )

    def plot(self, ax: Any = None, modes: int | None = None) -> Any:
        """Draw the mode shapes (the first ``modes``, default up to 4) over the masses, one
        Axes per mode (``ax``: that many Axes, or one Axes for all, or None for a new figure).

        **Returns:** the Axes (an array of them for several modes).
        """
        from ..plotting.torsion import plot_mode_shapes

        count = min(self.mode_count, 4 if modes is None else require_whole(modes, "TorsionalModes.plot(modes)"))
        return plot_mode_shapes(
            self.mass_names,
            self.mode_shapes[:count],
            self.natural_frequencies_hz[:count],
            f"{self.name}: torsional modes",
            throw_masses=self.throw_masses,
            ax=ax,
        )


# ---------------------------------------------------------------------- the analysis
def chain_of(chain_or_engine: Any, call: str) -> tuple[TorsionalChain, Engine | None]:
    """``(chain, engine)`` from a :class:`rotor.TorsionalChain` (engine ``None``) or a
    :class:`rotor.Engine` with a ``[torsion]`` table (:func:`rotor.torsional_chain`);
    ``call`` names the function in a :class:`TypeError` for anything else."""
    if isinstance(chain_or_engine, TorsionalChain):
        return chain_or_engine, None
    if isinstance(chain_or_engine, Engine):
        chain_or_engine.check()
        return torsional_chain(chain_or_engine), chain_or_engine
    hint = " (load it first: rotor.load_engine(...))" if isinstance(chain_or_engine, (str, bytes)) else ""
    raise TypeError(
        f"{call}: expected a rotor.TorsionalChain or a rotor.Engine{hint}, got {what_it_is(chain_or_engine)}"
    )


_spread = kept_program()(jax.jit(jax.vmap(_natural_frequencies_hz, in_axes=(0, None))))

EXACT_SPREAD_MASSES = 32
"""Chains of up to this many masses have their frequencies' range over the crank angle from
dense eigenproblems, compiled; longer ones from tridiagonal ones (see :func:`frequency_spread`)."""
MAX_MODE_MASSES = 2000
"""The most masses whose modes are computed: one dense eigenproblem of n × n takes about
4 s for 1000 masses on a 2-core machine and grows as n³ (an hour for 10⁴)."""
SECONDS_PER_EIGH_1000 = 4.0
"""Seconds of one dense symmetric eigenproblem of 1000 × 1000 with its vectors (2-core CPU),
for the time a refused chain would have taken."""


def check_mode_size(n: int, call: str) -> None:
    """Refuse, before any work, a chain of more than :data:`MAX_MODE_MASSES` masses, in one
    line naming the ``[torsion]`` table, with the time it would take and the memory."""
    if n <= MAX_MODE_MASSES:
        return
    seconds = SECONDS_PER_EIGH_1000 * (n / 1000) ** 3
    took = f"{seconds / 60:.0f} minutes" if seconds < 5400 else f"{seconds / 3600:.1f} hours"
    raise EngineError(
        f"{call}: the [torsion] table's chain has {n} masses: its modes are a dense eigenproblem of "
        f"{n} × {n} ({8 * n * n / 1e9:.2g} GB, about {took}); at most {MAX_MODE_MASSES} masses: lump the "
        "chain into fewer masses (a few per crank throw are enough for its lower modes)"
    )


def spread_points(n: int, points: int = 360) -> int:
    """The crank angles at which a chain of ``n`` masses is solved for its frequencies' range:
    ``points`` up to 100 masses, fewer above (36 at least), so that the work, angles × n²,
    stays about that of 100 masses at 360 angles."""
    return points if n <= 100 else max(36, min(points, int(points * 100 / n)))


def _tridiagonal_spread(engine: Engine, points: int) -> tuple[np.ndarray, np.ndarray]:
    """(f_min, f_max) [Hz] of each mode over ``points`` crank angles, each angle's
    eigenproblem taken as what it is, tridiagonal (J^(-1/2)·K·J^(-1/2)): all its eigenvalues
    in n² operations (LAPACK's ``sterf``), not a dense n³ one."""
    from scipy.linalg import eigvalsh_tridiagonal

    theta = jnp.linspace(0.0, 2 * jnp.pi, points, endpoint=False)
    J = np.asarray(mass_inertias(engine, theta), dtype=np.float64)  # (points, n)
    k = np.asarray(engine.torsion.stiffnesses_Nm_per_rad, dtype=np.float64)  # type: ignore[union-attr]
    diag = np.zeros(J.shape[1])
    diag[:-1] += k
    diag[1:] += k
    f = np.empty((points, J.shape[1] - 1))
    for i, j in enumerate(J):
        lam = eigvalsh_tridiagonal(diag / j, -k / np.sqrt(j[:-1] * j[1:]), lapack_driver="sterf")
        f[i] = np.sqrt(np.clip(lam[1:], 0.0, None)) / (2 * np.pi)
    return f.min(axis=0), f.max(axis=0)


def frequency_spread(engine: Engine, points: int = 360) -> tuple[np.ndarray, np.ndarray]:
    """Each elastic mode's lowest and highest natural frequency [Hz] over one revolution of
    ``engine`` (its ``[torsion]`` chain with every mass's inertia at each of ``points``
    crank angles, :func:`rotor.torsion.model.mass_inertias`). Sorted by frequency at every
    angle, so the n-th lowest is compared with the n-th lowest.

    A chain of up to :data:`EXACT_SPREAD_MASSES` masses solves its eigenproblems at all
    angles at once (compiled); a longer one solves each angle's as the tridiagonal problem it
    is, at :func:`spread_points` angles (36 at least: the range is then short of the
    true one by a fraction of a percent of its width), so that 1000 masses take seconds.

    **Returns:** ``(f_min, f_max)``, each (n − 1,) [Hz].
    """
    points = require_whole(points, "frequency_spread(points)", lo=4)
    n = int(np.size(engine.torsion.inertias_kgm2)) if engine.torsion is not None else 0
    if n > EXACT_SPREAD_MASSES:
        check_mode_size(n, "frequency_spread(engine)")
        return _tridiagonal_spread(engine, spread_points(n, points))
    theta = np.linspace(0.0, 2 * np.pi, points, endpoint=False)
    J = mass_inertias(engine, theta)
    f = np.asarray(_spread(J, engine.torsion.stiffnesses_Nm_per_rad))  # type: ignore[union-attr]
    return f.min(axis=0), f.max(axis=0)


def torsional_modes(
    chain_or_engine: TorsionalChain | Engine,
    *,
    rpm: float | None = None,
    method: str = "eigen",
) -> TorsionalModes:
    """The natural frequencies and mode shapes of a torsional chain or an engine's chain.

    **Arguments:**

    - ``chain_or_engine``: a :class:`rotor.TorsionalChain`, or a :class:`rotor.Engine` with a
      ``[torsion]`` table (its chain with the rods' and pistons' cycle-mean inertia on the
      throws, :func:`rotor.torsional_chain`; the result then also gives each frequency's
      range over the crank angle).
    - ``rpm``: an engine speed [rev/min] at which to say which engine order excites each
      mode (``resonant_orders``); default the engine's ``[operating] rpm``, none for a chain.
    - ``method``: ``"eigen"`` (the symmetric eigenproblem, default) or ``"holzer"`` (Holzer's
      transfer-matrix method; the mode shapes are then the Holzer amplitudes,
      :func:`holzer_shapes`).

    **Returns:** a :class:`TorsionalModes`; ``natural_frequencies_hz`` lists the undamped
    natural frequencies ascending, without the rigid-body mode.

    **Raises:** :class:`rotor.EngineError` for an engine without a ``[torsion]`` table or
    a bad argument; :class:`TypeError` for an argument of the wrong type.
    """
    chain, engine = chain_of(chain_or_engine, "torsional_modes(chain_or_engine)")
    if method not in _METHODS:
        raise EngineError(f"torsional_modes(method = {method!r}): one of {', '.join(map(repr, _METHODS))}")
    if rpm is not None:
        rpm = check_speed_rpm(rpm, "torsional_modes(rpm)")
    elif engine is not None:
        rpm = float(engine.operating.rpm)
    J = np.asarray(chain.inertias_kgm2, dtype=np.float64)
    k = np.asarray(chain.stiffnesses_Nm_per_rad, dtype=np.float64)
    check_mode_size(J.size, "torsional_modes(chain_or_engine)")
    phi_raw = None
    if method == "eigen":
        f_j, phi_j = _modal_jit(chain.inertias_kgm2, chain.stiffnesses_Nm_per_rad)
        phi_raw = np.asarray(phi_j)
        f, shapes = np.asarray(f_j), _normalise_shapes(phi_raw)
    else:
        f = holzer_frequencies(chain)
        shapes = holzer_shapes(chain, f)
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(shapes))):
        raise SolverError(f"torsional_modes: the {method} analysis gave non-finite frequencies or shapes")
    kinetic = J[None, :] * shapes**2
    modal_inertias = kinetic.sum(axis=1)
    participation = kinetic / modal_inertias[:, None]
    strain = k[None, :] * np.diff(shapes, axis=1) ** 2
    strain_share = strain / strain.sum(axis=1, keepdims=True)
    fd = zeta = None
    if chain.has_damping and phi_raw is not None and J.size > EXACT_SPREAD_MASSES:
        fd, zeta = _damped_modal(chain, f, phi_raw)  # a long chain: in modal coordinates
    elif chain.has_damping:
        fd, zeta = _damped(chain, f)
    fmin = fmax = None
    if engine is not None:
        fmin, fmax = frequency_spread(engine)
    return TorsionalModes(
        name=engine.name if engine is not None else "chain",
        method=method,
        mass_names=tuple(chain.names),
        inertias_kgm2=J,
        stiffnesses_Nm_per_rad=k,
        natural_frequencies_hz=f,
        mode_shapes=shapes,
        participation=participation,
        strain_energy_share=strain_share,
        modal_inertias_kgm2=modal_inertias,
        damped_frequencies_hz=fd,
        damping_ratios=zeta,
        frequency_min_hz=fmin,
        frequency_max_hz=fmax,
        throw_masses=tuple(chain.throw_masses),
        load_mass=int(chain.load_mass),
        rpm=rpm,
    )
