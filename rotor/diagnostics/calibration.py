"""Calibration of what users rarely know, from a recording with a cylinder-pressure channel.

A diagnosis from crank speed alone (:func:`rotor.identify`) needs the inertia of
everything that turns with the crankshaft, the angle from the wheel's gap to TDC and the
wheel's tooth errors; a bench engine's file rarely has them right. :func:`calibrate`
takes them from one recording that has a pressure channel, :class:`Calibration` keeps
them (JSON, :meth:`Calibration.save` / :meth:`Calibration.load`;
:mod:`rotor.diagnostics.calibration_record`), and :func:`rotor.diagnose` reuses them on
speed-only recordings of the same engine (:mod:`rotor.diagnostics.diagnosis`).

**What is calibrated, and how** (single-cylinder engines; the pressure channel is
cylinder 1's):

1. *TDC*: the angle from the gap to firing TDC by the polytropic fit of the compression
   (:func:`rotor.tdc_from_pressure`, with the engine's compression ratio and rod ratio);
   the firing revolution from the pressure peaks. *Tooth errors*: estimated on the same
   recording (:func:`rotor.estimate_tooth_errors`).
2. *Pressure scale*: the sensor's gain cannot come from the speed: a gain g and an
   inertia J that are both too large by the same factor explain the same speed (only
   g/J is seen), and the pressure trace's shape (the polytropic compression) fixes its
   offset but not its gain. So the gain is an input (``pressure_gain``, the sensor's data
   sheet or bench calibration), or comes from the recording's **motored cycles** (a
   motored stretch, an ignition cut: :mod:`rotor.diagnostics.pegging`, their compression
   polytropic and pegged at the intake pressure; ``pressure_gain="motored"``, and by
   default where the recording has such cycles), or else is **left unknown**: the one
   that gives the recording's mean IMEP the engine file's IMEP, which is all that TDC,
   the tooth errors and an inertia that reproduces that IMEP need (``fit['pressure_gain_from']``
   says which). The offset is fitted (step 3, or with the motored cycles' gain); it does
   not enter the IMEP (∮p·dV of a constant is 0).
3. *Inertia, pressure offset, losses* from the energy balance over the record
   (variable inertia, angle domain):
   ½·(J + I_m(θ))·ω² = E₀ + ∫M_gas dθ − ∫a_k dθ, with M_gas = (g·u(θ) + b − p_cc)·A·s′(θ)
   from the cycle's own pressure signal u, I_m the crank mechanism's inertia from the
   engine file, a_k one constant loss torque (friction + load) per cycle. Divided by J
   it is linear in 1/J, b/J, E₀/J and a_k/J: least squares. Both sides are low-passed
   (zero-phase Butterworth, ``max_order`` per revolution, default 4) before the fit: a
   bench's crank speed carries a torsional resonance of the coupling and the brake (on
   ``tue-single``'s bench recordings orders 4.5–5, which no rigid-body model explains); without
   the low-pass the fitted inertia depends on the angle step (regressor noise).
   Friction and load are one constant torque at one speed: a recording at one operating
   point cannot separate them (the result reports their sum, ``loss_torque_Nm``).
4. *Identification inertia*: :func:`rotor.identify` explains the speed with the engine
   file's pressure shape (fired and motored traces), not the measured one; with the
   energy-balance inertia it read the calibration recording's IMEP 8 % high on
   ``tue-single``'s bench (7.8 %: the Wiebe cycle and the estimated piston and rod masses are not the
   engine's exactly). ``inertia_kgm2`` is therefore the inertia with which
   :func:`rotor.diagnose` reproduces the recording's measured mean IMEP (a secant iteration on
   the identification from the speed alone); the energy-balance value stays in
   ``fit['energy_balance_inertia_kgm2']``. Their ratio is a figure of the model's error.

**Charge scaling** (``scaling="charge"``, the default; :mod:`rotor.diagnostics.charge`):
the calibration keeps σ, the recording's measured IMEP over the engine file's, as the
start of :func:`rotor.diagnose`'s charge iteration.

The saved calibration and the presets' are :class:`rotor.Calibration` and
:func:`rotor.preset_calibration` (:mod:`rotor.diagnostics.calibration_record`); the
pressure channel's work :func:`rotor.measured_imep` (:mod:`rotor.diagnostics.pressure_work`);
the diagnosis :class:`rotor.Diagnosis` and :func:`rotor.diagnose`
(:mod:`rotor.diagnostics.diagnosis`).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import equinox as eqx
import numpy as np

from ..errors import EngineError
from ..logs.analysis import LogAnalysis, PhaseSource
from ..logs.wheel import ToothErrors
from ..units import PA_PER_BAR
from .calibration_record import Calibration, check_argument_types, engine_geometry
from .charge import check_scaling, scaled
from .phase import tdc_bias_of
from .pressure_work import check_single_cylinder, piston_displacement, signal_work

if TYPE_CHECKING:
    from ..engine.model import Engine
    from .pegging import MotoredGain

__all__ = ["calibrate"]

DEFAULT_MAX_ORDER = 4.0


# ----------------------------------------------------------------------------- calibrate
def calibrate(
    engine: Engine,
    log: str | os.PathLike | LogAnalysis | Sequence[str | os.PathLike | LogAnalysis],
    *,
    wheel: str | None = None,
    columns: str | Sequence[str] | None = None,
    pressure_gain: float | str | None = None,
    intake_pa: float | None = None,
    max_order: float = DEFAULT_MAX_ORDER,
    scaling: str = "charge",
    refine: bool = True,
    tooth_errors: str | os.PathLike | ToothErrors | None = "estimate",
    load_per: str = "block",
    edge: str = "auto",
) -> Calibration:
    """Calibrate inertia, losses, TDC, tooth errors and the pressure offset from a recording
    with a cylinder-pressure channel (see the module doc).

    **Arguments:**
    - ``engine``: a single-cylinder :class:`rotor.Engine` (geometry, masses; its pressure's
      compression ratio for the TDC fit).
    - ``log``: a file (read with ``wheel`` and ``columns``, e.g. ``"time,pressure_v,encoder_v"``)
      or a :class:`rotor.LogAnalysis` with a pressure channel and TDC from it; or a list of
      them, recordings of the same installation at several loads or speeds: the inertia is
      the mean of their energy balances', refined on all of them at once (the mean of the
      log ratios of identified to measured IMEP), TDC the circular mean of their pressure
      TDCs, the sensor and wheel the first's; the calibration states each recording
      (``recordings``), the loads and speeds they cover (:meth:`Calibration.coverage`) and
      the speed-based TDC's bias they measure (``tdc_bias``).
    - ``pressure_gain``: pascal per unit of the pressure signal; ``"motored"``: from the
      recording's motored cycles (:func:`rotor.diagnostics.pegging.pressure_gain_from_motored`:
      their compression polytropic, pegged at the intake pressure; refused where there are
      none); None (default): from the motored cycles where the recording has some, else
      left unknown: the gain that gives the recording's mean IMEP the engine file's IMEP
      (enough where only TDC, tooth errors and the inertia that reproduces that IMEP are
      wanted; ``fit['pressure_gain_from']`` says which).
    - ``intake_pa``: the intake pressure of the motored cycles [Pa] for ``"motored"``
      (default the engine file's ``intake_pa``).
    - ``max_order``: the energy balance's low-pass [orders per revolution].
    - ``scaling``: ``"charge"`` (default) or ``"none"`` (see the module doc).
    - ``refine``: find the identification inertia (default) or keep the energy balance's.
    - ``tooth_errors``, ``load_per``: passed to :func:`rotor.analyze_log` and :func:`rotor.diagnose`.
    - ``edge``: ``"auto"`` (default: both read, the one that fits the wheel better taken,
      :func:`rotor.logs.track.read_track`), ``"rising"`` or ``"falling"`` edges of the wheel signal.

    **Returns:** :class:`Calibration`. Raises :class:`rotor.EngineError` /
    :class:`rotor.LogError` for what cannot be calibrated.
    """
    logs = list(log) if isinstance(log, (list, tuple)) else [log]
    if not logs:
        raise EngineError("calibrate: no recording given (a log file, an analysis, or a list of them)")
    for one in logs:
        check_argument_types("calibrate", engine, one, None, wheel, None)
    motored = isinstance(pressure_gain, str) and pressure_gain == "motored"
    _check_gain_type(pressure_gain, motored)
    check_single_cylinder(engine, "calibrate")
    check_scaling(scaling, engine, ": use scaling='none'")
    if not (pressure_gain is None or isinstance(pressure_gain, str)) and not (
        np.isfinite(pressure_gain) and pressure_gain > 0
    ):
        raise EngineError(
            f"pressure_gain={pressure_gain!r}: must be a positive number [Pa per signal unit]", argument="pressure_gain"
        )
    parts = [
        _measured(engine, one, wheel, columns, tooth_errors, edge, pressure_gain, motored, intake_pa, max_order)
        for one in logs
    ]
    first = parts[0]
    sigmas = [p.imep_mean / p.gain.nominal_imep_pa if scaling == "charge" else 1.0 for p in parts]
    sigma = float(np.exp(np.mean(np.log(sigmas))))
    fit = dict(first.fit)
    J = float(np.mean([p.inertia for p in parts]))
    if len(parts) > 1:
        fit["energy_balance_inertia_kgm2"] = J
        fit["recordings"] = len(parts)
    if refine:
        engines = [scaled(engine, s) if scaling == "charge" else engine for s in sigmas]
        J, refined = _refine_inertia(engines, [p.analysis for p in parts], J, [p.imep_mean for p in parts], load_per)
        fit.update(refined)
    calibrated = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, float(J))
    biases = [_speed_tdc_bias(calibrated, p.analysis) for p in parts]
    a = first.analysis
    return Calibration(
        engine=engine.name,
        inertia_kgm2=float(J),
        tdc_after_gap_deg=_mean_angle_deg([float(np.rad2deg(p.analysis.tdc_rad)) for p in parts]),
        pressure_gain_pa=float(first.gain.gain_pa),
        pressure_offset_pa=float(np.mean([p.offset for p in parts])),
        loss_torque_Nm=float(np.mean(first.loss_torque)),
        scaling=scaling,
        charge_scale=sigma,
        wheel=a.track.wheel.spec if a.track is not None else "",
        tooth_errors=a.tooth_errors,
        source=", ".join(p.analysis.source for p in parts),
        fit=fit,
        cylinders=int(engine.cylinders),
        strokes=int(engine.strokes),
        geometry=engine_geometry(engine),
        reading=_reading_of(a),
        tdc_bias=tdc_bias_of([b for b in biases if b is not None]),
        recordings=tuple(p.record(b) for p, b in zip(parts, biases)),
    )


@dataclasses.dataclass(frozen=True)
class _Measured:
    """What one calibration recording gives: its analysis, the pressure gain, the mean
    measured IMEP [Pa], the energy balance's inertia [kg·m²], offset [Pa] and losses per
    cycle [N·m], the pumping loop's mean pressure [Pa] and the fit's figures."""

    analysis: LogAnalysis
    gain: _Gain
    imep_mean: float
    inertia: float
    offset: float
    loss_torque: np.ndarray
    pumping_mep: float
    fit: dict

    def record(self, bias: tuple[float, float] | None) -> dict:
        """The recording as a :class:`Calibration` states it (``recordings``)."""
        return {
            "source": self.analysis.source,
            "mean_rpm": self.fit["mean_rpm"],
            "imep_measured_pa": self.imep_mean,
            "pumping_mep_pa": self.pumping_mep,
            "loss_torque_Nm": float(np.mean(self.loss_torque)),
            "tdc_after_gap_deg": float(np.rad2deg(self.analysis.tdc_rad)),
            "energy_balance_inertia_kgm2": self.inertia,
            "speed_tdc_bias_deg": None if bias is None else bias[0],
            "speed_tdc_model_std_deg": None if bias is None else bias[1],
        }


def _measured(engine, log, wheel, columns, tooth_errors, edge, pressure_gain, motored, intake_pa, max_order):
    """One calibration recording analysed and its energy balance fitted (:class:`_Measured`)."""
    a = _calibration_analysis(engine, log, wheel, columns, tooth_errors, edge)
    vh = float(engine.geometry.displacement_m3)
    work = signal_work(engine, a)
    w_cycle = work[:, -1]
    gain = _pressure_gain(engine, a, pressure_gain, motored, intake_pa, w_cycle)
    imep_cycles = gain.gain_pa * w_cycle / vh
    J_e, b_rel, a_k, figs = _energy_balance(engine, a, gain.gain_pa, max_order)
    offset = b_rel + float(engine.pressure.crankcase_pa)  # single-zone cycles
    imep_mean = float(np.mean(imep_cycles))
    if not imep_mean > 0:
        raise EngineError(
            f"{a.source}: no firing in the recording (mean IMEP {imep_mean / PA_PER_BAR:.3g} bar from the pressure "
            f"channel): the calibration needs fired cycles"
        )
    P = work.shape[1] - 1
    # the gas exchange: intake (0 … 180°) and exhaust (540 … 720°) strokes of the cycle from TDC before intake
    pumping = gain.gain_pa * float(np.mean(work[:, P // 4] + work[:, P] - work[:, 3 * P // 4])) / vh
    fit = {
        "energy_balance_inertia_kgm2": J_e,
        "max_order": float(max_order),
        "cycles": int(a.cycles),
        "imep_measured_pa": imep_mean,
        "imep_measured_cycles_pa": imep_cycles.tolist(),
        "loss_torque_cycles_Nm": a_k.tolist(),
        "pressure_gain_from": gain.source,
        "energy_balance_offset_pa": float(offset),
        **({} if gain.pegged is None else {"motored": gain.pegged.to_json_dict()}),
        "mean_rpm": float(np.mean(a.mean_rpm)),
        "loss_mep_pa": float(np.mean(a_k)) * float(engine.cycle_rad) / vh,  # friction + load as a mean pressure
        "pumping_mep_pa": pumping,
        **figs,
    }
    return _Measured(
        analysis=a,
        gain=gain,
        imep_mean=imep_mean,
        inertia=float(J_e),
        offset=float(offset if gain.pegged is None else gain.pegged.offset_pa),
        loss_torque=a_k,
        pumping_mep=pumping,
        fit=fit,
    )


def _mean_angle_deg(angles: list[float]) -> float:
    """The circular mean of angles [deg], in the range of the first (an angle after the gap)."""
    z = np.mean(np.exp(1j * np.deg2rad(angles)))
    mean = float(np.rad2deg(np.angle(z)))
    return angles[0] + ((mean - angles[0] + 180.0) % 360.0 - 180.0)


def _speed_tdc_bias(engine, analysis) -> tuple[float, float] | None:
    """The speed-based TDC's bias on a recording whose TDC the pressure gave: (speed's TDC −
    pressure's [deg], the fit's model term [deg]); None where the speed does not determine it."""
    from .phase import R2_MIN, tdc_from_speed

    try:
        fit = tdc_from_speed(engine, analysis)
    except (EngineError, ArithmeticError, ValueError):
        return None
    if fit.tdc_after_gap_deg is None or fit.r2 < R2_MIN or not fit.determined:
        return None
    bias = (float(fit.tdc_after_gap_deg) - float(np.rad2deg(analysis.tdc_rad)) + 180.0) % 360.0 - 180.0
    return float(bias), float(fit.std_model_deg)


def _reading_of(analysis) -> dict | None:
    """How the wheel of ``analysis`` was read (:class:`rotor.logs.recording.ReadingRecord`), as
    JSON; None for a speed log."""
    record = analysis.reading_record
    return None if record is None else record.to_json_dict()


def _check_gain_type(pressure_gain, motored: bool) -> None:
    if (
        pressure_gain is not None
        and not motored
        and (isinstance(pressure_gain, bool) or not isinstance(pressure_gain, (int, float, np.integer, np.floating)))
    ):
        raise TypeError(
            f"calibrate(pressure_gain): a number [Pa per signal unit], 'motored' or None, not {pressure_gain!r}"
        )


def _calibration_analysis(engine, log, wheel, columns, tooth_errors, edge) -> LogAnalysis:
    """The recording analysed (or ``log`` itself, an analysis), checked for a pressure channel and TDC."""
    from ..logs.analysis import analyze_log

    if isinstance(log, LogAnalysis):
        a = log
    else:
        cr = getattr(engine.pressure, "compression_ratio", None)
        rod_ratio = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
        a = analyze_log(
            log,
            wheel,
            columns=columns,
            strokes=engine.strokes,
            cylinders=engine.cylinders,
            tooth_errors=tooth_errors,
            compression_ratio=None if cr is None else float(cr),
            rod_ratio=None if cr is None else rod_ratio,
            edge=edge,
        )
    if a.pressure is None:
        raise EngineError(
            f"{a.source}: no pressure channel (a column pressure_v): a speed-only recording cannot be "
            f"calibrated; diagnose it with a saved calibration"
        )
    if a.tdc_source not in (PhaseSource.PRESSURE, PhaseSource.GIVEN):
        raise EngineError(f"{a.source}: TDC is not known ({a.tdc_method})")
    return a


@dataclasses.dataclass(frozen=True)
class _Gain:
    """The pressure channel's gain [Pa per signal unit], where it came from, the motored
    cycles' pegging (or None) and the engine file's IMEP [Pa]."""

    gain_pa: float
    source: str
    pegged: MotoredGain | None
    nominal_imep_pa: float


def _pressure_gain(engine, a, pressure_gain, motored, intake_pa, w_cycle) -> _Gain:
    """The gain given, from the motored cycles, or the one that gives the recording's mean
    IMEP the engine file's (see the module doc)."""
    from ..engine.forces import imep_pa

    nominal = float(imep_pa(engine))
    pegged = None
    if pressure_gain is None or motored:
        from .pegging import motored_cycles, pressure_gain_from_motored

        if motored or (engine.strokes == 4 and motored_cycles(a).any()):
            pegged = pressure_gain_from_motored(engine, a, intake_pa=intake_pa)
    if pegged is not None:
        return _Gain(pegged.gain_pa, f"motored cycles {', '.join(str(c) for c in pegged.cycles)}", pegged, nominal)
    if pressure_gain is None:
        vh = float(engine.geometry.displacement_m3)
        return _Gain(nominal * vh / float(np.mean(w_cycle)), "engine file's IMEP", None, nominal)
    return _Gain(float(pressure_gain), "given", None, nominal)


def _refine_inertia(engines, analyses, J_e, imep_means, load_per) -> tuple[float, dict]:
    """The inertia with which the identification from the speed alone reproduces the
    measured mean IMEPs ``imep_means`` of the recordings ``analyses`` (each identified on its
    engine of ``engines``), in the mean of their log ratios (a secant iteration on log J
    from the energy balance's ``J_e``), and the fit's figures of it."""
    from .identification import identify

    def g(logJ):
        means = []
        for eng, a in zip(engines, analyses):
            ident = identify(
                eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, eng, float(np.exp(logJ))), a, load_per=load_per
            )
            means.append(float(np.mean(ident.imep_pa[:, 0])))
        errs = [math.log(max(m, 1.0)) - math.log(max(t, 1.0)) for m, t in zip(means, imep_means)]
        return float(np.mean(errs)), means

    x0 = math.log(J_e)
    g0, first = g(x0)
    x1 = x0 - g0
    g1, last = g(x1)
    steps = 2
    while abs(g1) > 1e-4 and steps < 8 and g1 != g0:
        x0, g0, x1 = x1, g1, x1 - g1 * (x1 - x0) / (g1 - g0)
        g1, last = g(x1)
        steps += 1
    figs = {
        "identified_imep_with_energy_balance_inertia_pa": first[0] if len(first) == 1 else first,
        "refine_steps": steps,
        "identified_imep_mismatch": float(math.expm1(g1)),
    }
    if len(last) > 1:
        figs["identified_imep_pa"] = last
    return float(np.exp(x1)), figs


def _lowpass(x, max_order, P, revs):
    from scipy.signal import butter, filtfilt

    nyq = P / (2.0 * revs)  # orders per revolution
    wn = max_order / nyq
    if not 0 < wn < 1:
        raise EngineError(
            f"max_order={max_order!r}: must lie between 0 and {nyq:g} (half the points per revolution)",
            argument="max_order",
        )
    b, a = butter(4, wn)
    return filtfilt(b, a, x, axis=0)


def _energy_balance(engine, analysis, gain, max_order):
    """Least squares of ½(J + I_m)ω² = E₀ + g·W_u + b·A·s − Σ a_k·ramp_k (low-passed):
    returns J, b (offset less crankcase) [Pa], a_k [N·m] and fit figures."""
    from ..engine.inertia import reduced_inertia

    C, P = analysis.omega.shape
    if C < 2:
        raise EngineError(f"{analysis.source}: {C} complete cycle; the calibration needs at least 2")
    cyc = float(analysis.cycle_rad)
    revs = engine.strokes // 2
    psi = np.arange(P) * cyc / P
    Wu = signal_work(engine, analysis)
    Wc = np.empty(C * P)
    acc = 0.0
    for k in range(C):
        Wc[k * P : (k + 1) * P] = acc + Wu[k, :P]
        acc += Wu[k, -1]
    Wc *= gain
    w2 = analysis.omega.reshape(-1) ** 2
    s, _ = piston_displacement(engine, psi)
    s = np.tile(s, C)
    Im = np.tile(np.asarray(reduced_inertia(engine, psi)) - float(engine.crankshaft.inertia_kgm2), C)
    theta = np.arange(C * P) * cyc / P
    area = float(engine.geometry.piston_area_m2)
    cols = [Wc - 0.5 * Im * w2, area * s, np.ones(C * P)] + [np.clip(theta - k * cyc, 0.0, cyc) for k in range(C)]
    X = _lowpass(np.array(cols).T, max_order, P, revs)
    y = _lowpass(0.5 * w2, max_order, P, revs)
    keep = slice(P // 2, C * P - P // 2)  # the filter's edge effects
    Xk, yk = X[keep], y[keep]
    scale = np.sqrt(np.sum(Xk**2, axis=0))
    sol = np.linalg.lstsq(Xk / scale, yk, rcond=None)[0] / scale
    r = yk - Xk @ sol
    u = sol[0]
    if not u > 0:
        raise EngineError(
            f"{analysis.source}: the energy balance gives no positive inertia (the speed does not follow "
            f"the pressure's torque: check the columns and TDC)"
        )
    J = 1.0 / u
    b_rel = sol[1] / u
    a_k = -sol[3:] / u
    fluct = yk - Xk[:, 2:] @ sol[2:]
    w_mean = float(np.mean(analysis.omega))
    return (
        J,
        b_rel,
        a_k,
        {
            "energy_balance_r2": float(1 - np.sum(r**2) / np.sum((fluct - fluct.mean()) ** 2)),
            "energy_balance_rms_rad_s": float(np.sqrt(np.mean(r**2)) / w_mean),
        },
    )
