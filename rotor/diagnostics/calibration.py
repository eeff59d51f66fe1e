"""Calibration of what users rarely know, from a recording with a cylinder-pressure channel.

A diagnosis from crank speed alone (:func:`rotor.identify`) needs the inertia of
everything that turns with the crankshaft, the angle from the wheel's gap to TDC and the
wheel's tooth errors; a bench engine's file rarely has them right. :func:`calibrate`
takes them from one recording that has a pressure channel, :class:`Calibration` keeps
them (JSON, :meth:`Calibration.save` / :meth:`Calibration.load`), and :func:`diagnose`
reuses them on speed-only recordings of the same engine.

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
   the tue-4gb10 recordings orders 4.5–5, which no rigid-body model explains); without
   the low-pass the fitted inertia depends on the angle step (regressor noise).
   Friction and load are one constant torque at one speed: a recording at one operating
   point cannot separate them (the result reports their sum, ``loss_torque_Nm``).
4. *Identification inertia*: :func:`rotor.identify` explains the speed with the engine
   file's pressure shape (fired and motored traces), not the measured one; with the
   energy-balance inertia it read the calibration recording's IMEP 8 % high on
   tue-4gb10 (7.8 %: the Wiebe cycle and the estimated piston and rod masses are not the
   engine's exactly). ``inertia_kgm2`` is therefore the inertia with which
   :func:`diagnose` reproduces the recording's measured mean IMEP (a secant iteration on
   the identification from the speed alone); the energy-balance value stays in
   ``fit['energy_balance_inertia_kgm2']``. Their ratio is a figure of the model's error.

**Charge scaling** (``scaling="charge"``, the default): a throttled spark-ignition engine
changes its load by the intake pressure, and the whole cylinder pressure (compression
and combustion) scales with the trapped charge; :func:`rotor.identify` scales only the
combustion part of the engine file's cycle (a diesel's way). :func:`diagnose` therefore
scales the file's Wiebe cycle as a whole (intake pressure and IMEP by one factor σ) and
iterates σ until the firings' mean combustion scale is 1. On tue-4gb10 (no load to full
load, compression pressure 60° before TDC 1.15 to 2.89 bar) it cut the speed-only IMEP
error at half load from −0.28 to −0.06 bar and at no load from −0.60 to −0.19 bar.
``scaling="none"`` keeps the file's cycle (diesels, or a table pressure).

**A preset's own calibration**: a preset may ship one beside its TOML
(``rotor/presets/<name>.calibration.json``; ``tue-single``'s from tue-4gb10's full_load.txt,
written by ``benchmarks/diagnose_real.py``). :func:`diagnose` uses it when no calibration
is given (``calibration="preset"``, the default; ``None``: the engine file as it is). A
calibration stores its engine's name, cylinders, strokes and geometry, and one of another
engine is refused.

**Does the engine match the log?** :func:`diagnose` says so in ``Diagnosis.mismatch``
(also among its ``warnings``, in the text and the JSON) where:

- a cylinder's identified mean IMEP over its normal firings exceeds :data:`IMEP_FACTOR_MAX`
  (3) times the engine file's, or :data:`IMEP_MAX_PA` (40 bar) in any case: the highest
  brake mean effective pressures of production engines are about 10 bar (naturally
  aspirated spark ignition) to 20–25 bar (turbocharged diesels; Heywood, *Internal
  Combustion Engine Fundamentals*, ch. 2), the indicated a bar or two above;
- the log's mean speed is more than :data:`SPEED_FACTOR_MAX` (2) times the engine file's
  operating speed, or its mean piston speed exceeds :data:`PISTON_SPEED_MAX_M_S`
  (25 m/s, beyond racing engines; most engines stay under about 15 m/s at rated speed,
  Heywood, ch. 2);
- an engine of several cylinders with no misfire found and a fit of R² below
  :data:`PATTERN_R2` (0.9), whose speed fluctuates more than :data:`PATTERN_FACTOR` (3)
  times as much at some order below its firing order (half its cylinders per revolution
  for a four-stroke) as at the firing order: the cylinders' firing pattern is not in the
  speed (a log of another engine, e.g. a single cylinder). (Uneven cylinders alone raise
  the low orders too, but the identification explains them: its R² stays high.)

A poor fit (R² below :data:`rotor.diagnostics.identification.POOR_FIT_R2`) is a warning of
its own. A single-cylinder recording diagnosed as the four-cylinder ``4chn15`` (3000 rpm)
trips all three (IMEP 120–360 bar).

Measured figures: ``benchmarks/diagnose_real.py`` (``benchmarks/results/diagnose_real.json``)
and ``docs/diagnostics.md``.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import equinox as eqx
import numpy as np

from ..errors import EngineError, LogError
from ..fileio import load_json, save_json
from ..logs.analysis import LogAnalysis, PhaseSource
from ..logs.reader import read_log
from ..logs.track import read_track
from ..logs.wheel import ToothErrors, parse_wheel
from ..results import Result, json_safe
from ..units import PA_PER_BAR, RPM_PER_RAD_S
from .identification import NO_FIRING_NOTE, POOR_FIT_R2, Identification
from .phase import TOOTH_MISMATCH, TdcCheck, TdcVerdict

if TYPE_CHECKING:
    from ..dynamics.result import SpeedResult
    from ..engine.model import Engine

__all__ = [
    "Calibration",
    "Diagnosis",
    "calibrate",
    "diagnose",
    "measured_imep",
    "preset_calibration",
    "CALIBRATION_FORMAT",
    "IMEP_FACTOR_MAX",
    "IMEP_MAX_PA",
    "SPEED_FACTOR_MAX",
    "PISTON_SPEED_MAX_M_S",
    "PATTERN_FACTOR",
    "PATTERN_R2",
]

CALIBRATION_FORMAT = "rotor-calibration"
CALIBRATION_VERSION = 1
BIN_DEG = 0.5  # the pressure signal is averaged in bins of this width per cycle
DEFAULT_MAX_ORDER = 4.0
SCALINGS = ("charge", "none")
SIGMA_RANGE = (0.05, 5.0)  # the charge scale's physical range: intake pressure × σ (a deep throttle … a big boost)
IMEP_FACTOR_MAX = 3.0  # identified IMEP over the engine file's: above, the engine does not match the log
IMEP_MAX_PA = 40e5  # no engine reaches this IMEP [Pa] (see the module doc)
SPEED_FACTOR_MAX = 2.0  # the log's mean speed over the engine file's operating speed
PISTON_SPEED_MAX_M_S = 25.0  # mean piston speed beyond racing engines [m/s]
PATTERN_FACTOR = 3.0  # a lower order this many times the firing order's amplitude: the pattern is not seen
PATTERN_R2 = 0.9  # … looked for only where the fit explains less than this of the speed fluctuation
PRESETS_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "presets")


# ----------------------------------------------------------------------------- the record
@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Calibration(Result):
    """What :func:`calibrate` found, to reuse on speed-only recordings of the same engine.

    **Fields:** ``engine`` (the engine's name); ``inertia_kgm2``: crankshaft, flywheel and
    all that turns rigidly with them [kg·m²] (the identification inertia, see the module
    doc); ``tdc_after_gap_deg``: from the first tooth edge after the gap to cylinder 1's
    TDC [deg]; ``pressure_gain_pa``: pascal per unit of the pressure signal;
    ``pressure_offset_pa``: absolute pressure = gain·signal + offset [Pa];
    ``loss_torque_Nm``: the mean of friction plus load over the recording [N·m];
    ``scaling``: ``"charge"`` or ``"none"`` (see the module doc); ``charge_scale``: σ of the
    calibration recording (its IMEP over the engine file's) [-]; ``wheel`` (spec);
    ``tooth_errors``: a :class:`rotor.ToothErrors` or None; ``source``: the recording;
    ``fit``: figures of the fit (energy-balance inertia, residuals, IMEP measured).
    """

    engine: str
    inertia_kgm2: float
    tdc_after_gap_deg: float
    pressure_gain_pa: float
    pressure_offset_pa: float
    loss_torque_Nm: float
    scaling: str = "charge"
    charge_scale: float = 1.0
    wheel: str = ""
    tooth_errors: ToothErrors | None = None
    source: str = ""
    fit: dict = dataclasses.field(default_factory=dict)
    cylinders: int = 0  # of the calibrated engine (0: not stored, an older file)
    strokes: int = 0
    geometry: dict = dataclasses.field(default_factory=dict)  # bore_m, stroke_m, rod_length_m (empty: not stored)

    def __post_init__(self):
        for key in ("inertia_kgm2", "pressure_gain_pa", "charge_scale"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v > 0):
                raise EngineError(f"calibration {key} = {v!r}: must be a positive number")
        for key in ("tdc_after_gap_deg", "pressure_offset_pa", "loss_torque_Nm"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise EngineError(f"calibration {key} = {v!r}: must be a finite number")
        if self.scaling not in SCALINGS:
            raise EngineError(f"calibration scaling = {self.scaling!r}: one of {', '.join(SCALINGS)}")

    def check_engine(self, engine: Engine, where: str = "calibration") -> None:
        """Raise :class:`rotor.EngineError` unless ``engine`` is the calibrated one: the same
        name, cylinder count, strokes and geometry (those the calibration stores); ``where``
        names the calibration in the message."""
        diffs = []
        if self.engine and self.engine != engine.name:
            diffs.append(f"engine {self.engine!r}, not {engine.name!r}")
        if self.cylinders and self.cylinders != engine.cylinders:
            diffs.append(f"{self.cylinders} cylinder(s), not {engine.cylinders}")
        if self.strokes and self.strokes != engine.strokes:
            diffs.append(f"{self.strokes} strokes, not {engine.strokes}")
        for key, v in self.geometry.items():
            have = float(getattr(engine.geometry, key))
            if not math.isclose(float(v), have, rel_tol=1e-6, abs_tol=1e-12):
                diffs.append(f"{key} {float(v):g}, not {have:g}")
        if diffs:
            raise EngineError(
                f"{where}: calibrated on another engine ({'; '.join(diffs)}): its inertia and TDC do "
                f"not apply; calibrate this engine (rotor diagnose --save-calibration)"
            )

    def apply(self, engine: Engine) -> Engine:
        """``engine`` with the calibrated crankshaft inertia [kg·m²]."""
        return eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, float(self.inertia_kgm2))

    def to_json_dict(self) -> dict:
        """Plain JSON (what :meth:`save` writes and ``rotor diagnose --json`` reports): the
        calibrated quantities in SI units, the tooth errors, the fit's figures."""
        return {
            "format": CALIBRATION_FORMAT,
            "version": CALIBRATION_VERSION,
            "engine": self.engine,
            "inertia_kgm2": float(self.inertia_kgm2),
            "tdc_after_gap_deg": float(self.tdc_after_gap_deg),
            "pressure_gain_pa": float(self.pressure_gain_pa),
            "pressure_offset_pa": float(self.pressure_offset_pa),
            "loss_torque_Nm": float(self.loss_torque_Nm),
            "scaling": self.scaling,
            "charge_scale": float(self.charge_scale),
            "wheel": self.wheel,
            "tooth_errors": None if self.tooth_errors is None else self.tooth_errors.to_json_dict(),
            "source": self.source,
            "fit": json_safe(self.fit),
            "cylinders": int(self.cylinders),
            "strokes": int(self.strokes),
            "geometry": json_safe(self.geometry),
        }

    @classmethod
    def from_json_dict(cls, d: dict, where: str = "calibration") -> Calibration:
        """Build from :meth:`to_json_dict`'s dict ``d``; errors name ``where`` and the key."""
        if not isinstance(d, dict):
            raise EngineError(f"{where}: not a calibration (a JSON object is needed)")
        if d.get("format") != CALIBRATION_FORMAT:
            raise EngineError(f"{where}: key 'format' must be {CALIBRATION_FORMAT!r} (not a rotor calibration file)")
        if d.get("version") != CALIBRATION_VERSION:
            raise EngineError(
                f"{where}: key 'version' = {d.get('version')!r}: this rotor reads version {CALIBRATION_VERSION}"
            )

        def num(key, positive=False):
            if key not in d:
                raise EngineError(f"{where}: missing key {key!r}")
            v = d[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
                raise EngineError(
                    f"{where}: key {key!r} = {v!r}: must be a {'positive' if positive else 'finite'} number"
                )
            return float(v)

        def text(key):
            v = d.get(key, "")
            if not isinstance(v, str):
                raise EngineError(f"{where}: key {key!r} = {v!r}: must be a string")
            return v

        scaling = text("scaling") or "charge"
        if scaling not in SCALINGS:
            raise EngineError(f"{where}: key 'scaling' = {scaling!r}: one of {', '.join(SCALINGS)}")
        te = d.get("tooth_errors")
        if te is not None:
            if not isinstance(te, dict) or "wheel" not in te or "errors_rad" not in te:
                raise EngineError(
                    f"{where}: key 'tooth_errors' must be null or an object with 'wheel' and 'errors_rad'"
                )
            try:
                te = ToothErrors(
                    wheel=te["wheel"],
                    errors_rad=np.asarray(te["errors_rad"], dtype=np.float64),
                    method=str(te.get("method", "given")),
                    revolutions=int(te.get("revolutions", 0)),
                    engine_orders=tuple(float(k) for k in te.get("engine_orders", ())),
                    source=str(te.get("source", "")),
                )
            except (TypeError, ValueError) as e:
                raise EngineError(f"{where}: key 'tooth_errors': {e}") from None
        fit = d.get("fit", {})
        if not isinstance(fit, dict):
            raise EngineError(f"{where}: key 'fit' must be an object")

        def whole(key):
            v = d.get(key, 0)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise EngineError(f"{where}: key {key!r} = {v!r}: must be a whole number")
            return v

        geo = d.get("geometry", {})
        if not isinstance(geo, dict) or not all(
            k in _GEOMETRY_KEYS
            and isinstance(v, (int, float))
            and not isinstance(v, bool)
            and math.isfinite(v)
            and v >= 0
            for k, v in geo.items()
        ):
            raise EngineError(f"{where}: key 'geometry' must be an object of numbers ({', '.join(_GEOMETRY_KEYS)})")
        return cls(
            engine=text("engine"),
            inertia_kgm2=num("inertia_kgm2", True),
            tdc_after_gap_deg=num("tdc_after_gap_deg"),
            pressure_gain_pa=num("pressure_gain_pa", True),
            pressure_offset_pa=num("pressure_offset_pa"),
            loss_torque_Nm=num("loss_torque_Nm"),
            scaling=scaling,
            charge_scale=num("charge_scale", True) if "charge_scale" in d else 1.0,
            wheel=text("wheel"),
            tooth_errors=te,
            source=text("source"),
            fit=fit,
            cylinders=whole("cylinders"),
            strokes=whole("strokes"),
            geometry=dict(geo),
        )

    def save(self, path: str | os.PathLike) -> None:
        """Write as JSON to ``path``, whole or not at all."""
        save_json(path, self.to_json_dict(), what="the calibration", error=EngineError)

    @classmethod
    def load(cls, path: str | os.PathLike) -> Calibration:
        """Read a file written by :meth:`save` from ``path``; a malformed file raises
        :class:`rotor.EngineError` naming the file and the key."""
        path = os.fspath(path)
        if os.path.isdir(path):
            raise EngineError(f"{path}: is a folder, not a calibration file")
        if not os.path.exists(path):
            raise EngineError(f"{path}: No such file or directory (no calibration file there)")
        d = load_json(path, what="a calibration file", error=EngineError)
        return cls.from_json_dict(d, where=path)  # type: ignore[arg-type]  # checked there

    def to_pandas(self) -> Any:
        """Tidy: one row per cycle of the calibration recording: ``cycle``,
        ``imep_measured_pa`` (from the pressure channel with the calibrated gain) and
        ``loss_torque_Nm`` (friction plus load fitted by the energy balance). No rows for
        a calibration file without these figures (``fit``)."""
        import pandas as pd

        imep, loss = self._cycle_figures()
        return pd.DataFrame({"cycle": np.arange(1, imep.size + 1), "imep_measured_pa": imep, "loss_torque_Nm": loss})

    def plot(self, ax: Any = None, kind: str | None = None) -> Any:
        """The calibration recording's IMEP per cycle from the pressure channel (with the
        engine file's, for charge scaling) and the fitted friction + load per cycle, on
        ``ax`` (two Axes, or None for a new figure), or with ``kind`` (``"imep"``,
        ``"loss"``) that panel alone on the one Axes ``ax``
        (:func:`rotor.plotting.diagnostics.plot_calibration`). Returns what it drew on."""
        from ..plotting.diagnostics import plot_calibration

        imep, loss = self._cycle_figures()
        mean = self.fit.get("imep_measured_pa")
        file_imep = float(mean) / self.charge_scale if (self.scaling == "charge" and mean is not None) else None
        return plot_calibration(
            imep_measured_pa=imep,
            loss_torque_Nm=loss,
            imep_file_pa=file_imep,
            title=f"calibration of {self.engine}" + (f" from {self.source}" if self.source else ""),
            ax=ax,
            kind=kind,
        )

    def _cycle_figures(self) -> tuple[np.ndarray, np.ndarray]:
        imep = np.asarray(self.fit.get("imep_measured_cycles_pa", []), dtype=np.float64).reshape(-1)
        loss = np.asarray(self.fit.get("loss_torque_cycles_Nm", []), dtype=np.float64).reshape(-1)
        if loss.size != imep.size:
            loss = np.full(imep.size, np.nan)
        return imep, loss

    def summary(self) -> str:
        """A few lines: inertia, TDC, the pressure sensor's gain and offset, the losses, σ."""
        j_e = self.fit.get("energy_balance_inertia_kgm2", float("nan"))
        imep = self.fit.get("imep_measured_pa", float("nan"))
        sign = "+" if self.pressure_offset_pa >= 0 else "−"
        lines = [
            f"calibration of {self.engine} from {self.source or 'a recording'}:",
            f"  inertia {self.inertia_kgm2:.5f} kg·m² (energy balance {j_e:.5f})",
            f"  TDC {self.tdc_after_gap_deg:.2f}° after the gap; pressure = "
            f"{self.pressure_gain_pa / PA_PER_BAR:.4g} bar × signal {sign} "
            f"{abs(self.pressure_offset_pa) / PA_PER_BAR:.4g} bar"
            + (f" (gain: {self.fit['pressure_gain_from']})" if self.fit.get("pressure_gain_from") else ""),
            f"  friction + load {self.loss_torque_Nm:.3f} N·m; measured IMEP {imep / PA_PER_BAR:.3f} bar; "
            f"scaling {self.scaling} (σ {self.charge_scale:.4f})",
        ]
        return "\n".join(lines) + "\n"


_GEOMETRY_KEYS = ("bore_m", "stroke_m", "rod_length_m")


def _engine_geometry(engine: Engine) -> dict:
    return {k: float(getattr(engine.geometry, k)) for k in _GEOMETRY_KEYS}


def preset_calibration(engine: Engine) -> tuple[Calibration, str] | None:
    """The calibration shipped with the preset of ``engine`` (``rotor/presets/<name>.calibration.json``
    whose stored engine is this one), as (Calibration, path), or None."""
    import glob

    for path in sorted(glob.glob(os.path.join(PRESETS_DIR, "*.calibration.json"))):
        cal = Calibration.load(path)
        if cal.engine == engine.name:
            try:
                cal.check_engine(engine)
            except EngineError:
                continue  # the preset's name on another geometry: not its calibration
            return cal, path
    return None


# ----------------------------------------------------------------------------- pieces
def _check_single(engine, what):
    if engine.cylinders != 1:
        raise EngineError(
            f"{what}: engine {engine.name!r} has {engine.cylinders} cylinders; a calibration from a "
            f"pressure channel needs every cylinder's pressure, which a log of one channel has only "
            f"for a single-cylinder engine (not yet: several cylinders)"
        )


def _binned_pressure(analysis, step_deg=BIN_DEG):
    """Each complete cycle's pressure signal averaged in bins of ``step_deg``
    (:func:`rotor.diagnostics.pegging.binned_pressure`)."""
    from .pegging import binned_pressure

    return binned_pressure(analysis, step_deg)


def _displacement(engine, theta):
    from ..engine.mechanism import engine_piston_motion

    pm = engine_piston_motion(engine, np.asarray(theta))
    return np.asarray(pm.s)[..., 0], np.asarray(pm.ds)[..., 0]


def _signal_work(engine, analysis):
    """∫ u·A·s′ dθ per cycle from the cycle start, at the speed's grid angles ((cycles, P+1),
    the last column the whole cycle), u the pressure signal."""
    centres, sig = _binned_pressure(analysis)
    h = analysis.cycle_rad / centres.size
    _, ds = _displacement(engine, centres)
    area = float(engine.geometry.piston_area_m2)
    edges = np.arange(centres.size + 1) * h
    cum = np.concatenate([np.zeros((sig.shape[0], 1)), np.cumsum(sig * ds * area * h, axis=1)], axis=1)
    P = analysis.points_per_cycle
    psi = np.arange(P + 1) * analysis.cycle_rad / P
    return np.stack([np.interp(psi, edges, row) for row in cum])


def measured_imep(engine: Engine, analysis: LogAnalysis, pressure_gain: float) -> np.ndarray:
    """IMEP of each complete cycle from the recording's pressure channel, ∮p·dV / V_h [Pa].

    **Arguments:** ``engine`` (its geometry: the swept volume and the crank mechanism);
    ``analysis``: a :class:`rotor.LogAnalysis` with a pressure channel and TDC;
    ``pressure_gain``: pascal per unit of the signal (the offset drops out of ∮p·dV).

    **Returns:** (cycles,) [Pa].
    """
    _check_single(engine, "measured_imep")
    w = _signal_work(engine, analysis)[:, -1]
    return float(pressure_gain) * w / float(engine.geometry.displacement_m3)


def _lowpass(x, max_order, P, revs):
    from scipy.signal import butter, filtfilt

    nyq = P / (2.0 * revs)  # orders per revolution
    wn = max_order / nyq
    if not 0 < wn < 1:
        raise EngineError(f"max_order = {max_order!r}: must lie between 0 and {nyq:g} (half the points per revolution)")
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
    Wu = _signal_work(engine, analysis)
    Wc = np.empty(C * P)
    acc = 0.0
    for k in range(C):
        Wc[k * P : (k + 1) * P] = acc + Wu[k, :P]
        acc += Wu[k, -1]
    Wc *= gain
    w2 = analysis.omega.reshape(-1) ** 2
    s, _ = _displacement(engine, psi)
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


def _scaled(engine, sigma):
    """The engine with its pressure's whole charge scaled by σ (:meth:`scale_charge`)."""
    return eqx.tree_at(lambda e: e.pressure, engine, engine.pressure.scale_charge(sigma))


def _check_scaling(scaling, engine, hint=""):
    if scaling not in SCALINGS:
        raise EngineError(f"scaling = {scaling!r}: one of {', '.join(SCALINGS)}")
    if scaling == "charge" and not engine.pressure.charge_scalable:
        raise EngineError(
            f"scaling='charge' scales a Wiebe cycle (intake_pa, imep_pa); engine {engine.name!r} has "
            f"{type(engine.pressure).__name__}{hint}"
        )


def _mean_scale(ident):
    ok = ident.identified & ~ident.misfire
    if not ok.any():
        ok = ident.identified
    return float(np.mean(ident.scale[ok]))


def _check_types(fn, engine, log, calibration, wheel, tdc_deg):
    """TypeError naming the argument of ``fn`` (diagnose or calibrate) of the wrong type."""
    from ..dynamics.result import SpeedResult
    from ..engine.model import Engine

    if not isinstance(engine, Engine):
        hint = " (load it first: rotor.load_engine(...))" if isinstance(engine, (str, os.PathLike)) else ""
        raise TypeError(f"{fn}(engine): expected a rotor.Engine{hint}, got {type(engine).__name__} {engine!r:.60}")
    if not isinstance(log, (str, os.PathLike, LogAnalysis, SpeedResult, np.ndarray)) and not (
        fn == "diagnose" and isinstance(log, (list, tuple))
    ):
        raise TypeError(
            f"{fn}(log): a log file's name (str or os.PathLike), a rotor.LogAnalysis"
            + (", a rotor.SpeedResult or a speed array (cycles, points) [rad/s]" if fn == "diagnose" else "")
            + f"; got {type(log).__name__}"
        )
    if calibration is not None and not isinstance(calibration, (Calibration, str, os.PathLike)):
        raise TypeError(
            f"{fn}(calibration): a rotor.Calibration, a calibration file's name, 'preset' or None; "
            f"got {type(calibration).__name__}"
        )
    if wheel is not None and not isinstance(wheel, str):
        from ..logs.wheel import Wheel

        if not isinstance(wheel, Wheel):
            raise TypeError(f"{fn}(wheel): a spec such as '60-2', a rotor.Wheel or None; got {type(wheel).__name__}")
    if (
        tdc_deg is not None
        and not (fn == "diagnose" and isinstance(tdc_deg, str))
        and (isinstance(tdc_deg, bool) or not isinstance(tdc_deg, (int, float, np.integer, np.floating)))
    ):
        raise TypeError(f"{fn}(tdc_deg): a number [deg] or None; got {type(tdc_deg).__name__}")


def _mismatch(engine, ident, misfire):
    """Lines saying where ``engine`` does not match the log it identified (see the module doc)."""
    from ..engine.forces import imep_pa

    out = []
    nominal = float(imep_pa(engine))
    ok = ident.identified & ~np.asarray(misfire)
    bad = []
    for c in range(ident.cylinders):
        if ok[:, c].any():
            m = float(np.mean(ident.imep_pa[ok[:, c], c]))
            if m > IMEP_MAX_PA or (nominal > 0 and m > IMEP_FACTOR_MAX * nominal):
                bad.append((c + 1, m))
    if bad:
        shown = ", ".join(f"cylinder {c} {m / PA_PER_BAR:.3g} bar" for c, m in bad[:4]) + (
            ", …" if len(bad) > 4 else ""
        )
        out.append(
            f"implausible IMEP for {engine.name!r}: {shown}, against the engine file's {nominal / PA_PER_BAR:.3g} bar "
            f"(over {IMEP_FACTOR_MAX:g}× it, or over {IMEP_MAX_PA / PA_PER_BAR:g} bar, which no engine reaches): "
            f"is it the engine of this log?"
        )
    rpm = float(np.mean(ident.mean_omega)) * RPM_PER_RAD_S
    op = float(engine.operating.rpm)
    piston = 2.0 * float(engine.geometry.stroke_m) * rpm / 60.0
    if rpm > SPEED_FACTOR_MAX * op or piston > PISTON_SPEED_MAX_M_S:
        out.append(
            f"the log runs at {rpm:.0f} rpm, {rpm / op:.2g}× the engine file's operating speed {op:.0f} rpm "
            f"(mean piston speed {piston:.3g} m/s): outside the engine's range"
        )
    n = ident.cylinders
    if n > 1 and not np.asarray(misfire).any() and float(ident.fit_r2) < PATTERN_R2:
        omega = np.asarray(ident.omega, dtype=np.float64)
        P = omega.shape[1]
        if P > 2 * n:
            amp = np.mean(np.abs(np.fft.rfft(omega - omega.mean(axis=1, keepdims=True), axis=1)), axis=0) * 2 / P
            revs = engine.strokes // 2
            k_low = int(np.argmax(amp[1:n])) + 1
            if amp[k_low] > PATTERN_FACTOR * amp[n]:
                out.append(
                    f"the firing pattern of {n} cylinders is not seen: the speed fluctuates {amp[k_low] / amp[n]:.3g}× "
                    f"more at order {k_low / revs:g} than at the firing order {n / revs:g}, and no misfire "
                    f"explains it: is it a log of this engine?"
                )
    return tuple(out)


# ----------------------------------------------------------------------------- calibrate
def calibrate(
    engine: Engine,
    log: str | os.PathLike | LogAnalysis,
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
      or a :class:`rotor.LogAnalysis` with a pressure channel and TDC from it.
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
    - ``tooth_errors``, ``load_per``: passed to :func:`rotor.analyze_log` and :func:`diagnose`.
    - ``edge``: ``"auto"`` (default: both read, the one that fits the wheel better taken,
      :func:`rotor.logs.track.read_track`), ``"rising"`` or ``"falling"`` edges of the wheel signal.

    **Returns:** :class:`Calibration`. Raises :class:`rotor.EngineError` /
    :class:`rotor.LogError` for what cannot be calibrated.
    """
    from ..logs.analysis import analyze_log

    _check_types("calibrate", engine, log, None, wheel, None)
    motored = pressure_gain == "motored" if isinstance(pressure_gain, str) else False
    if (
        pressure_gain is not None
        and not motored
        and (isinstance(pressure_gain, bool) or not isinstance(pressure_gain, (int, float, np.integer, np.floating)))
    ):
        raise TypeError(
            f"calibrate(pressure_gain): a number [Pa per signal unit], 'motored' or None, not {pressure_gain!r}"
        )
    _check_single(engine, "calibrate")
    _check_scaling(scaling, engine, ": use scaling='none'")
    if not (pressure_gain is None or isinstance(pressure_gain, str)) and not (
        np.isfinite(pressure_gain) and pressure_gain > 0
    ):
        raise EngineError(f"pressure_gain = {pressure_gain!r}: must be a positive number [Pa per signal unit]")
    rod_ratio = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
    if isinstance(log, LogAnalysis):
        a = log
    else:
        cr = getattr(engine.pressure, "compression_ratio", None)
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
    vh = float(engine.geometry.displacement_m3)
    from ..engine.forces import imep_pa as _imep

    w_cycle = _signal_work(engine, a)[:, -1]
    nominal = float(_imep(engine))
    pegged = None
    if pressure_gain is None or motored:
        from .pegging import motored_cycles, pressure_gain_from_motored

        if motored or (engine.strokes == 4 and motored_cycles(a).any()):
            pegged = pressure_gain_from_motored(engine, a, intake_pa=intake_pa)
    if pegged is not None:
        gain = pegged.gain_pa
        gain_from = f"motored cycles {', '.join(str(c) for c in pegged.cycles)}"
    elif pressure_gain is None:
        gain = nominal * vh / float(np.mean(w_cycle))
        gain_from = "engine file's IMEP"
    else:
        gain = float(pressure_gain)
        gain_from = "given"
    imep_cycles = gain * w_cycle / vh
    J_e, b_rel, a_k, figs = _energy_balance(engine, a, gain, max_order)
    offset = b_rel + float(engine.pressure.crankcase_pa)  # single-zone cycles
    imep_mean = float(np.mean(imep_cycles))
    if not imep_mean > 0:
        raise EngineError(
            f"{a.source}: no firing in the recording (mean IMEP {imep_mean / PA_PER_BAR:.3g} bar from the pressure "
            f"channel): the calibration needs fired cycles"
        )
    sigma = imep_mean / nominal if scaling == "charge" else 1.0
    fit = {
        "energy_balance_inertia_kgm2": J_e,
        "max_order": float(max_order),
        "cycles": int(a.cycles),
        "imep_measured_pa": imep_mean,
        "imep_measured_cycles_pa": imep_cycles.tolist(),
        "loss_torque_cycles_Nm": a_k.tolist(),
        "pressure_gain_from": gain_from,
        "energy_balance_offset_pa": float(offset),
        **({} if pegged is None else {"motored": pegged.to_json_dict()}),
        "mean_rpm": float(np.mean(a.mean_rpm)),
        "loss_mep_pa": float(np.mean(a_k)) * float(engine.cycle_rad) / vh,  # friction + load as a mean pressure
        **figs,
    }
    J = J_e
    if refine:
        eng_s = _scaled(engine, sigma) if scaling == "charge" else engine
        from .identification import identify

        def g(logJ):
            ident = identify(
                eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, eng_s, float(np.exp(logJ))), a, load_per=load_per
            )
            ident_mean = float(np.mean(ident.imep_pa[:, 0]))
            return math.log(max(ident_mean, 1.0)) - math.log(max(imep_mean, 1.0)), ident_mean

        x0 = math.log(J_e)
        g0, first = g(x0)
        fit["identified_imep_with_energy_balance_inertia_pa"] = first
        x1 = x0 - g0
        g1, _ = g(x1)
        steps = 2
        while abs(g1) > 1e-4 and steps < 8 and g1 != g0:
            x0, g0, x1 = x1, g1, x1 - g1 * (x1 - x0) / (g1 - g0)
            g1, _ = g(x1)
            steps += 1
        J = float(np.exp(x1))
        fit["refine_steps"] = steps
        fit["identified_imep_mismatch"] = float(math.expm1(g1))
    return Calibration(
        engine=engine.name,
        inertia_kgm2=float(J),
        tdc_after_gap_deg=float(np.rad2deg(a.tdc_rad)),
        pressure_gain_pa=float(gain),
        pressure_offset_pa=float(offset if pegged is None else pegged.offset_pa),
        loss_torque_Nm=float(np.mean(a_k)),
        scaling=scaling,
        charge_scale=float(sigma),
        wheel=a.track.wheel.spec if a.track is not None else "",
        tooth_errors=a.tooth_errors,
        source=a.source,
        fit=fit,
        cylinders=int(engine.cylinders),
        strokes=int(engine.strokes),
        geometry=_engine_geometry(engine),
    )


class DiagnosisVerdict(enum.Enum):
    """What a diagnosis concludes about the recording as a whole (a typed state)."""

    FITS = "the engine model explains the speed"
    NO_FIRING = "no firing found: the engine does not fire in this record (a coast-down or motored run)"
    MODEL_DOES_NOT_FIT = "the engine model does not fit this recording"


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Diagnosis(Identification):
    """What :func:`diagnose` found: an :class:`rotor.Identification` (every field of it)
    with the recording and the calibration it used.

    **Fields added:** ``calibration`` (the :class:`Calibration` used, or None);
    ``calibration_source`` (``"preset <path>"``, ``"file <path>"``, ``"given"``, or what the
    caller named it; None without one); ``analysis`` (the :class:`rotor.LogAnalysis` of the
    recording, or None for a speed array); ``scaling`` (``"charge"`` or ``"none"``);
    ``charge_scale`` σ [-] and ``charge_iterations`` (identifications it took);
    ``no_firing`` (the record holds no firing: every firing a misfire);
    ``measured_imep_pa`` (cycles,) [Pa]: the IMEP of each cycle from the recording's
    pressure channel with the calibration's gain (single cylinder), or None;
    ``mismatch``: one line per sign that the engine does not match the log (see the module
    doc; also among ``warnings``); ``tdc_check``: the calibration's TDC checked against the
    speed, or found from it (:class:`rotor.diagnostics.phase.TdcCheck`, None where not
    checked); ``cycle_flags``: per cycle the reason the data cannot support it, or ``""``
    (``supported``: the cycles without one); ``partial_deg``: the recording's span before
    the first whole cycle and after the last [deg], not diagnosed; ``phase_warning``: where
    the firing revolution came from a cam or pressure channel (or was given) and the speed's
    fit puts it in the other revolution, the line that says so (also among ``warnings``),
    else ``""``; ``verdict``: :class:`DiagnosisVerdict` — where the model does not explain
    the speed (a poor fit, an implausible IMEP, speed or firing pattern), the misfire flags
    are not judged (all ``False``) and no firing is concluded, and ``verdict_reason`` says
    what to check.

    ``summary()`` and ``to_json_dict()`` are what ``rotor diagnose`` prints.
    """

    calibration: Calibration | None = None
    calibration_source: str | None = None
    analysis: LogAnalysis | None = None
    scaling: str = "none"
    charge_scale: float = 1.0
    charge_iterations: int = 0
    no_firing: bool = False
    measured_imep_pa: np.ndarray | None = None
    mismatch: tuple = ()
    tdc_check: TdcCheck | None = None
    cycle_flags: tuple = ()
    partial_deg: tuple = (0.0, 0.0)
    phase_warning: str = ""
    verdict: DiagnosisVerdict = DiagnosisVerdict.FITS
    verdict_reason: str = ""

    @property
    def warnings(self) -> tuple[str, ...]:
        """The identification's warnings (a poor fit, with its likely cause where the
        calibration's tooth errors are another wheel's), a TDC corrected from the speed
        (:attr:`tdc_check`), and :attr:`mismatch`: where the engine does not match the log
        (see the module doc). Empty when there is nothing to warn about."""
        base = Identification.warnings.fget(self)  # type: ignore[attr-defined]
        chk = self.tdc_check
        if base and chk is not None and chk.tooth_mismatch > TOOTH_MISMATCH:
            base = (
                base[0] + f" (the calibration's tooth errors do not fit this wheel: they differ from the "
                f"recording's own estimate by {chk.tooth_mismatch:.2f}× their rms)",
                *base[1:],
            )
        own = (chk.message,) if chk is not None and chk.corrected else ()
        phase = (self.phase_warning,) if self.phase_warning else ()
        return tuple(base) + own + phase + tuple(self.mismatch)

    @property
    def supported(self) -> np.ndarray:
        """(cycles,) bool: the cycles whose figures the data support (no :attr:`cycle_flags` reason)."""
        if not self.cycle_flags:
            return np.ones(self.cycles, dtype=bool)
        return np.array([not f for f in self.cycle_flags], dtype=bool)

    @property
    def source(self) -> str | None:
        """The recording's name (None for a speed array)."""
        return None if self.analysis is None else self.analysis.source

    def summary(self) -> str:
        """The calibration (if any) and where it came from, the identification's summary,
        and the identified IMEP against the pressure channel's (if measured)."""
        text = ""
        if self.calibration is not None:
            text += self.calibration.summary() + f"  calibration: {self.calibration_source}\n"
        if self.tdc_check is not None and not self.tdc_check.corrected:
            text += f"  {self.tdc_check.message}\n"
        if self.verdict is DiagnosisVerdict.MODEL_DOES_NOT_FIT:
            text += f"  verdict: {self.verdict.value}: {self.verdict_reason}\n"
        text += Identification.summary(self)
        flagged = [(k, f) for k, f in enumerate(self.cycle_flags, start=1) if f]  # cycles from 1
        if flagged:
            text += f"  {len(flagged)} of {self.cycles} cycles not supported by the data:\n" + "".join(
                f"    cycle {k}: {f}\n" for k, f in flagged[:8]
            )
            if len(flagged) > 8:
                text += f"    … and {len(flagged) - 8} more (see --json)\n"
        lead, tail = self.partial_deg
        if lead > 0 or tail > 0:
            text += (
                f"  the recording holds {lead:.0f}° before the first whole cycle and {tail:.0f}° after the last: "
                f"not diagnosed (partial cycles)\n"
            )
        if self.measured_imep_pa is not None:
            measured = self.measured_imep_pa
            err = self.imep_pa[:, 0] - measured
            text += (
                f"  IMEP from the pressure channel {np.mean(measured) / PA_PER_BAR:.3f} bar; identified − measured: "
                f"mean {np.mean(err) / PA_PER_BAR:+.3f} bar, rms {np.sqrt(np.mean(err**2)) / PA_PER_BAR:.3f} bar\n"
            )
        return text

    def plot(self, ax: Any = None, kind: str | None = None) -> Any:
        """The identification's plot (:meth:`rotor.Identification.plot`, ``kind`` as there)
        with the IMEP the pressure channel measured per cycle (``measured_imep_pa``, when
        there is one) over the identified IMEP. Returns the three Axes, or with ``kind`` the
        one."""
        from ..plotting.diagnostics import plot_identification

        title = f"{self.engine_name}: speed; rms residual {self.rms_residual:.3g} rad/s, R² {self.fit_r2:.4f}"
        if Identification.warnings.fget(self):  # type: ignore[attr-defined]
            title += " (poor fit)"
        if self.mismatch:
            title += " (the engine does not match the log?)"
        return plot_identification(
            omega=self.omega,
            omega_model=self.omega_model,
            cylinder_torques=self.cylinder_torques(),
            imep_pa=self.imep_pa,
            imep_std_pa=self.imep_std_pa,
            misfire=self.misfire,
            title=title,
            measured_imep_pa=self.measured_imep_pa,
            ax=ax,
            kind=kind,
        )

    def to_json_dict(self, written: Sequence[str] = ()) -> dict:
        """What ``rotor diagnose --json`` prints: per cycle its number ``cycle`` (from 1, as
        in ``misfires`` and ``unsupported_cycles``), the start time [s], mean speed [rpm], each cylinder's IMEP and its standard deviation [Pa], misfire flags,
        contributions, load torque [N·m] (and the IMEP measured by the pressure channel);
        the misfires, the calibration, σ, TDC and the fit. ``written``: the files the
        command wrote, listed last. ``None``, never NaN."""
        a = self.analysis
        t0 = self.t_start_s
        cycles = []
        for k in range(self.cycles):
            row = {
                "cycle": k + 1,
                "t_start_s": None if t0 is None else t0[k],
                "mean_rpm": self.mean_omega[k] * RPM_PER_RAD_S,
                "imep_pa": self.imep_pa[k],
                "imep_std_pa": self.imep_std_pa[k],
                "misfire": self.misfire[k],
                "contribution": self.contribution[k],
                "load_torque_Nm": self.load_torque_Nm[k],
            }
            if self.measured_imep_pa is not None:
                row["measured_imep_pa"] = [self.measured_imep_pa[k]]
            flag = self.cycle_flags[k] if k < len(self.cycle_flags) else ""
            row["supported"] = not flag
            row["flag"] = flag or None
            cycles.append(row)
        cal = self.calibration
        return json_safe(
            {
                "engine": self.engine_name,
                "source": self.source,
                "cylinders": self.cylinders,
                "cycles": cycles,
                "misfires": self.misfires(),
                "verdict": self.verdict.name.lower(),
                "verdict_reason": self.verdict_reason or None,
                "calibration": None if cal is None else {**cal.to_json_dict(), "loaded_from": self.calibration_source},
                "calibration_source": self.calibration_source,
                "ambiguous_pairs": [list(p) for p in self.ambiguous_pairs],
                "scaling": self.scaling,
                "charge_scale": self.charge_scale,
                "tdc_after_gap_deg": None if a is None else np.rad2deg(a.tdc_rad),
                "tdc_check": None if self.tdc_check is None else self.tdc_check.to_json_dict(),
                "partial_cycles_deg": {"before_first": self.partial_deg[0], "after_last": self.partial_deg[1]},
                "unsupported_cycles": [k for k, f in enumerate(self.cycle_flags, start=1) if f],
                "tdc_method": None if a is None else a.tdc_method,
                "firing_method": None if a is None else a.firing_method,
                "rms_residual_rad_s": self.rms_residual,
                "r2": self.fit_r2,
                "warnings": list(self.warnings),
                "mismatch": list(self.mismatch),
                "threshold": self.threshold,
                "notes": list(self.notes) + (list(a.notes) if a is not None else []),
                "written": list(written),
            }
        )


# ----------------------------------------------------------------------------- diagnose
def diagnose(
    engine: Engine,
    log: str | os.PathLike | LogAnalysis | SpeedResult | np.ndarray,
    calibration: Calibration | str | os.PathLike | None = "preset",
    *,
    wheel: str | None = None,
    columns: str | Sequence[str] | None = None,
    tdc_deg: float | None = None,
    firing: str | int = "auto",
    load_per: str = "block",
    scaling: str | None = None,
    max_iterations: int = 8,
    calibration_source: str | None = None,
    edge: str = "auto",
    check_tdc: bool = True,
    **identify_kwargs: Any,
) -> Diagnosis:
    """Per-firing IMEP, load and misfires of a recording from its crank speed alone, with a
    calibration (see the module doc).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`; its crankshaft inertia is replaced by the
      calibration's.
    - ``log``: a file (read with ``wheel`` (default the calibration's), ``columns``; TDC
      ``tdc_deg`` or the calibration's, tooth errors the calibration's), a
      :class:`rotor.LogAnalysis`, or anything :func:`rotor.identify` takes.
    - ``calibration``: a :class:`Calibration`, the path of a saved one, ``"preset"``
      (default: the one shipped with the engine's preset, e.g. ``tue-single``, else none)
      or None (the engine as it is). A calibration of another engine (name, cylinders,
      strokes, geometry) is refused.
    - ``load_per``: of :func:`rotor.identify` (default ``"block"``: a steady load).
    - ``scaling``: ``"charge"`` or ``"none"`` (default: the calibration's, else ``"none"``).
    - ``max_iterations``: of the charge-scale iteration; other keywords go to
      :func:`rotor.identify`.
    - ``calibration_source``: how the result names where the calibration came from
      (default ``"preset <path>"``, ``"file <path>"`` or ``"given"``).
    - ``edge``: ``"auto"`` (default: both read, the one that fits the wheel better taken,
      :func:`rotor.logs.track.read_track`), ``"rising"`` or ``"falling"`` edges of the wheel signal.
    - ``tdc_deg``: angle from the gap to cylinder 1's TDC [deg] (default the calibration's,
      else from a pressure channel), or ``"speed"``: found from the recording's speed alone
      (:func:`rotor.diagnostics.phase.tdc_from_speed`); refused with the reason
      (:class:`rotor.diagnostics.phase.TdcNotDetermined`) where the speed cannot determine it.
    - ``check_tdc``: check a calibration's TDC against the recording's speed (default True,
      see below).

    **A calibration checked against the recording** (a log file whose TDC comes from the
    calibration): the engine's speed signature is fitted at every offset
    (:func:`rotor.diagnostics.phase.check_tdc`), on the recording's own tooth-error estimate
    where the calibration's tooth errors are another wheel's. A TDC that the speed
    determines and that lies more than 3 of its stated σ from the speed's
    (:class:`rotor.diagnostics.phase.TdcVerdict` ``DISAGREES``; the σ holds the engine
    model's own error) is **corrected** and a warning says so, with both TDCs and how many σ
    apart; one the speed contradicts but cannot replace, or a speed with no engine
    signature at all, is refused (:class:`rotor.diagnostics.phase.TdcNotDetermined`, the
    measured offset in the message); otherwise the calibration's TDC is kept (the firing
    revolution taken from the fit) and a note says how well it agrees. ``tdc_check`` of
    the result holds the figures. Where the log gives the firing revolution itself (a cam
    channel; a pressure channel) or ``firing`` is given, that phase is kept at the TDC used,
    and the fit's firing revolution is checked against it: a note where they agree, a
    warning (``phase_warning``) where the fit puts firing TDC one revolution away.

    **Recordings of any length**: the partial cycles at the record's ends are not diagnosed
    (``partial_deg`` says how much), and every cycle whose figures the data cannot support
    carries its reason in ``cycle_flags`` (a firing cut by the record's end; a cycle the
    model explains poorly), listed in the text and as ``supported``/``flag`` per cycle in the JSON.

    **Returns:** a :class:`Diagnosis`: the :class:`rotor.Identification` with the
    calibration used, where it came from, the charge scale σ, the
    :class:`rotor.LogAnalysis` of the recording and the IMEP its pressure channel measured
    (if it has one and a calibration gives the sensor's gain).

    **No firing** (a coast-down, fuel cut): where the firings' mean combustion scale lies
    below the misfire floor (:data:`rotor.diagnostics.misfire.FLOOR_SCALE`) the charge iteration stops
    (σ stays the calibration's), every firing is a misfire, and a note says so. σ is kept
    within :data:`SIGMA_RANGE`.
    """
    from ..logs.analysis import analyze_log
    from .identification import identify
    from .misfire import FLOOR_SCALE

    _check_types("diagnose", engine, log, calibration, wheel, tdc_deg)
    cal_source = None
    if isinstance(calibration, str) and calibration == "preset":
        found = preset_calibration(engine)
        calibration, cal_source = (None, None) if found is None else (found[0], f"preset {found[1]}")
    elif calibration is not None and not isinstance(calibration, Calibration):
        cal_source = f"file {os.fspath(calibration)}"
        calibration = Calibration.load(calibration)
    elif calibration is not None:
        cal_source = "given"
    if calibration is not None:
        calibration.check_engine(engine, where=cal_source if cal_source not in (None, "given") else "calibration")
    if calibration_source is not None:
        cal_source = calibration_source
    if scaling is None:
        scaling = calibration.scaling if calibration is not None else "none"
    _check_scaling(scaling, engine)
    analysis: LogAnalysis | None = None
    eng = calibration.apply(engine) if calibration is not None else engine
    from_speed = isinstance(tdc_deg, str)
    if from_speed and tdc_deg != "speed":
        raise TypeError(
            f"diagnose(tdc_deg): expected an angle [deg], 'speed' (from the speed alone) or None, got {tdc_deg!r}"
        )
    if from_speed and not isinstance(log, (str, os.PathLike)):
        raise EngineError("tdc_deg='speed' needs a log file (a wheel's gap to count the angle from)")
    check: TdcCheck | None = None
    phase_warning = phase_note = ""
    if isinstance(log, (str, os.PathLike)):
        if tdc_deg is None and calibration is None:  # a log that states its phase (rotor simulate --record)
            from .stated import stated_phase

            stated = stated_phase(log)
            if stated is not None:
                tdc_deg = stated[0]
                firing = stated[1] if firing == "auto" else firing
                phase_note = (
                    f"TDC {tdc_deg:g}° after the gap and the firing revolution as the log's header states them "
                    "(# tdc_after_gap_deg, # firing_parity)"
                )
        from_calibration = tdc_deg is None and calibration is not None
        if from_calibration:
            tdc_deg = calibration.tdc_after_gap_deg  # type: ignore[union-attr]
        w = wheel or (calibration.wheel if calibration is not None and calibration.wheel else None)
        te = "estimate" if calibration is None or calibration.tooth_errors is None else calibration.tooth_errors
        rod_ratio = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
        cr = getattr(engine.pressure, "compression_ratio", None)

        # the file is read and its wheel signal placed once; each TDC or firing revolution tried reuses it
        source_log = read_log(log, columns)
        reading = (
            read_track(source_log, w, edge=edge, name=os.path.basename(os.fspath(log)))
            if source_log.kind != "speed" and w is not None
            else None
        )
        if reading is not None and isinstance(te, ToothErrors) and parse_wheel(te.wheel) != reading.wheel:
            origin = (
                f"the preset's own calibration, {cal_source[len('preset ') :]}"
                if cal_source is not None and cal_source.startswith("preset ")
                else f"the calibration{f' ({cal_source})' if cal_source else ''}"
            )
            raise LogError(
                f"{reading.source}: {origin} holds the tooth errors of a {te.wheel} wheel, and this log's wheel is "
                f"{reading.wheel.spec}: give a calibration made on this wheel (calibration=, --calibration FILE) or "
                f"none (calibration=None, --no-calibration)"
            )

        def read(tdc, fire, teeth):
            return analyze_log(
                reading if reading is not None else source_log,
                w,
                columns=columns,
                strokes=engine.strokes,
                cylinders=engine.cylinders,
                tdc_deg=tdc,
                firing=fire,
                tooth_errors=teeth,
                compression_ratio=None if cr is None else float(cr),
                rod_ratio=None if cr is None else rod_ratio,
                edge=edge,
            )

        analysis = read(0.0 if from_speed else tdc_deg, firing, te)
        if analysis.tdc_source is PhaseSource.UNKNOWN:
            raise EngineError(
                f"{analysis.source}: TDC is not known: give a calibration (--calibration), tdc_deg "
                f"(--tdc-deg DEG, or --tdc-deg speed: from the speed alone) or a pressure channel"
            )
        if analysis.kind != "speed" and (from_speed or (from_calibration and check_tdc)):
            check = _speed_check(eng, analysis, None if from_speed else float(tdc_deg), te, read)  # type: ignore[arg-type]
            # a firing revolution from a cam or pressure channel, or given, stands: re-read at the TDC used with it
            own_phase = firing not in ("auto", "speed") or analysis.firing_source in CHANNELS
            if own_phase and check.verdict in (TdcVerdict.DISAGREES, TdcVerdict.FOUND):
                analysis = read(check.used_deg, firing, te)
                if firing == "auto" and analysis.firing_source not in CHANNELS:
                    own_phase = False  # the channel no longer decides at this TDC: the fit's revolution
            if own_phase:
                phase_warning = _phase_agreement(check, analysis)
                if not phase_warning and check.firing_parity is not None:
                    phase_note = (
                        f"firing revolution from the log ({analysis.firing_method}), where the speed's fit puts it too"
                    )
            elif check.verdict in (TdcVerdict.DISAGREES, TdcVerdict.FOUND) or (
                check.firing_parity is not None and check.firing_parity != analysis.firing_parity
            ):
                analysis = read(check.used_deg, firing if check.firing_parity is None else check.firing_parity, te)
        speed: LogAnalysis | SpeedResult | np.ndarray = analysis
    else:
        speed = log
    sigma = calibration.charge_scale if (calibration is not None and scaling == "charge") else 1.0
    lo, hi = (math.log(v) for v in SIGMA_RANGE)
    iters = 0
    extra = []
    no_firing = False
    settled = True
    if scaling == "charge":
        sigma = min(max(sigma, SIGMA_RANGE[0]), SIGMA_RANGE[1])
        try:
            xa = math.log(sigma)
            ident = identify(_scaled(eng, sigma), speed, load_per=load_per, **identify_kwargs)
            iters = 1
            ma = _mean_scale(ident)
            if not (math.isfinite(ma) and ma > FLOOR_SCALE):
                no_firing = True
                extra.append(
                    f"charge scaling stopped: no firing (mean combustion scale {ma:.3f}, below the misfire "
                    f"floor {FLOOR_SCALE:g}): every firing a misfire, σ kept at {sigma:.4g}"
                )
            else:
                ga = math.log(ma)
                xb = min(max(xa + ga, lo), hi)
                while abs(ga) > 1e-3 and iters < max_iterations and xb != xa:
                    idb = identify(_scaled(eng, math.exp(xb)), speed, load_per=load_per, **identify_kwargs)
                    iters += 1
                    mb = _mean_scale(idb)
                    if not (math.isfinite(mb) and mb > FLOOR_SCALE):
                        break  # keep the last σ with a firing
                    gb = math.log(mb)
                    xn = xb - gb * (xb - xa) / (gb - ga) if gb != ga else xb
                    xa, ga, ident = xb, gb, idb
                    xb = min(max(xn, lo), hi)
                sigma = math.exp(xa)
                settled = abs(ga) <= 1e-3
                if not settled:
                    at = " (at the bound of its range)" if xb in (lo, hi) or xa in (lo, hi) else ""
                    extra.append(
                        f"the charge scale did not settle in {iters} identification{'s' if iters != 1 else ''}{at} (σ {sigma:.4g}, "
                        f"mean combustion scale {math.exp(ga):.3f})"
                    )
        except ArithmeticError as e:
            raise EngineError(f"diagnose: the charge-scale iteration failed ({e}); try scaling='none'") from None
    else:
        ident = identify(eng, speed, load_per=load_per, **identify_kwargs)
        if ident.identified.any() and not _mean_scale(ident) > FLOOR_SCALE:
            no_firing = True
            if NO_FIRING_NOTE not in ident.notes:
                extra.append(
                    f"no firing (mean combustion scale below the misfire floor {FLOOR_SCALE:g}): every firing a misfire"
                )
    if isinstance(log, LogAnalysis):
        analysis = log
    if cal_source is not None and cal_source.startswith("preset"):
        extra.append(f"calibration: the preset's own ({cal_source[len('preset ') :]})")
    measured = None
    if calibration is not None and analysis is not None and analysis.pressure is not None and engine.cylinders == 1:
        measured = measured_imep(engine, analysis, calibration.pressure_gain_pa)
    if check is not None and not check.corrected:
        extra.append(check.message)
    if phase_note:
        extra.append(phase_note)
    fields = {f.name: getattr(ident, f.name) for f in dataclasses.fields(Identification)}
    fields["notes"] = ident.notes + tuple(extra)
    if no_firing:
        fields["misfire"] = ident.misfire | ident.identified
    mismatch = _mismatch(engine, ident, fields["misfire"])
    verdict = DiagnosisVerdict.NO_FIRING if no_firing else DiagnosisVerdict.FITS
    verdict_reason = ""
    structure = _residual_structure(ident, engine.strokes)
    poor = not float(ident.fit_r2) >= POOR_FIT_R2 and not structure <= RESIDUAL_STRUCTURE_MAX
    if poor or mismatch:
        # a model that does not explain the speed says nothing about firing or misfires
        verdict = DiagnosisVerdict.MODEL_DOES_NOT_FIT
        why = [
            f"it explains {max(float(ident.fit_r2), 0.0):.0%} of the speed's fluctuation (R² below {POOR_FIT_R2:g}), "
            f"and what it leaves is no noise: {structure:.3g}× more per harmonic at the low orders than at the high ones"
        ]
        if not poor:
            why = ["the identified figures are implausible (see the warnings)"]
        verdict_reason = (
            "; ".join(why) + ": check the engine file, the wheel and its edge, and TDC; the misfires are not judged"
        )
        no_firing = False
        fields["misfire"] = np.zeros_like(np.asarray(ident.misfire, dtype=bool))
        fields["notes"] = tuple(n for n in fields["notes"] if n != NO_FIRING_NOTE)
    return Diagnosis(
        **fields,
        calibration=calibration,
        calibration_source=cal_source,
        analysis=analysis,
        scaling=scaling,
        charge_scale=float(sigma),
        charge_iterations=iters,
        no_firing=no_firing,
        measured_imep_pa=measured,
        mismatch=mismatch,
        tdc_check=check,
        cycle_flags=_cycle_flags(ident, fields["misfire"]),
        partial_deg=_partial(analysis),
        phase_warning=phase_warning,
        verdict=verdict,
        verdict_reason=verdict_reason,
    )


CHANNELS = (PhaseSource.CAM, PhaseSource.PRESSURE)  # a firing revolution from a recorded channel
RESIDUAL_STRUCTURE_MAX = 2.0
"""A fit's residual whose power per harmonic at the engine's low orders (0.5 … 4) is more than
this many times that at the higher ones is the model's misfit, not the wheel's noise (whose
power, from timer jitter, grows with the order): with a poor R², the model does not fit."""


def _residual_structure(ident, strokes: int) -> float:
    """The residual's mean power per harmonic at orders up to 4 over that from there to a quarter
    of the grid's resolution [-], the median over the cycles (NaN where the grid is too coarse)."""
    r = np.asarray(ident.omega, dtype=np.float64) - np.asarray(ident.omega_model, dtype=np.float64)
    if r.ndim != 2 or r.shape[1] < 64:
        return float("nan")
    revs = max(int(strokes) // 2, 1)
    k_lo = 4 * revs  # harmonics of the cycle up to order 4
    X = np.abs(np.fft.rfft(r, axis=1)) ** 2
    lo = X[:, 1 : k_lo + 1].mean(axis=1)
    hi = X[:, k_lo + 1 : r.shape[1] // 4].mean(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.nanmedian(lo / hi))


def _speed_check(eng, analysis, given_deg, te, read):
    """Check (or find, ``given_deg`` None) TDC from the speed of ``analysis``: the fit on the
    recording's own tooth-error estimate where the given ones are another wheel's."""
    from ..logs.wheel import ToothErrors
    from .phase import check_tdc, tdc_from_speed, tooth_error_mismatch

    fit_on, te_mismatch = analysis, float("nan")
    if isinstance(te, ToothErrors):
        try:
            own = read(0.0 if given_deg is None else given_deg, analysis.firing_parity, "estimate")
        except LogError:
            own = None
        if own is not None and own.tooth_errors is not None:
            te_mismatch = tooth_error_mismatch(te, own.tooth_errors)
            if not te_mismatch <= TOOTH_MISMATCH:
                fit_on = own
    fit = tdc_from_speed(eng, fit_on)
    return check_tdc(fit, given_deg, what="the calibration's", tooth_mismatch=te_mismatch)


def _phase_agreement(check, analysis):
    """Where the firing revolution came from a cam or pressure channel (or was given) and the
    speed's fit puts firing TDC in the other revolution: the line that says so ("" where they
    agree, or the fit has no firing revolution)."""
    fit_parity = check.firing_parity
    if fit_parity is None or analysis.firing_parity is None or fit_parity == analysis.firing_parity:
        return ""
    return (
        f"firing revolution: the {analysis.firing_source.value} channel's kept"
        if analysis.firing_source in CHANNELS
        else "firing revolution: the one given kept"
    ) + (
        f"; the speed's fit puts firing TDC one revolution away ({check.fit.separation:.0f} σ separation): "
        f"check the {'cam' if analysis.firing_source is PhaseSource.CAM else 'firing'} channel's phase"
    )


def _cycle_flags(ident, misfire):
    """Per cycle: why the data cannot support its figures, or "" (see :class:`Diagnosis`)."""
    out = []
    r2 = np.asarray(ident.r2, dtype=np.float64).reshape(-1)
    for k in range(ident.cycles):
        why = []
        cut = ~np.asarray(ident.identified[k], dtype=bool)
        if cut.any():
            cyl = ", ".join(str(c + 1) for c in np.flatnonzero(cut))
            why.append(f"firing of cylinder {cyl} cut by the record's end (tied to its neighbour)")
        if k < r2.size and np.isfinite(r2[k]) and r2[k] < POOR_FIT_R2 and not np.asarray(misfire[k]).all():
            why.append(f"the model explains little of this cycle's speed (R² {r2[k]:.2f})")
        out.append("; ".join(why))
    return tuple(out)


def _partial(analysis):
    """The recording's span before the first whole cycle and after the last [deg]."""
    if analysis is None or analysis.track is None or analysis.cycles == 0:
        return (0.0, 0.0)
    phi = analysis.track.nominal_angle
    lead = float(analysis.cycle_start_rad[0] - phi[0])
    tail = float(phi[-1] - (analysis.cycle_start_rad[-1] + analysis.cycle_rad))
    return (max(float(np.rad2deg(lead)), 0.0), max(float(np.rad2deg(tail)), 0.0))
