"""TDC from crank speed alone: where the engine's own speed signature lies on the wheel.

A new installation's angle from the wheel's gap to TDC is rarely known, and one copied
from another bench (a preset's calibration) can be off by anything. Compression and
expansion leave a phase signature in every revolution's speed, motored or fired: the
crank slows into each compression and speeds up after it, and a firing revolution
differs from the gas-exchange one. :func:`tdc_from_speed` finds it by fitting the
engine's own simulated speed signature against the measured speed at every candidate
offset, the idea of the speed-based TDC and combustion diagnosis of Taraza et al.
("Determining the top dead centre of an engine from crankshaft speed") and Rizzoni
("Estimate of indicated torque from crankshaft speed fluctuations: a model for the
dynamics of the IC engine", IEEE Trans. Vehicular Technology, 1989):

1. **The signature**: two periodic steady states of the engine at the recording's mean
   speed (:func:`rotor.steady_state`, one compiled solve for both): the fired cycle and
   the motored one (combustion scale 0). Their harmonics up to ``max_order`` (default
   4 per revolution: a bench's coupling resonance lies above, see
   :mod:`rotor.diagnostics.calibration`) are the shapes *combustion* (fired − motored)
   and *motored* (compression, expansion and the reciprocating inertia's ripple).
2. **The fit**: for every candidate offset d (0.25° steps over the whole cycle, 720° for
   a four-stroke, so the firing revolution is chosen too) and every cycle k, the cycle's
   detrended harmonics (:func:`rotor.cycles.cycle_spectrum`) are fitted by
   a_k·combustion + b_k·motored shifted by d, with a_k, b_k ≥ 0 (non-negative least
   squares): each cycle is free to fire or not (an ignition cut, a coast-down) and to
   fire harder or softer, but never with its sign turned (which would let a signature
   half a period off fit as well). The offset minimises the residual summed over the
   cycles, refined between grid points by a parabola.
3. **How sure**: ``std_deg``, one standard deviation [deg], holds two parts.
   ``std_statistical_deg``: the offset's spread over :data:`BOOTSTRAP` resamples of the
   cycles (Efron's bootstrap; where fewer than three cycles, the fit's curvature,
   2σ²/S″), or the cycles' own offsets' spread (1.4826 times their median absolute
   deviation, over √cycles), whichever is larger: noise and cycle-to-cycle variation.
   ``std_model_deg``: the engine model's own error, which no cycle shows apart from the
   others — a jackknife over the fitted harmonics (each left out in turn: where the
   signature describes the speed they all put TDC in the same place), times
   :data:`MODEL_STD_FACTOR`. ``std_deg`` is their root sum of squares. ``separation``:
   how many σ of the residual's noise the best offset outside ±:data:`ALTERNATIVE_DEG` of
   it lies worse, √((S_alt − S)/σ²). The offset is **determined** where the signature
   explains at least :data:`R2_MIN` of the speed's fluctuation up to ``max_order``, the
   separation reaches :data:`SEPARATION_MIN`, the signature has more numbers a cycle than
   the fit has free parameters (alike cylinders up to order 4 have not: then ``std_deg``
   is that of an offset anywhere in the firing interval), and ±3σ does not span the
   whole period; otherwise ``determined`` is False and ``reason`` says why.
4. **The charge**: a throttled spark-ignition engine's motored speed does not scale
   with its combustion (intake and compression pressures fall with the charge, exhaust
   and crankcase pressures do not); a Wiebe engine's signature is taken at the charge
   that explains the speed best (``charge_scale``, :data:`CHARGE_SCALES`). With the file's
   full charge, an idling recording at a quarter of it put TDC 15° early.
5. **Alike cylinders**: an engine of several evenly firing cylinders repeats its
   signature every firing interval, and the speed cannot tell cylinder 1 from the
   others: shifts under which the signature matches itself (R² above
   :data:`SYMMETRY_R2`) are equivalent (``period_deg``), the offset is given modulo
   them, the one nearest ``prior_deg`` (e.g. a calibration's) reported.

**Accuracy** (``benchmarks/tdc_from_speed.py``: simulated tue-single recordings at
3000 rpm through a 60-2 wheel, the wheel's gap moved 0/30/90/180°, steady, with an
ignition cut or coasting down, tooth times or the raw analog signal; ``tests/diagnostics/test_tdc_from_speed.py``
holds its records under 1°): worst 0.6° steady, 0.4° coasting down, 1.2° with an ignition
cut of two cycles (the cut's transient is not the steady signature).

**Is the σ honest** (``benchmarks/tdc_coverage.py``, 240 simulated records over the four
presets, 0.45–1.3 times their speed, loads 0.25–1, cycle-to-cycle variation, 20 ns–1 µs
of timer jitter, tooth errors 0–0.3°, the wheels 60-2, 60-1, 36-1 and 36-2-1;
``tests/diagnostics/test_tdc_coverage.py`` holds a smaller matrix to a binomial bound): see the table
in ``benchmarks/README.md``. The real single-cylinder bench recordings (speed only, against the
pressure channel's polytropic-fit TDC of 29.4°, 30.7°, 28.9°): the speed puts TDC 7°
later at full load, 11° at half load and 19° at no load (R² 0.97 / 0.94 / 0.80): the
engine file's Wiebe cycle is not the engine's at part load, and the harmonics say so —
σ 2.9°, 4.5° and 8.5°, nearly all of it the model's, so the pressure's TDC lies 2.2–2.5σ
from the speed's. That bias follows the model term: κ = bias / model term came out 2.41,
2.61 and 2.36. A calibration measures κ on its recordings (:class:`TdcBias`), and
:func:`check_tdc` with it compares the given TDC with the speed's less κ times the model
term, within σ = √(scatter² + (σ_κ·model term)² + min(|bias|, 1°)²): calibrated on one of
the three, the others' speed TDC less the bias lay 0.3–2.1° from their pressure TDC, and a
right calibration agrees at most 3.9° apart (at 1.2σ) where it agreed 17° apart before.
So the speed corrects a gross error (another installation's mounting, a wrong firing
revolution) but does not replace a pressure channel; :func:`check_tdc` says "agrees" within
:data:`AGREE_SIGMA` σ and "disagrees" beyond, as a :class:`TdcVerdict`. Where the engine
has no steady state at the record's mean speed (a cranking, a coast-down to a stop) there
is no signature to fit: :class:`NoSignature`.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from ..cycles import cycle_spectrum
from ..errors import LogError, NoSteadyStateError
from ..logs.analysis import LogAnalysis
from ..logs.wheel import ToothErrors
from ..results import Result, json_safe
from ..units import RPM_PER_RAD_S

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = [
    "SpeedTdc",
    "TdcNotDetermined",
    "NoSignature",
    "tdc_from_speed",
    "R2_MIN",
    "SEPARATION_MIN",
    "ALTERNATIVE_DEG",
    "SYMMETRY_R2",
    "AGREE_DEG",
    "DEFAULT_MAX_ORDER",
    "CONTRADICT_RATIO",
    "TOOTH_MISMATCH",
    "TdcCheck",
    "TdcVerdict",
    "AGREE_SIGMA",
    "check_tdc",
    "residual_at",
    "tooth_error_mismatch",
    "engine_signature",
    "TdcBias",
    "KAPPA_REL",
    "tdc_bias_of",
    "BIAS_LEFT_DEG",
    "BIAS_FIRING_MIN",
]

R2_MIN = 0.5
"""The signature must explain at least this fraction of the speed's fluctuation [-]."""
SEPARATION_MIN = 5.0
"""… and the best offset must beat every other (more than :data:`ALTERNATIVE_DEG` away) by
this many standard deviations of the residual's noise [-]."""
ALTERNATIVE_DEG = 30.0
"""Offsets this far from the best [deg] count as alternatives."""
SYMMETRY_R2 = 0.98
"""A shift under which the engine's signature explains itself this well is one the speed
cannot tell apart (alike cylinders) [-]."""
AGREE_DEG = 10.0
"""Formerly the distance [deg] within which a TDC (a calibration's) was kept; the verdict
now rests on the stated σ (:data:`AGREE_SIGMA`). Kept for code that reads it."""
DEFAULT_MAX_ORDER = 4.0
STEP_DEG = 0.25
TWO_PI = 2.0 * math.pi


class TdcNotDetermined(LogError):
    """The recording's speed cannot determine TDC (or cannot check a given one)."""


class NoSignature(TdcNotDetermined):
    """The engine has no steady state at the recording's mean speed (a cranking, a coast-down
    to a stop): no speed signature to fit, so TDC can be neither found nor checked."""


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class SpeedTdc(Result):
    """What :func:`tdc_from_speed` found (see the module doc).

    **Fields:** ``offset_deg``: from the start of the speed's cycle grid to cylinder 1's TDC
    at the start of intake [deg], in [0, cycle); ``tdc_after_gap_deg``: from the wheel's gap
    to cylinder 1's TDC [deg] in [0, 360) and ``firing_parity`` (0 or 1, as
    :func:`rotor.analyze_log`'s ``firing``), for a :class:`rotor.LogAnalysis` (None for a
    plain array); ``std_deg``: one standard deviation [deg], the root sum of squares of
    ``std_statistical_deg`` (the cycles' scatter) and ``std_model_deg`` (the engine model's
    own error; see the module doc); ``charge_scale``: the charge at which a Wiebe engine's
    signature fits best (1 = the file's; 1 for other pressure sources) [-]; ``separation``: the best
    alternative's distance [σ]; ``alternative_deg``: that alternative's ``offset_deg``;
    ``r2``: fraction of the fluctuation the signature explains [-]; ``determined`` and
    ``reason``; ``period_deg``: the shift under which the signature repeats (alike
    cylinders; the cycle's length when it does not); ``cycles``; per cycle
    ``cycle_offset_deg`` (each cycle's own best offset) and ``cycle_combustion``
    (its combustion amplitude a_k, 1 = the engine file's) [-]; ``candidates_deg`` and
    ``residual`` (the summed residual at each candidate, over the total power) for the plot;
    ``mean_rpm``; ``max_order``.
    """

    offset_deg: float
    tdc_after_gap_deg: float | None
    firing_parity: int | None
    std_deg: float
    separation: float
    alternative_deg: float
    r2: float
    determined: bool
    reason: str
    period_deg: float
    cycle_deg: float
    cycles: int
    cycle_offset_deg: np.ndarray
    cycle_combustion: np.ndarray
    candidates_deg: np.ndarray
    residual: np.ndarray
    mean_rpm: float
    max_order: float
    source: str = ""
    firing_tdc_wheel_deg: float | None = None
    std_statistical_deg: float = float("nan")
    std_model_deg: float = float("nan")
    charge_scale: float = 1.0

    def parity_for(self, tdc_deg: float) -> int | None:
        """The firing parity (as :func:`rotor.analyze_log`'s ``firing``) that puts firing TDC,
        at ``tdc_deg`` [deg] after the gap, nearest this fit's firing TDC (None for a
        two-stroke or a plain array)."""
        if self.firing_tdc_wheel_deg is None or self.cycle_deg < 719.0:
            return None
        return int(round((self.firing_tdc_wheel_deg - float(tdc_deg)) / 360.0)) % 2

    def summary(self) -> str:
        """A few lines: the offset, how sure, and why not where it is not determined."""
        where = (
            f"TDC {self.tdc_after_gap_deg:.1f}° after the gap (firing parity {self.firing_parity})"
            if self.tdc_after_gap_deg is not None
            else f"TDC {self.offset_deg:.1f}° after the grid's start"
        )
        lines = [
            f"TDC from the speed{' of ' + self.source if self.source else ''}: {where}, ± {self.std_deg:.2f}° (1σ: "
            f"{self.std_statistical_deg:.2f}° the cycles' scatter, {self.std_model_deg:.2f}° the engine model); "
            f"R² {self.r2:.3f}, next best offset {self.separation:.1f} σ worse ({self.cycles} cycles, "
            f"{self.mean_rpm:.0f} rpm)",
        ]
        if self.period_deg < self.cycle_deg - 1e-9:
            lines.append(
                f"  the engine's signature repeats every {self.period_deg:g}°: the offset is known modulo it "
                f"(cylinder 1 cannot be told from the others by the speed)"
            )
        if not self.determined:
            lines.append(f"  not determined: {self.reason}")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle: ``cycle``, ``offset_deg`` (its own best offset) and
        ``combustion`` (its fitted combustion amplitude, 1 = the engine file's) [-]."""
        import pandas as pd

        return pd.DataFrame(
            {
                "cycle": np.arange(1, self.cycles + 1),  # counted from 1
                "offset_deg": self.cycle_offset_deg,
                "combustion": self.cycle_combustion,
            }
        )

    def to_json_dict(self) -> dict:
        """The offset, how sure, per cycle figures; ``None``, never NaN."""
        return json_safe(
            {
                "offset_deg": self.offset_deg,
                "tdc_after_gap_deg": self.tdc_after_gap_deg,
                "firing_parity": self.firing_parity,
                "std_deg": self.std_deg,
                "std_statistical_deg": self.std_statistical_deg,
                "std_model_deg": self.std_model_deg,
                "charge_scale": self.charge_scale,
                "separation_sigma": self.separation,
                "alternative_deg": self.alternative_deg,
                "r2": self.r2,
                "determined": self.determined,
                "reason": self.reason,
                "period_deg": self.period_deg,
                "cycles": self.cycles,
                "cycle_offset_deg": self.cycle_offset_deg,
                "cycle_combustion": self.cycle_combustion,
                "mean_rpm": self.mean_rpm,
                "max_order": self.max_order,
                "source": self.source,
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The fit's residual (over the fluctuation's power) against the candidate offset,
        the best one marked, on ``ax`` (or a new figure)
        (:func:`rotor.plotting.diagnostics.plot_speed_tdc`). Returns the Axes."""
        return self._plot(ax, None)

    def _plot(self, ax: Any, given_deg: float | None) -> Any:
        from ..plotting.diagnostics import plot_speed_tdc

        return plot_speed_tdc(
            candidates_deg=self.candidates_deg,
            residual=self.residual,
            offset_deg=self.offset_deg,
            std_deg=self.std_deg,
            r2=self.r2,
            cycle_deg=self.cycle_deg,
            given_deg=given_deg,
            ax=ax,
        )


def _harmonics(omega_cycle: np.ndarray, K: int) -> np.ndarray:
    """Harmonics 1 … K of one periodic cycle sampled uniformly (ω ≈ mean + Σ Re(c_m e^{imψ}))."""
    P = omega_cycle.size
    return np.fft.rfft(omega_cycle)[1 : K + 1] * (2.0 / P)


def engine_signature(engine: Engine, rpm: float, harmonics: int, imep_scale: float = 1.0) -> np.ndarray:
    """The engine's speed signature at time-mean speed ``rpm`` [rpm]: (3, harmonics)
    complex harmonics [rad/s] of one cycle, cycle angle 0 at cylinder 1's TDC at the start
    of intake, in the convention ω(ψ) ≈ mean + Σ Re(c_m·e^{imψ/r}) (r revolutions per
    cycle): the combustion part (fired − motored steady state, the fired one at
    ``imep_scale``, :func:`rotor.steady_state`'s), the gas part of the motored
    speed (compression and expansion), and the reciprocating masses' ripple
    (ω ∝ I(θ)^(−1/2) at constant kinetic energy)."""
    from ..dynamics.steady import steady_state
    from ..engine.inertia import reduced_inertia

    fired_ss = steady_state(engine, rpm, imep_scale=imep_scale)
    fired = np.asarray(fired_ss.omega, dtype=np.float64)
    motored = np.asarray(steady_state(engine, rpm, imep_scale=0.0).omega, dtype=np.float64)
    theta = np.asarray(fired_ss.theta, dtype=np.float64)
    inv = 1.0 / np.sqrt(np.asarray(reduced_inertia(engine, theta), dtype=np.float64))
    ripple = np.mean(motored) * inv / np.mean(inv)
    return np.stack(
        [
            _harmonics(fired - motored, harmonics),
            _harmonics(motored - ripple, harmonics),
            _harmonics(ripple, harmonics),
        ]
    )


def _nnls_explained(r: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """max over β ≥ 0 of 2β·r − βᵀGβ (the residual's decrease), for r (..., n) and G (n, n),
    by trying every support (n ≤ 3). Returns (explained (...), β (..., n))."""
    n = G.shape[0]
    best = np.zeros(r.shape[:-1])
    beta = np.zeros(r.shape)
    for mask in range(1, 2**n):
        S = [i for i in range(n) if mask >> i & 1]
        Gs = G[np.ix_(S, S)]
        if abs(np.linalg.det(Gs)) < 1e-300:
            continue
        b = r[..., S] @ np.linalg.inv(Gs).T
        ok = np.all(b >= 0, axis=-1)
        ex = np.sum(b * r[..., S], axis=-1)
        take = ok & (ex > best)
        best = np.where(take, ex, best)
        full = np.zeros(r.shape)
        full[..., S] = b
        beta = np.where(take[..., None], full, beta)
    return best, beta


def _circ(x, period):
    """x wrapped into [−period/2, period/2)."""
    return (np.asarray(x) + period / 2) % period - period / 2


CHARGE_SCALES = (1.0, 0.7, 0.5, 0.35, 0.25, 0.18, 0.13, 0.09)
"""The charge scales [-] (intake pressure and IMEP × σ, a throttle) at which a Wiebe engine's
signature is tried, from the file's own down while the fit improves. Never above the
file's: an ignition cut's transient fits a boost marginally better, and puts TDC further
off."""
INFORMATIVE = 1e-4
"""A harmonic carries the signature where it holds more than this fraction of its power [-]."""
COARSE = 4
"""The charge search and the jackknife fit on every this-many-th candidate offset (1°), the
minimum refined by a parabola."""
BOOTSTRAP = 200
"""Bootstrap resamples of the cycles for the statistical part of ``std_deg``."""
MODEL_STD_FACTOR = 0.6
"""The model term of ``std_deg`` is this many times the harmonics' jackknife spread [-]:
calibrated so that the true TDC lies within ±1σ in about two thirds of the simulated records
of ``benchmarks/tdc_coverage.py`` that the speed determines (1.0 covered 90 %); the real
single-cylinder bench recordings' pressure TDC then lies 2.2–2.5σ from the speed's."""


def _shape_fit(B: np.ndarray, Y: np.ndarray, E: np.ndarray, power: np.ndarray) -> tuple:
    """The fit of every cycle's harmonics ``Y`` (C, K) by the shapes ``B`` (n, K) shifted by
    every candidate (``E`` (K, D)): (B, explained (C, D), β (C, D, n), summed residual (D,))."""
    G = np.real(B @ B.conj().T)
    # r[k, d, j] = Re Σ_m Y_km · conj(B_jm) · e^{imd/revs}: the fit of cycle k's harmonics by shape j shifted by d
    r = np.stack([np.real((Y * B[j].conj()[None, :]) @ E) for j in range(B.shape[0])], axis=-1)  # (C, D, n)
    explained, beta = _nnls_explained(r, G)
    return B, explained, beta, np.sum(power[:, None] - explained, axis=0)


def _charge_fit(engine: Engine, rpm: float, K: int, Y: np.ndarray, E: np.ndarray, power: np.ndarray) -> tuple:
    """The fit with the engine's signature at the charge that explains the speed best.

    A throttled spark-ignition engine's motored part does not scale with its combustion (the
    intake and compression pressures fall with the charge, the exhaust and crankcase
    pressures do not), so a Wiebe engine's signature is tried at the charge scales of
    :data:`CHARGE_SCALES`, and between the best and its neighbours (a parabola in log σ):
    without it, a recording at a quarter of the charge puts TDC some 15° early. Other
    pressure sources: their own signature (their combustion part scales alone). Returns
    (the fit, the charge scale [-])."""
    import equinox as eqx

    from ..errors import EngineError

    scalable = bool(getattr(engine.pressure, "charge_scalable", False))

    def at(sigma):
        eng = engine
        if sigma != 1.0:
            eng = eqx.tree_at(lambda e: e.pressure, engine, engine.pressure.scale_charge(sigma))
        try:
            with warnings.catch_warnings():  # a probe of the charge, not a run the user asked for
                warnings.simplefilter("ignore")
                B = engine_signature(eng, rpm, K)
        except (EngineError, ArithmeticError, ValueError):
            return None
        if not np.all(np.isfinite(B)):
            return None
        return _shape_fit(B, Y, coarse, power)

    coarse = E[:, ::COARSE]
    if not scalable:
        return _shape_fit(engine_signature(engine, rpm, K), Y, E, power), 1.0
    first = at(1.0)
    if first is None:
        return _shape_fit(engine_signature(engine, rpm, K), Y, E, power), 1.0
    tried = {1.0: first}

    def score(sigma):
        f = tried[sigma]
        return float(np.min(f[3])) if f is not None else float("inf")

    seq = list(CHARGE_SCALES[1:])
    for sigma in seq:
        tried[sigma] = at(sigma)
        if score(sigma) >= min(score(x) for x in tried if x != sigma):
            break
    xs = sorted(tried)
    j = min(range(len(xs)), key=lambda n: score(xs[n]))
    if 0 < j < len(xs) - 1 and all(math.isfinite(score(xs[n])) for n in (j - 1, j, j + 1)):
        x0, x1, x2 = (math.log(xs[n]) for n in (j - 1, j, j + 1))
        y0, y1, y2 = (score(xs[n]) for n in (j - 1, j, j + 1))
        den = (x0 - x1) * (x0 - x2) * (x1 - x2)
        a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den if den else 0.0
        b = (x2**2 * (y0 - y1) + x1**2 * (y2 - y0) + x0**2 * (y1 - y2)) / den if den else 0.0
        if a > 0:
            xv = -b / (2 * a)
            if x0 < xv < x2:
                sigma = float(math.exp(xv))
                tried[sigma] = at(sigma)
    best = min(tried, key=score)
    return _shape_fit(tried[best][0], Y, E, power), best


def _bootstrap_std(Sk: np.ndarray, best: float, step: float, period: float) -> float:
    """The offset's standard deviation [rad] over :data:`BOOTSTRAP` resamples of the cycles
    (their residual curves ``Sk`` (C, D) summed with multinomial weights), about ``best``,
    scaled by √(C/(C − 1)) (the bootstrap's small-sample shrinkage)."""
    C, D = Sk.shape
    rng = np.random.default_rng(0)
    W = rng.multinomial(C, np.full(C, 1.0 / C), size=BOOTSTRAP).astype(np.float64)
    Sb = W @ Sk  # (BOOTSTRAP, D)
    i = np.argmin(Sb, axis=1)
    rows = np.arange(BOOTSTRAP)
    s0, s1, s2 = Sb[rows, (i - 1) % D], Sb[rows, i], Sb[rows, (i + 1) % D]
    curv = s0 - 2 * s1 + s2
    frac = np.where(curv > 0, 0.5 * (s0 - s2) / np.where(curv > 0, curv, 1.0), 0.0)
    off = _circ((i + frac) * step - best, period)
    return float(np.sqrt(np.mean(off**2) * C / (C - 1)))


def _model_std(
    Y: np.ndarray, B: np.ndarray, E: np.ndarray, power: np.ndarray, best: float, step: float, wrap: float
) -> float:
    """The model's own error in the offset [rad]: a jackknife over the fitted harmonics.

    Where the engine's signature describes the speed, every harmonic puts TDC in the same
    place, and leaving one out moves the offset by little more than the noise; where it does
    not (a real engine's combustion, gas exchange or coupling unlike the file's, a tooth-error
    estimate that took part of an engine order), the harmonics disagree, and the offset's
    spread over the K fits that each leave one harmonic out, √((K − 1)/K · Σ (d₋ₘ − d̄)²)
    (Quenouille and Tukey's jackknife), times :data:`MODEL_STD_FACTOR`, is the error a
    single fit cannot see in its own residual. Offsets wrapped within ``wrap`` [rad]."""
    C, K = Y.shape
    if K < 3:
        return 0.0
    D = E.shape[1]
    G = np.real(B[:, None, :] * B.conj()[None, :, :])  # (n, n, K)
    rm = np.stack(
        [np.real(Y[:, None, :] * B[j].conj()[None, None, :] * E.T[None, :, :]) for j in range(B.shape[0])], -1
    )  # (C, D, K, n)
    r_all = rm.sum(axis=2)
    offs = np.empty(K)
    for k in range(K):
        explained, _ = _nnls_explained(r_all - rm[:, :, k, :], G.sum(axis=-1) - G[:, :, k])
        S = np.sum((power - np.abs(Y[:, k]) ** 2)[:, None] - explained, axis=0)
        i = int(np.argmin(S))
        s0, s1, s2 = S[(i - 1) % D], S[i], S[(i + 1) % D]
        curv = s0 - 2 * s1 + s2
        offs[k] = (i + (0.5 * (s0 - s2) / curv if curv > 0 else 0.0)) * step
    dev = _circ(offs - best, wrap)
    # a harmonic that carries the offset alone (the only firing order of an even engine up to max_order) leaves
    # the others to an alias or to nothing when left out: such a jump is not the model's error but that
    # harmonic's weight, and is left out of the jackknife
    dev = dev[np.abs(dev) <= np.deg2rad(ALTERNATIVE_DEG)]
    n = dev.size
    if n < 2:
        return 0.0
    return MODEL_STD_FACTOR * float(np.sqrt((n - 1) / n * np.sum((dev - dev.mean()) ** 2)))


def _speed_cycles(engine, speed, mean_omega, max_order) -> tuple[np.ndarray, np.ndarray, float, str]:
    """The speed's cycles (cycles, points) [rad/s], their mean speeds [rad/s], the cycle
    [rad] and the recording's name, checked."""
    if isinstance(speed, LogAnalysis):
        omega = np.asarray(speed.omega, dtype=np.float64)
        mean_w = np.asarray(speed.mean_omega, dtype=np.float64)
        cycle = float(speed.cycle_rad)
        source = speed.source
    else:
        omega = np.asarray(speed, dtype=np.float64)
        if omega.ndim == 1:
            omega = omega[None, :]
        cycle = TWO_PI * (engine.strokes // 2)
        mean_w = omega.mean(axis=1) if mean_omega is None else np.asarray(mean_omega, dtype=np.float64).reshape(-1)
        source = ""
    if omega.ndim != 2 or omega.shape[0] < 1 or omega.shape[1] < 8:
        raise LogError(f"tdc_from_speed: speed of shape {omega.shape}: needs (cycles, points), a whole cycle or more")
    if not (np.all(np.isfinite(omega)) and np.all(omega > 0)):
        raise LogError("tdc_from_speed: the speed must be finite and positive")
    if not (isinstance(max_order, (int, float)) and max_order > 0):
        raise LogError(f"max_order={max_order!r}: a positive order", argument="max_order")
    return omega, mean_w, cycle, source


def _alike_period(B, m, cycle: float, revs: int, cylinders: int) -> float:
    """Alike cylinders: the shortest shift cycle/n under which the combustion shape (of the
    harmonics ``m``) fits itself [rad]; the cycle where none does."""
    shape = B[0] if np.any(B[0]) else B[1]
    norm = max(float(np.sum(np.abs(shape) ** 2)), 1e-300)
    for n in range(max(cylinders, 1), 1, -1):
        if np.real(np.sum(np.abs(shape) ** 2 * np.exp(1j * m * (cycle / n) / revs))) / norm > SYMMETRY_R2:
            return cycle / n
    return cycle


def _on_the_wheel(analysis: LogAnalysis, best: float) -> tuple[float, int | None, float | None]:
    """Cylinder 1's TDC after the gap [deg] for the offset ``best`` [rad] of the analysis's
    cycles, and (four-stroke) the firing parity and firing TDC's wheel angle [deg]: TDC
    before intake at wheel angle start + best, firing TDC one revolution later."""
    tdc_before_intake = float(analysis.cycle_start_rad[0]) + best
    tdc_gap = float(np.rad2deg(np.mod(tdc_before_intake, TWO_PI)))
    if analysis.strokes != 4:
        return tdc_gap, None, None
    firing_tdc = tdc_before_intake + TWO_PI
    return tdc_gap, int(math.floor(firing_tdc / TWO_PI + 1e-9)) % 2, float(np.rad2deg(firing_tdc))


def tdc_from_speed(
    engine: Engine,
    speed: LogAnalysis | np.ndarray,
    *,
    mean_omega: np.ndarray | None = None,
    max_order: float = DEFAULT_MAX_ORDER,
    prior_deg: float | None = None,
) -> SpeedTdc:
    """Cylinder 1's TDC from the crank speed alone (see the module doc).

    **Arguments:**
    - ``engine``: the :class:`rotor.Engine` (its inertia, the calibrated one where there is
      one; its pressure cycle gives the signature's shape, its amplitude is fitted).
    - ``speed``: a :class:`rotor.LogAnalysis` (its cycles, whatever TDC they were cut at:
      a calibration's, ``tdc_deg=0``, …), or an array (cycles, points) of the speed [rad/s]
      on a uniform angle grid of consecutive whole cycles, each starting at the same crank
      phase.
    - ``mean_omega``: for an array, each cycle's time-mean speed [rad/s] (default the
      rows' means).
    - ``max_order``: highest engine order fitted [orders per revolution] (default 4).
    - ``prior_deg``: an offset [deg, same frame as ``offset_deg``] to prefer among shifts
      the speed cannot tell apart (alike cylinders); None: the first.

    **Returns:** :class:`SpeedTdc` (never raises for a poor record: ``determined`` is
    False and ``reason`` says why). Raises :class:`rotor.LogError` for a speed without a
    whole cycle.
    """
    omega, mean_w, cycle, source = _speed_cycles(engine, speed, mean_omega, max_order)
    revs = round(cycle / TWO_PI)
    C, P = omega.shape
    K = int(min(math.floor(max_order * revs + 1e-9), P // 2 - 1))
    if K < 1:
        raise LogError(f"tdc_from_speed: {P} points per cycle resolve no order up to {max_order:g}")
    rpm = float(np.mean(mean_w)) * RPM_PER_RAD_S
    Y = cycle_spectrum(omega, mean_w, cycle)[:, 1 : K + 1]  # (C, K)
    m = np.arange(1, K + 1)
    D = int(round(360.0 * revs / STEP_DEG))
    d = np.arange(D) * (cycle / D)
    E = np.exp(1j * m[:, None] * d[None, :] / revs)  # (K, D): harmonic m is order m/revs
    power = np.sum(np.abs(Y) ** 2, axis=1)  # (C,)
    total = float(np.sum(power))
    try:
        fit, charge = _charge_fit(engine, rpm, K, Y, E, power)
    except NoSteadyStateError as e:
        raise NoSignature(
            f"{source + ': ' if source else ''}the engine has no steady state at the record's mean speed, "
            f"{rpm:.0f} rpm, to take its speed signature from ({str(e).split(':')[1].strip()}): "
            "a transient (a cranking, a coast-down to a stop)"
        ) from None

    B, explained, beta, S = fit
    i = int(np.argmin(S))
    s0, s1, s2 = S[(i - 1) % D], S[i], S[(i + 1) % D]
    curv = s0 - 2 * s1 + s2
    frac = 0.5 * (s0 - s2) / curv if curv > 0 else 0.0
    step = cycle / D
    best = (d[i] + frac * step) % cycle
    s_best = float(s1 - 0.25 * (s0 - s2) * frac) if curv > 0 else float(s1)
    dof = max(2 * C * K - B.shape[0] * C - 1, 1)
    sigma2 = max(s_best, 1e-300) / dof
    # alike cylinders: the shortest shift cycle/n under which the combustion shape fits itself
    period = _alike_period(B, m, cycle, revs, int(engine.cylinders))
    # an equivalent offset nearest the prior
    if period < cycle and prior_deg is not None:
        shifts = best + period * np.arange(round(cycle / period))
        best = float(shifts[np.argmin(np.abs(_circ(shifts - np.deg2rad(prior_deg), cycle)))] % cycle)
    far = np.abs(_circ(d - best, period)) > np.deg2rad(ALTERNATIVE_DEG)
    if far.any():
        j_alt = int(np.flatnonzero(far)[np.argmin(S[far])])
        s_alt, alt = float(S[j_alt]), float(d[j_alt])
    else:
        s_alt, alt = float("inf"), float("nan")
    separation = math.sqrt(max(s_alt - s_best, 0.0) / sigma2) if math.isfinite(s_alt) else float("inf")
    std_curv = math.sqrt(2 * sigma2 / (curv / step**2)) if curv > 0 else float("inf")
    # each cycle's own best offset (within the equivalence) and combustion amplitude at the best offset
    Sk = power[:, None] - explained
    per = d[np.argmin(Sk, axis=1)]
    per = best + _circ(per - best, period)
    j_best = int(round(best / step)) % D
    a_k = beta[:, j_best, 0]
    # the cycles' own offsets, robustly (a cycle between firing and not may stand apart): 1.4826·MAD/√C
    spread = float(1.4826 * np.median(np.abs(_circ(per - best, period))) / math.sqrt(C)) if C >= 3 else 0.0
    std_boot = _bootstrap_std(Sk, best, step, period) if C >= 3 else float("nan")
    std_model = _model_std(Y, B, E[:, ::COARSE], power, best, step * COARSE, min(period, TWO_PI))
    std_stat = max(std_curv, spread) if not math.isfinite(std_boot) else max(std_boot, spread)
    std = math.sqrt(std_stat**2 + std_model**2)
    r2 = 1.0 - s_best / total if total > 0 else 0.0
    reasons = []
    if total <= 0 or r2 < R2_MIN:
        reasons.append(
            f"the engine's speed signature explains {max(r2, 0.0):.0%} of the speed's fluctuation up to order "
            f"{max_order:g} (at least {R2_MIN:.0%} needed): a speed without the engine's compression and firing in it "
            f"(constant, noise, or another engine)"
        )
    if separation < SEPARATION_MIN:
        reasons.append(
            f"another offset ({np.rad2deg(alt):.0f}°) fits nearly as well ({separation:.1f} σ worse; "
            f"{SEPARATION_MIN:g} σ needed): {C} cycle{'s' if C != 1 else ''} too few or too noisy"
        )
    span = min(period, TWO_PI) / 2
    # the harmonics that carry the signature: with as many real numbers per cycle as the fit has free
    # parameters (the shapes' amplitudes and the offset), any signature fits and the model cannot be checked:
    # the offset then rests on the engine file alone, and its σ is that of an offset anywhere in the period
    band = np.sum(np.abs(B) ** 2, axis=0)
    informative = int(np.sum(band > INFORMATIVE * float(np.sum(band))))
    free = int(np.sum(np.sum(np.abs(B) ** 2, axis=1) > 0)) + 1
    if 2 * informative <= free:
        orders = ", ".join(f"{x / revs:g}" for x in m[band > INFORMATIVE * float(np.sum(band))])
        reasons.append(
            f"up to order {max_order:g} the engine's signature has {informative} order{'s' if informative != 1 else ''} "
            f"({orders} per revolution: alike cylinders), {2 * informative} numbers a cycle for {free} free "
            f"parameters: too few to place TDC and check the engine model at once (a higher max_order, where "
            f"the bench allows it, or a pressure or cam channel)"
        )
        std = max(std, 2 * span / math.sqrt(12.0))
    elif not AGREE_SIGMA * std < span:
        reasons.append(
            f"its uncertainty, ± {np.rad2deg(std):.0f}° (1σ; {np.rad2deg(std_model):.0f}° of it the engine model's "
            f"orders disagreeing), leaves every offset within ±{np.rad2deg(span):.0f}° inside {AGREE_SIGMA:g} σ: "
            f"the engine's signature up to order {max_order:g} holds too little of where TDC lies"
        )
    tdc_gap, parity, firing_wheel = _on_the_wheel(speed, best) if isinstance(speed, LogAnalysis) else (None,) * 3
    return SpeedTdc(
        offset_deg=float(np.rad2deg(best)),
        tdc_after_gap_deg=tdc_gap,
        firing_parity=parity,
        std_deg=float(np.rad2deg(std)),
        separation=float(separation),
        alternative_deg=float(np.rad2deg(alt)),
        r2=float(r2),
        determined=not reasons,
        reason="; ".join(reasons),
        period_deg=float(np.rad2deg(period)),
        cycle_deg=float(np.rad2deg(cycle)),
        cycles=C,
        cycle_offset_deg=np.rad2deg(np.mod(per, cycle)),
        cycle_combustion=a_k,
        candidates_deg=np.rad2deg(d),
        residual=S / total if total > 0 else S,
        mean_rpm=rpm,
        max_order=float(max_order),
        source=source,
        firing_tdc_wheel_deg=firing_wheel,
        std_statistical_deg=float(np.rad2deg(std_stat)),
        std_model_deg=float(np.rad2deg(std_model)),
        charge_scale=float(charge),
    )


CONTRADICT_RATIO = 2.0
"""Formerly the ratio of unexplained fluctuation at a given TDC to the best fit's beyond
which the TDC was contradicted [-]; it no longer decides (the verdict rests on the stated σ,
:data:`AGREE_SIGMA`: the residual ratio said "agrees" 8σ away on a real recording). The
ratio is still reported (``given_unexplained``, ``best_unexplained``)."""
TOOTH_MISMATCH = 0.5
"""A calibration's tooth errors whose rms difference from the recording's own estimate
exceeds this fraction of their rms (outside the orders left to the engine) belong to
another wheel [-] (the same wheel's recordings: under 0.1; another wheel's: about 1.1)."""


def residual_at(fit: SpeedTdc, offset_deg: float) -> float:
    """The fraction of the speed's fluctuation that ``fit``'s signature leaves unexplained
    with cylinder 1's TDC at ``offset_deg`` [deg, the fit's frame] (1 − R² there) [-]."""
    x = np.append(fit.candidates_deg, fit.cycle_deg)
    y = np.append(fit.residual, fit.residual[0])
    return float(np.interp(float(offset_deg) % fit.cycle_deg, x, y))


def tooth_error_mismatch(given: ToothErrors, own: ToothErrors) -> float:
    """How far a given wheel's tooth errors (a calibration's) lie from the recording's own
    estimate: the rms of their difference over the rms of the given ones, both without the
    orders the estimate left to the engine [-] (0: the same wheel; about 1.1 for another
    wheel of the same kind). NaN where the wheels differ in spec."""
    if given.wheel != own.wheel:
        return float("nan")

    def strip(e):
        e = np.asarray(e, dtype=np.float64) - np.mean(e)
        X = np.fft.rfft(e)
        for k in own.engine_orders:
            if 0 < int(round(k)) < X.size:
                X[int(round(k))] = 0.0
        return np.fft.irfft(X, n=e.size)

    g, o = strip(given.errors_rad), strip(own.errors_rad)
    rms = float(np.sqrt(np.mean(g**2)))
    return float(np.sqrt(np.mean((g - o) ** 2)) / rms) if rms > 0 else 0.0


class TdcVerdict(enum.StrEnum):
    """What :func:`check_tdc` concluded (decide on the members, never on a message's text).

    - ``AGREES``: the TDC given lies within :data:`AGREE_SIGMA` of the speed's stated σ
      (kept).
    - ``DISAGREES``: it lies further away, and the speed determines TDC: the speed's is
      used, and the message gives both with what to check.
    - ``UNDETERMINED``: the speed does not determine TDC closely enough to check it (too
      few cycles, too little of the engine's signature, or a σ that leaves every offset
      within 3σ): the TDC given is kept, unchecked.
    - ``FOUND``: none was given; the speed's is used.

    The values are the strings these outcomes had before the enumeration ("corrected" for
    ``DISAGREES``: the speed's TDC used; "consistent" for ``UNDETERMINED``), so that code
    comparing with them keeps working; the JSON gives the member's name in lower case.
    """

    AGREES = "agrees"
    DISAGREES = "corrected"
    UNDETERMINED = "consistent"
    FOUND = "found"


AGREE_SIGMA = 3.0
"""A TDC given within this many of the speed's stated standard deviations agrees [-]."""


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class TdcCheck(Result):
    """A TDC (a calibration's, or one given) checked against the recording's speed.

    **Fields:** ``verdict``: a :class:`TdcVerdict`; ``given_deg`` (the TDC checked, after
    the gap [deg], or None); ``used_deg`` (the TDC used) and ``firing_parity``;
    ``distance_sigma`` (how far the given TDC lies from the speed's, in the speed's σ; NaN
    where none was given); ``given_unexplained`` and ``best_unexplained`` (1 − R² of the
    signature at the given TDC and at the best) [-]; ``tooth_mismatch``
    (:func:`tooth_error_mismatch`, NaN without given tooth errors) [-]; ``fit``: the
    :class:`SpeedTdc`; ``message``: one line for the text output.
    """

    verdict: TdcVerdict
    given_deg: float | None
    used_deg: float
    firing_parity: int | None
    given_unexplained: float
    best_unexplained: float
    tooth_mismatch: float
    fit: SpeedTdc
    message: str
    distance_sigma: float = float("nan")
    bias_deg: float = 0.0
    std_deg: float = float("nan")

    @property
    def corrected(self) -> bool:
        """Whether the TDC used is not the one given (the verdict ``DISAGREES``)."""
        return self.verdict is TdcVerdict.DISAGREES

    def summary(self) -> str:
        """The verdict's line and the fit's summary."""
        return f"{self.message}\n" + self.fit.summary()

    def to_pandas(self) -> Any:
        """The fit's per-cycle table (:meth:`SpeedTdc.to_pandas`)."""
        return self.fit.to_pandas()

    def to_json_dict(self) -> dict:
        """The verdict (``agrees``, ``disagrees``, ``undetermined``, ``found``), whether the
        speed's TDC was used, the TDCs, how sure (``std_deg`` and its parts,
        ``distance_sigma``, ``separation_sigma``), the fit."""
        return json_safe(
            {
                "verdict": self.verdict.name.lower(),
                "corrected": self.corrected,
                "given_tdc_after_gap_deg": self.given_deg,
                "used_tdc_after_gap_deg": self.used_deg,
                "firing_parity": self.firing_parity,
                "speed_tdc_after_gap_deg": self.fit.tdc_after_gap_deg,
                "std_deg": self.fit.std_deg,
                "std_statistical_deg": self.fit.std_statistical_deg,
                "std_model_deg": self.fit.std_model_deg,
                "bias_deg": self.bias_deg,
                "compared_std_deg": self.std_deg,
                "distance_sigma": self.distance_sigma,
                "separation_sigma": self.fit.separation,
                "r2": self.fit.r2,
                "given_unexplained": self.given_unexplained,
                "best_unexplained": self.best_unexplained,
                "tooth_mismatch": self.tooth_mismatch,
                "message": self.message,
                "fit": self.fit.to_json_dict(),
            }
        )

    def plot(self, ax: Any = None) -> Any:
        """The fit's residual against the offset (:meth:`SpeedTdc.plot`), the checked TDC
        marked where one was given (:func:`rotor.plotting.diagnostics.plot_speed_tdc`)."""
        if self.given_deg is None:
            return self.fit.plot(ax=ax)
        # the fit ran on cycles cut at the given TDC: it lies at offset 0, or one revolution on
        cands = [0.0] + ([360.0] if self.fit.cycle_deg > 719.0 else [])
        at = min(cands, key=lambda c: residual_at(self.fit, c))
        return self.fit._plot(ax, at)


KAPPA_REL = 0.15
"""The least relative uncertainty of a calibration's bias factor κ [-]: on the three real
tue-4gb10 bench recordings (no, half and full load) κ came out 2.36, 2.61 and 2.41, ±5 %
about their mean; a calibration from one recording has no spread of its own, and its κ is
taken to ±15 % (three times that)."""


BIAS_LEFT_DEG = 1.0
"""What the bias model leaves of the speed's TDC error, at most [deg]: calibrated on one of the
three tue-4gb10 recordings and read on another, the speed's TDC less the bias lay 0.3–2.1°
from the pressure's (rms 1.1°). A bias smaller than this is uncertain by itself: where the
engine model fits (a simulated recording), the speed's TDC has no load bias to remove."""
BIAS_FIRING_MIN = 0.1
"""The bias is applied to records whose mean fitted combustion (1 = the engine file's) exceeds
this [-]: a coast-down's or motored run's signature has no combustion to be late."""


@dataclasses.dataclass(frozen=True)
class TdcBias:
    """The speed-based TDC's bias, measured by a calibration on recordings whose TDC the
    pressure channel gave.

    The speed's TDC lies late where the engine file's pressure cycle is not the engine's
    (combustion later and longer at light load): on the tue-4gb10 bench 7° at full load,
    11° at half load and 18° at no load. The harmonics' jackknife spread (``std_model_deg``
    of :class:`SpeedTdc`) measures the same mismatch, and the bias follows it:
    bias = κ·std_model_deg, κ = 2.4–2.6 on those three recordings. A calibration measures κ
    on its own recordings (:func:`tdc_bias_of`); a check with it compares the given TDC
    with the speed's less κ·std_model_deg, within σ = √(σ_stat² + (σ_κ·std_model_deg)²).

    **Fields:** ``kappa`` (κ, signed: positive where the speed puts TDC late) [-];
    ``kappa_std`` (its standard deviation: the recordings' spread, at least
    :data:`KAPPA_REL`·|κ|) [-]; ``recordings``: how many gave it."""

    kappa: float
    kappa_std: float
    recordings: int = 1

    def to_json_dict(self) -> dict:
        """The bias factor, its σ and how many recordings gave it."""
        return {"kappa": float(self.kappa), "kappa_std": float(self.kappa_std), "recordings": int(self.recordings)}

    @classmethod
    def from_json_dict(cls, d: Any) -> TdcBias | None:
        """From :meth:`to_json_dict`'s dict (None for None or a malformed one)."""
        try:
            k, s, n = float(d["kappa"]), float(d["kappa_std"]), int(d.get("recordings", 1))
        except (TypeError, KeyError, ValueError):
            return None
        if not (math.isfinite(k) and math.isfinite(s) and s >= 0):
            return None
        return cls(k, s, n)


def tdc_bias_of(pairs: list[tuple[float, float]]) -> TdcBias | None:
    """The bias factor κ from ``pairs`` of (speed's TDC − pressure's TDC [deg], the speed
    fit's ``std_model_deg`` [deg]), one per calibration recording: the mean of their ratios,
    its σ their spread (at least :data:`KAPPA_REL`·|κ|). None where no recording has a
    model term to scale (under 0.05°)."""
    ks = [b / m for b, m in pairs if m > 0.05 and math.isfinite(b)]
    if not ks:
        return None
    kappa = float(np.mean(ks))
    spread = float(np.std(ks, ddof=1)) if len(ks) > 1 else 0.0
    return TdcBias(kappa, max(spread, KAPPA_REL * abs(kappa)), len(ks))


def _bias_and_sigma(fit: SpeedTdc, bias: TdcBias | None) -> tuple[float, float]:
    """The speed's TDC bias at this recording [deg] (0 without a calibration's :class:`TdcBias`,
    or for a record that does not fire: the bias is the fired shape's) and the σ of the
    speed's TDC less it [deg]: the fit's ``std_deg`` without a bias; with one, the cycles'
    scatter, the bias factor's uncertainty times the model term and what the bias model
    leaves, the bias itself up to :data:`BIAS_LEFT_DEG` (the model term itself is what the
    bias removes)."""
    firing = fit.cycle_combustion.size > 0 and float(np.mean(fit.cycle_combustion)) > BIAS_FIRING_MIN
    if bias is None or not math.isfinite(fit.std_model_deg) or not firing:
        return 0.0, float(fit.std_deg)
    stat = fit.std_statistical_deg if math.isfinite(fit.std_statistical_deg) else 0.0
    m = float(fit.std_model_deg)
    b = bias.kappa * m
    sigma = math.sqrt(stat**2 + (bias.kappa_std * m) ** 2 + min(abs(b), BIAS_LEFT_DEG) ** 2)
    if not fit.determined:  # the fit's own σ then holds what leaves every offset possible
        sigma = max(sigma, float(fit.std_deg))
    return float(b), float(sigma)


def check_tdc(
    fit: SpeedTdc,
    given_deg: float | None,
    *,
    what: str = "the calibration's",
    tooth_mismatch: float = float("nan"),
    bias: TdcBias | None = None,
) -> TdcCheck:
    """Check a TDC against the speed's fit, or take the speed's where none is given.

    The verdict (:class:`TdcVerdict`) rests on the fit's stated σ alone (``std_deg``, which
    holds the engine model's own error, see the module doc): the given TDC **agrees** within
    :data:`AGREE_SIGMA` σ of the speed's (modulo the shifts the speed cannot tell apart),
    **disagrees** beyond (the speed's used, both named, and what to check), and is
    **undetermined** (kept) where the fit does not determine TDC.

    **Arguments:** ``fit``: :func:`tdc_from_speed` on a :class:`rotor.LogAnalysis` cut at
    ``given_deg`` (so that the given TDC lies at offset 0 or one revolution, either
    firing revolution); ``given_deg``: the TDC checked, after the gap [deg], or None (find
    it); ``what``: how the messages name it; ``tooth_mismatch``: reported as is.

    **Returns:** :class:`TdcCheck`. **Raises** :class:`TdcNotDetermined` (one line, with
    the measured offset and why) where the speed cannot determine TDC and none is given, or
    carries no signature of the engine at all (R² below :data:`R2_MIN`: a constant or noisy
    speed; then a given TDC can be neither found nor checked, and a diagnosis would be
    noise).
    """
    if fit.tdc_after_gap_deg is None:
        raise LogError("check_tdc: the fit must come from a rotor.LogAnalysis (a wheel's gap to count from)")
    src = f"{fit.source}: " if fit.source else ""
    b_deg, sigma = _bias_and_sigma(fit, bias)
    speed_deg = (float(fit.tdc_after_gap_deg) - b_deg) % 360.0
    measured = (
        f"{fit.tdc_after_gap_deg:.1f}° ± {fit.std_deg:.1f}° after the gap (1σ: {fit.std_statistical_deg:.1f}° "
        f"from the cycles' scatter, {fit.std_model_deg:.1f}° from the engine model; R² {fit.r2:.2f}, next best "
        f"{fit.separation:.0f} σ worse)"
    )
    if bias is not None and b_deg != 0.0:
        measured += (
            f", {speed_deg:.1f}° ± {sigma:.1f}° less the bias this load gives the speed's TDC ({b_deg:+.1f}°: "
            f"{bias.kappa:.2f} ± {bias.kappa_std:.2f} times the model term, as the calibration measured it)"
        )
    best_un = 1.0 - fit.r2
    if fit.r2 < R2_MIN:
        raise TdcNotDetermined(
            f"{src}the speed cannot determine TDC (best {measured}): {fit.reason}; "
            + (
                "give tdc_deg=DEG or a pressure channel"
                if given_deg is None
                else f"{what} TDC {given_deg:.1f}° cannot be checked"
            )
        )
    if given_deg is None:
        if not fit.determined:
            raise TdcNotDetermined(f"{src}the speed cannot determine TDC (best {measured}): {fit.reason}")
        return TdcCheck(
            verdict=TdcVerdict.FOUND,
            given_deg=None,
            used_deg=speed_deg,
            firing_parity=fit.firing_parity,
            given_unexplained=float("nan"),
            best_unexplained=best_un,
            tooth_mismatch=tooth_mismatch,
            fit=fit,
            message=f"TDC from the speed: {measured}",
            bias_deg=b_deg,
            std_deg=sigma,
        )
    revs = round(fit.cycle_deg / 360.0)
    # the given TDC at offset 0 of the fit's frame, or one revolution on (the other firing revolution)
    cands = [0.0] + ([360.0] if revs == 2 else [])
    un = [residual_at(fit, c) for c in cands]
    j = int(np.argmin(un))
    given_un = un[j]
    dist = abs(float(_circ(fit.offset_deg - b_deg - cands[j], fit.period_deg)))
    z = dist / sigma if sigma > 0 else (0.0 if dist == 0 else float("inf"))

    def made(verdict: TdcVerdict, used: float, parity: int | None, message: str) -> TdcCheck:
        return TdcCheck(
            verdict=verdict,
            given_deg=float(given_deg),
            used_deg=used,
            firing_parity=parity,
            given_unexplained=given_un,
            best_unexplained=best_un,
            tooth_mismatch=tooth_mismatch,
            fit=fit,
            message=message,
            distance_sigma=float(z),
            bias_deg=b_deg,
            std_deg=sigma,
        )

    apart = f"{dist:.1f}° apart, {z:.1f} σ"
    if not fit.determined:
        return made(
            TdcVerdict.UNDETERMINED,
            float(given_deg),
            None,
            f"{what} TDC {given_deg:.1f}° after the gap kept unchecked: the recording's speed does not determine "
            f"TDC (best {measured}: {apart}): {fit.reason}",
        )
    if z <= AGREE_SIGMA:
        return made(
            TdcVerdict.AGREES,
            float(given_deg),
            fit.parity_for(float(given_deg)),
            f"{what} TDC {given_deg:.1f}° after the gap agrees with the recording's speed, {measured}: {apart} "
            f"(within {AGREE_SIGMA:g} σ)",
        )
    return made(
        TdcVerdict.DISAGREES,
        speed_deg,
        fit.firing_parity,
        f"TDC corrected: {what} {given_deg:.1f}° after the gap disagrees with the recording's speed, which puts it "
        f"at {measured}: {apart} (more than {AGREE_SIGMA:g} σ); diagnosed with {speed_deg:.1f}°; "
        f"check whether the calibration comes from this installation (the wheel's mounting, the sensor), the "
        f"engine file (R² {fit.r2:.2f}), or measure TDC with a pressure channel",
    )
