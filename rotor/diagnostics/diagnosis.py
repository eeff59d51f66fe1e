"""The diagnose workflow: per-firing IMEP, load and misfires of a recording from its crank
speed alone, with a calibration (:mod:`rotor.diagnostics.calibration`).

:func:`diagnose` reads the recording (its TDC from the calibration, the log's own header,
a pressure channel, or the speed alone), checks a calibration's TDC against the speed
(:mod:`rotor.diagnostics.phase`), identifies each firing (:func:`rotor.identify`) with
the calibrated inertia and the charge scaled (:mod:`rotor.diagnostics.charge`), and says
whether the engine model explains the recording at all (:class:`DiagnosisVerdict`).
:class:`Diagnosis` holds the :class:`rotor.Identification` (``identification``) with
the recording and the calibration it used.

**Charge scaling** (``scaling="charge"``, a calibration's default): a throttled
spark-ignition engine changes its load by the intake pressure; the file's Wiebe cycle is
scaled as a whole until the firings' mean combustion scale is 1. On ``tue-single``'s
bench recordings (no load to full load, compression pressure 60° before TDC 1.15 to
2.89 bar) it cut the speed-only IMEP error at half load from −0.28 to −0.06 bar and at no
load from −0.60 to −0.19 bar. ``scaling="none"`` keeps the file's cycle (diesels, or a
table pressure).

**A preset's own calibration** (:func:`rotor.diagnostics.calibration_record.preset_calibration`):
:func:`diagnose` uses it when no calibration is given (``calibration="preset"``, the
default; ``None``: the engine file as it is). A calibration stores its engine's name,
cylinders, strokes and geometry, and one of another engine is refused.

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
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np

from ..errors import EngineError, LogError
from ..logs.analysis import LogAnalysis, PhaseSource, analyze_log
from ..logs.reader import read_log
from ..logs.recording import PatternReading, ReadingRecord, read_wheel
from ..logs.track import WheelReading
from ..logs.wheel import TooFewOrders, ToothErrors, parse_wheel
from ..results import Result, json_safe
from ..units import PA_PER_BAR, RPM_PER_RAD_S
from .calibration_record import Calibration, check_argument_types, preset_calibration
from .charge import ChargeFit, check_scaling, fit_charge
from .identification import NO_FIRING_NOTE, POOR_FIT_R2, Identification
from .phase import TOOTH_MISMATCH, TdcCheck, TdcVerdict
from .pressure_work import measured_imep

if TYPE_CHECKING:
    from ..dynamics.result import SpeedResult
    from ..engine.model import Engine

__all__ = [
    "Diagnosis",
    "DiagnosisVerdict",
    "diagnose",
    "IMEP_FACTOR_MAX",
    "IMEP_MAX_PA",
    "SPEED_FACTOR_MAX",
    "PISTON_SPEED_MAX_M_S",
    "PATTERN_FACTOR",
    "PATTERN_R2",
]

IMEP_FACTOR_MAX = 3.0  # identified IMEP over the engine file's: above, the engine does not match the log
IMEP_MAX_PA = 40e5  # no engine reaches this IMEP [Pa] (see the module doc)
SPEED_FACTOR_MAX = 2.0  # the log's mean speed over the engine file's operating speed
PISTON_SPEED_MAX_M_S = 25.0  # mean piston speed beyond racing engines [m/s]
PATTERN_FACTOR = 3.0  # a lower order this many times the firing order's amplitude: the pattern is not seen
PATTERN_R2 = 0.9  # … looked for only where the fit explains less than this of the speed fluctuation
CHANNELS = (PhaseSource.CAM, PhaseSource.PRESSURE)  # a firing revolution from a recorded channel
RESIDUAL_STRUCTURE_MAX = 2.0
"""A fit's residual whose power per harmonic at the engine's low orders (0.5 … 4) is more than
this many times that at the higher ones is the model's misfit, not the wheel's noise (whose
power, from timer jitter, grows with the order): with a poor R², the model does not fit."""


class DiagnosisVerdict(enum.Enum):
    """What a diagnosis concludes about the recording as a whole (a typed state)."""

    FITS = "the engine model explains the speed"
    NO_FIRING = "no firing found: the engine does not fire in this record (a coast-down or motored run)"
    MODEL_DOES_NOT_FIT = "the engine model does not fit this recording"


_T = TypeVar("_T")


class _Identified(Generic[_T]):
    """A read-only attribute of a :class:`Diagnosis` that is its identification's of the same
    name (``diagnosis.imep_pa`` is ``diagnosis.identification.imep_pa``)."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.__doc__ = f"The identification's ``{name}`` (:class:`rotor.Identification`)."

    def __get__(self, obj: Any, owner: type | None = None) -> _T:
        if obj is None:
            return self  # type: ignore[return-value]  # the class's own attribute: this descriptor
        return getattr(obj.identification, self.name)


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Diagnosis(Result):
    """What :func:`diagnose` found: the :class:`rotor.Identification` of the recording
    (``identification``) with the recording and the calibration it used.

    **Fields:** ``identification``: the :class:`rotor.Identification` (its misfire flags
    and notes as the diagnosis concludes them); its figures read as the diagnosis's own
    too (``diagnosis.imep_pa``, ``diagnosis.misfire``, ``diagnosis.misfires()``, …).
    ``calibration`` (the :class:`rotor.Calibration` used, or None);
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
    what to check; ``coverage``: where the recording lies outside the speeds and loads its
    calibration's recordings cover (:meth:`rotor.Calibration.outside`), the line that says
    so (also among ``warnings``, every cycle flagged, ``supported: false`` in the JSON), else ``""``.

    ``summary()`` and ``to_json_dict()`` are what ``rotor diagnose`` prints.
    """

    identification: Identification
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
    coverage: str = ""

    # the identification's figures, read as the diagnosis's own
    scale = _Identified[np.ndarray]()
    scale_std = _Identified[np.ndarray]()
    imep_pa = _Identified[np.ndarray]()
    imep_std_pa = _Identified[np.ndarray]()
    identified = _Identified[np.ndarray]()
    contribution = _Identified[np.ndarray]()
    misfire = _Identified[np.ndarray]()
    reference_scale = _Identified[np.ndarray]()
    load_torque_Nm = _Identified[np.ndarray]()
    load_std_Nm = _Identified[np.ndarray]()
    loss_torque_Nm = _Identified[np.ndarray]()
    mean_omega = _Identified[np.ndarray]()
    covariance = _Identified[np.ndarray]()
    rms_residual_rad_s = _Identified[np.ndarray]()
    r2 = _Identified[np.ndarray]()
    omega = _Identified[np.ndarray]()
    omega_model = _Identified[np.ndarray]()
    rms_residual = _Identified[float]()
    fit_r2 = _Identified[float]()
    relative_residual = _Identified[float]()
    imep_nominal_pa = _Identified[np.ndarray]()
    threshold = _Identified[float]()
    engine = _Identified["Engine"]()
    ambiguous_pairs = _Identified[tuple]()
    t_start_s = _Identified["np.ndarray | None"]()
    notes = _Identified[tuple]()
    engine_name = _Identified[str]()
    wall_s = _Identified[float]()
    blocks = _Identified[int]()
    block_cycles = _Identified[int]()
    block_starts = _Identified[tuple]()
    iterations = _Identified[tuple]()
    table_points = _Identified[int]()
    load_per = _Identified[str]()
    cycles = _Identified[int]()
    cylinders = _Identified[int]()
    imep_cycle_std_pa = _Identified[np.ndarray]()

    def misfires(self) -> list:
        """The misfires as (cycle, cylinder) pairs, both from 1 (:meth:`rotor.Identification.misfires`)."""
        return self.identification.misfires()

    def cylinder_torques(self) -> np.ndarray:
        """Each cylinder's identified gas torque (:meth:`rotor.Identification.cylinder_torques`)."""
        return self.identification.cylinder_torques()

    @property
    def warnings(self) -> tuple[str, ...]:
        """The identification's warnings (a poor fit, with its likely cause where the
        calibration's tooth errors are another wheel's), a TDC corrected from the speed
        (:attr:`tdc_check`), and :attr:`mismatch`: where the engine does not match the log
        (see the module doc). Empty when there is nothing to warn about."""
        base = self.identification.warnings
        chk = self.tdc_check
        if base and chk is not None and chk.tooth_mismatch > TOOTH_MISMATCH:
            base = (
                base[0] + f" (the calibration's tooth errors do not fit this wheel: they differ from the "
                f"recording's own estimate by {chk.tooth_mismatch:.2f}× their rms)",
                *base[1:],
            )
        own = (chk.message,) if chk is not None and chk.corrected else ()
        phase = (self.phase_warning,) if self.phase_warning else ()
        cover = (self.coverage,) if self.coverage else ()
        return tuple(base) + own + phase + tuple(self.mismatch) + cover

    def cylinder_imep_pa(self) -> np.ndarray:
        """Each cylinder's mean identified IMEP over its normal firings (identified, not a
        misfire), the figure the text's table shows [Pa], (cylinders,) (NaN where none)."""
        return _cylinder_means(self.identification, self.misfire)

    def mean_rpm(self) -> np.ndarray:
        """Each cycle's time-mean speed [rpm], (cycles,): the harmonic mean of the speed on the
        uniform angle grid (the cycle's angle over its duration), not the angle mean
        (:attr:`mean_omega`)."""
        return _time_mean_rpm(self.identification)

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
        """The calibration (if any) and where it came from, the identification's summary
        (with the diagnosis's :attr:`warnings`), and the identified IMEP against the
        pressure channel's (if measured)."""
        text = ""
        if self.calibration is not None:
            text += self.calibration.summary() + f"  calibration: {self.calibration_source}\n"
        if self.tdc_check is not None and not self.tdc_check.corrected:
            text += f"  {self.tdc_check.message}\n"
        if self.verdict is DiagnosisVerdict.MODEL_DOES_NOT_FIT:
            text += f"  verdict: {self.verdict.value}: {self.verdict_reason}\n"
        text += self.identification.summary(warnings=self.warnings)
        if self.coverage:
            text += f"  not supported: {self.coverage}\n"
        flagged = [(k, f) for k, f in enumerate(self.cycle_flags, start=1) if f]  # cycles from 1
        if flagged:
            text += f"  {len(flagged)} of {self.cycles} cycles not supported by the data:\n" + "".join(
                f"    cycle {k}: {f}\n" for k, f in flagged[:8]
            )
            if len(flagged) > 8:
                text += f"    … and {len(flagged) - 8} more (listed in the JSON)\n"
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

    def to_pandas(self) -> Any:
        """The identification's table (:meth:`rotor.Identification.to_pandas`): one row per
        cycle and cylinder."""
        return self.identification.to_pandas()

    def plot(self, ax: Any = None, kind: str | None = None) -> Any:
        """The identification's plot (:meth:`rotor.Identification.plot`, ``kind`` as there)
        with the IMEP the pressure channel measured per cycle (``measured_imep_pa``, when
        there is one) over the identified IMEP. Returns the three Axes, or with ``kind`` the
        one."""
        end = " (the engine does not match the log?)" if self.mismatch else ""
        return self.identification._plot(ax, kind, end, self.measured_imep_pa)

    def to_json_dict(self, written: Sequence[str] = ()) -> dict:
        """What ``rotor diagnose --json`` prints: per cycle its number ``cycle`` (from 1, as
        in ``misfires`` and ``unsupported_cycles``), the start time [s], mean speed [rpm], each cylinder's IMEP and its standard deviation [Pa], misfire flags,
        contributions, load torque [N·m] (and the IMEP measured by the pressure channel);
        the misfires, the calibration, σ, TDC and the fit. ``written``: the files the
        command wrote, listed last. ``None``, never NaN."""
        a = self.analysis
        t0 = self.t_start_s
        rpm = self.mean_rpm()
        cycles = []
        for k in range(self.cycles):
            row = {
                "cycle": k + 1,
                "t_start_s": None if t0 is None else t0[k],
                "mean_rpm": rpm[k],
                "angle_mean_rpm": self.mean_omega[k] * RPM_PER_RAD_S,
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
                "cylinder_imep_pa": self.cylinder_imep_pa(),
                "cylinder_imep_over": "normal firings (identified, not misfires), as the text's table",
                "mean_rpm": float(np.mean(rpm)) if rpm.size else None,
                "supported": not self.coverage,
                "unsupported_reason": self.coverage or None,
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
    within :data:`rotor.diagnostics.charge.SIGMA_RANGE`.
    """
    check_argument_types("diagnose", engine, log, calibration, wheel, tdc_deg)
    calibration, cal_source = _resolve_calibration(engine, calibration, calibration_source)
    if scaling is None:
        scaling = calibration.scaling if calibration is not None else "none"
    check_scaling(scaling, engine)
    eng = calibration.apply(engine) if calibration is not None else engine
    _check_tdc_deg(tdc_deg, log)
    if isinstance(log, (str, os.PathLike)):
        plan = _ReadPlan(wheel, columns, tdc_deg, firing, edge, check_tdc)
        phased = _phased_analysis(engine, eng, log, calibration, cal_source, plan)
        speed: LogAnalysis | SpeedResult | np.ndarray = phased.analysis  # type: ignore[assignment]
    else:
        phased = _Phased(log if isinstance(log, LogAnalysis) else None)
        speed = log
    sigma = calibration.charge_scale if (calibration is not None and scaling == "charge") else 1.0
    charge = fit_charge(eng, speed, scaling, sigma, max_iterations, {"load_per": load_per, **identify_kwargs})
    return _conclude(engine, charge, phased, calibration, cal_source, scaling)


def _resolve_calibration(engine, calibration, calibration_source) -> tuple[Calibration | None, str | None]:
    """The calibration ``diagnose`` was given (``"preset"``, a file, one, or None) as one,
    checked against ``engine``, and how the result names where it came from."""
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
    return calibration, cal_source


def _check_tdc_deg(tdc_deg, log) -> None:
    if isinstance(tdc_deg, str) and tdc_deg != "speed":
        raise TypeError(
            f"diagnose(tdc_deg): expected an angle [deg], 'speed' (from the speed alone) or None, got {tdc_deg!r}"
        )
    if isinstance(tdc_deg, str) and not isinstance(log, (str, os.PathLike)):
        raise EngineError(
            "tdc_deg='speed' needs a log file (a wheel's gap to count the angle from)", argument="tdc_deg"
        )


@dataclasses.dataclass(frozen=True)
class _ReadPlan:
    """How ``diagnose`` reads a log file: its arguments of the reading and phasing."""

    wheel: Any
    columns: str | Sequence[str] | None
    tdc_deg: float | str | None
    firing: str | int
    edge: str
    check_tdc: bool


@dataclasses.dataclass(frozen=True)
class _Phased:
    """The recording analysed at the TDC and firing revolution used, the check of that TDC
    against the speed (or None), a warning where the fit's firing revolution is not the
    log's, and a note on where the phase came from."""

    analysis: LogAnalysis | None
    check: TdcCheck | None = None
    phase_warning: str = ""
    phase_note: str = ""


@dataclasses.dataclass(frozen=True)
class _Reader:
    """The log file read and its wheel signal placed once (``reading``, else the log as read,
    ``log``); each call analyses it at one TDC, firing revolution and tooth errors."""

    engine: Engine
    log: Any
    reading: Any
    wheel: Any
    columns: str | Sequence[str] | None
    edge: str

    def __call__(self, tdc: float | None, fire: str | int, teeth: Any) -> LogAnalysis:
        engine = self.engine
        cr = getattr(engine.pressure, "compression_ratio", None)
        rod_ratio = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
        try:
            return self._analysis(tdc, fire, teeth, cr, rod_ratio)
        except TooFewOrders as e:
            raise LogError(
                f"{str(e).split(';')[0]}; give a calibration made on this wheel from a coast-down or motored run "
                "(calibration=FILE)"
            ) from None

    def _analysis(self, tdc, fire, teeth, cr, rod_ratio) -> LogAnalysis:
        engine = self.engine
        return analyze_log(
            self.reading if self.reading is not None else self.log,
            self.wheel,
            columns=self.columns,
            strokes=engine.strokes,
            cylinders=engine.cylinders,
            tdc_deg=tdc,
            firing=fire,
            tooth_errors=teeth,
            compression_ratio=None if cr is None else float(cr),
            rod_ratio=None if cr is None else rod_ratio,
            edge=self.edge,
        )


def _phased_analysis(engine, eng, log, calibration, cal_source, plan: _ReadPlan) -> _Phased:
    """The log file read at its TDC (given, stated by the log, the calibration's, a pressure
    channel's, or from the speed) and checked against the speed where it is the calibration's."""
    tdc_deg, firing, phase_note = plan.tdc_deg, plan.firing, ""
    from_speed = isinstance(tdc_deg, str)
    if tdc_deg is None and calibration is None:  # a log that states its phase (rotor.diagnostics.record)
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
        tdc_deg = calibration.tdc_after_gap_deg
    w = plan.wheel or (calibration.wheel if calibration is not None and calibration.wheel else None)
    te = "estimate" if calibration is None or calibration.tooth_errors is None else calibration.tooth_errors
    try:
        read = _open_log(engine, log, w, te, plan, cal_source, None if calibration is None else calibration.reading)
    except LogError as e:
        if plan.wheel is None and calibration is not None and calibration.wheel and e.argument != "as_read":
            origin = f"the calibration{f' ({cal_source})' if cal_source else ''}"
            raise LogError(
                f"{os.path.basename(os.fspath(log))}: {origin} was made on a {calibration.wheel} wheel, which this "
                f"log's edges do not fit ({str(e).split(': ', 1)[-1][:160]}); give a calibration made on this log's "
                "wheel, or none (calibration=None)"
            ) from None
        raise
    analysis = read(0.0 if from_speed else tdc_deg, firing, te)  # type: ignore[arg-type]
    if analysis.tdc_source is PhaseSource.UNKNOWN:
        raise EngineError(
            f"{analysis.source}: TDC is not known: give a calibration (calibration=FILE), tdc_deg=DEG "
            f"(or tdc_deg='speed': from the speed alone) or a pressure channel"
        )
    if analysis.kind != "speed" and (from_speed or (from_calibration and plan.check_tdc)):
        given = None if from_speed else float(tdc_deg)  # type: ignore[arg-type]
        bias = calibration.tdc_bias if calibration is not None else None
        return _checked_phase(eng, analysis, read, given, firing, te, phase_note, bias)
    return _Phased(analysis, phase_note=phase_note)


def _open_log(engine, log, wheel, te, plan: _ReadPlan, cal_source, calibrated_reading=None) -> _Reader:
    """The log file read and its wheel signal placed, once; refused where the calibration's
    tooth errors are another wheel's."""
    source_log = read_log(log, plan.columns)
    # read as the calibration's recording was, unless the wheel or the edge is given
    as_read = _recorded(calibrated_reading) if plan.wheel is None and plan.edge == "auto" else None
    if as_read is not None and wheel is not None and as_read.wheel != getattr(wheel, "spec", wheel):
        as_read = None  # the calibration's wheel is not the one its reading records: the wheel decides
    reading = (
        read_wheel(source_log, wheel, edge=plan.edge, name=os.path.basename(os.fspath(log)), as_read=as_read)
        if source_log.kind != "speed"
        else None
    )
    if isinstance(reading, PatternReading) and isinstance(te, ToothErrors):
        raise LogError(
            f"{reading.source}: the calibration holds the tooth errors of a {te.wheel} wheel, and this log's wheel "
            f"is the {reading.pattern.name} pattern: give a calibration made on this wheel or none (calibration=None)"
        )
    if isinstance(reading, WheelReading) and isinstance(te, ToothErrors) and parse_wheel(te.wheel) != reading.wheel:
        origin = (
            f"the preset's own calibration, {cal_source[len('preset ') :]}"
            if cal_source is not None and cal_source.startswith("preset ")
            else f"the calibration{f' ({cal_source})' if cal_source else ''}"
        )
        raise LogError(
            f"{reading.source}: {origin} holds the tooth errors of a {te.wheel} wheel, and this log's wheel is "
            f"{reading.wheel.spec}: give a calibration made on this wheel (calibration=FILE) or "
            f"none (calibration=None)"
        )
    return _Reader(engine, source_log, reading, wheel, plan.columns, plan.edge)


def _recorded(reading: dict | None) -> ReadingRecord | None:
    """A calibration's reading as a :class:`rotor.logs.recording.ReadingRecord`; None where it
    holds none (a calibration written before readings were recorded states its choices only)."""
    if not isinstance(reading, dict) or "channel" not in reading:
        return None
    return ReadingRecord.from_json_dict(reading)


def _checked_phase(eng, analysis, read, given_deg, firing, te, phase_note, bias=None) -> _Phased:
    """The calibration's TDC checked against the speed (``given_deg``), or TDC found from it
    (``given_deg`` None), and the recording re-read at the TDC and firing revolution used:
    a firing revolution from a cam or pressure channel, or given, stands."""
    check = _speed_check(eng, analysis, given_deg, te, read, bias)
    if check is None:
        note = f"TDC {given_deg:.1f}° after the gap kept unchecked: the engine has no steady state at this record's mean speed"
        return _Phased(analysis, None, "", "; ".join(n for n in (phase_note, note) if n))
    own_phase = firing not in ("auto", "speed") or analysis.firing_source in CHANNELS
    moved = check.verdict in (TdcVerdict.DISAGREES, TdcVerdict.FOUND)
    if own_phase and moved:
        analysis = read(check.used_deg, firing, te)
        if firing == "auto" and analysis.firing_source not in CHANNELS:
            own_phase = False  # the channel no longer decides at this TDC: the fit's revolution
    phase_warning = ""
    if own_phase:
        phase_warning = _phase_agreement(check, analysis)
        if not phase_warning and check.firing_parity is not None:
            phase_note = f"firing revolution from the log ({analysis.firing_method}), where the speed's fit puts it too"
    elif moved or (check.firing_parity is not None and check.firing_parity != analysis.firing_parity):
        analysis = read(check.used_deg, firing if check.firing_parity is None else check.firing_parity, te)
    return _Phased(analysis, check, phase_warning, phase_note)


def _conclude(engine, charge: ChargeFit, phased: _Phased, calibration, cal_source, scaling) -> Diagnosis:
    """The diagnosis: the identification with its notes, the misfires as concluded (every
    firing where the record holds none; none judged where the model does not fit), the
    engine's mismatch with the log and the verdict."""
    ident, analysis, check = charge.identification, phased.analysis, phased.check
    extra = list(charge.notes)
    if cal_source is not None and cal_source.startswith("preset"):
        extra.append(f"calibration: the preset's own ({cal_source[len('preset ') :]})")
    measured = None
    if calibration is not None and analysis is not None and analysis.pressure is not None and engine.cylinders == 1:
        measured = measured_imep(engine, analysis, calibration.pressure_gain_pa)
    if check is not None and not check.corrected:
        extra.append(check.message)
    if phased.phase_note:
        extra.append(phased.phase_note)
    notes = ident.notes + tuple(extra)
    no_firing = charge.no_firing
    misfire = ident.misfire | ident.identified if no_firing else ident.misfire
    mismatch = _mismatch(engine, ident, misfire)
    verdict, verdict_reason = _verdict(engine, ident, no_firing, mismatch)
    if verdict is DiagnosisVerdict.MODEL_DOES_NOT_FIT:  # a model that does not explain the speed says nothing
        no_firing = False  # about firing or misfires
        misfire = np.zeros_like(np.asarray(ident.misfire, dtype=bool))
        notes = tuple(n for n in notes if n != NO_FIRING_NOTE)
        # the warning quotes the IMEP the table shows: over the firings left normal
        mismatch = _mismatch(engine, ident, misfire) or mismatch
    coverage = ""
    if calibration is not None and ident.cycles:
        ok = ident.identified & ~np.asarray(misfire)
        imep = float(np.mean(ident.imep_pa[ok])) if ok.any() else float(np.mean(ident.imep_pa))
        coverage = calibration.outside(float(np.mean(_time_mean_rpm(ident))), None if no_firing else imep)
    flags = _cycle_flags(ident, misfire)
    if coverage:
        flags = tuple(f"{f}; {coverage}" if f else coverage for f in flags)
    return Diagnosis(
        identification=dataclasses.replace(ident, misfire=misfire, notes=notes),
        calibration=calibration,
        calibration_source=cal_source,
        analysis=analysis,
        scaling=scaling,
        charge_scale=float(charge.sigma),
        charge_iterations=charge.iterations,
        no_firing=no_firing,
        measured_imep_pa=measured,
        mismatch=mismatch,
        tdc_check=check,
        cycle_flags=flags,
        partial_deg=_partial(analysis),
        phase_warning=phased.phase_warning,
        verdict=verdict,
        verdict_reason=verdict_reason,
        coverage=coverage,
    )


def _verdict(engine, ident, no_firing: bool, mismatch: tuple) -> tuple[DiagnosisVerdict, str]:
    """Whether the model explains the speed (a poor fit with a residual that is no noise, or
    a mismatch: it does not), and what to check where it does not."""
    structure = _residual_structure(ident, engine.strokes)
    poor = not float(ident.fit_r2) >= POOR_FIT_R2 and not structure <= RESIDUAL_STRUCTURE_MAX
    if not (poor or mismatch):
        return (DiagnosisVerdict.NO_FIRING if no_firing else DiagnosisVerdict.FITS), ""
    why = (
        f"it explains {max(float(ident.fit_r2), 0.0):.0%} of the speed's fluctuation (R² below {POOR_FIT_R2:g}), "
        f"and what it leaves is no noise: {structure:.3g}× more per harmonic at the low orders than at the high ones"
        if poor
        else "the identified figures are implausible (see the warnings)"
    )
    return DiagnosisVerdict.MODEL_DOES_NOT_FIT, (
        why + ": check the engine file, the wheel and its edge, and TDC; the misfires are not judged"
    )


def _cylinder_means(ident, misfire) -> np.ndarray:
    """Each cylinder's mean identified IMEP over its normal firings [Pa] (NaN where none)."""
    ok = np.asarray(ident.identified, dtype=bool) & ~np.asarray(misfire, dtype=bool)
    out = np.full(ident.cylinders, np.nan)
    for c in range(ident.cylinders):
        if ok[:, c].any():
            out[c] = float(np.mean(ident.imep_pa[ok[:, c], c]))
    return out


def _time_mean_rpm(ident) -> np.ndarray:
    """Each cycle's time-mean speed [rpm]: the harmonic mean of ω on the uniform angle grid."""
    omega = np.asarray(ident.omega, dtype=np.float64)
    return RPM_PER_RAD_S / np.mean(1.0 / omega, axis=1)


def _mismatch(engine, ident, misfire):
    """Lines saying where ``engine`` does not match the log it identified (see the module doc)."""
    from ..engine.forces import imep_pa

    out = []
    nominal = float(imep_pa(engine))
    bad = [
        (c + 1, float(m))
        for c, m in enumerate(_cylinder_means(ident, misfire))
        if np.isfinite(m) and (m > IMEP_MAX_PA or (nominal > 0 and m > IMEP_FACTOR_MAX * nominal))
    ]
    if bad:
        shown = ", ".join(f"cylinder {c} {m / PA_PER_BAR:.3f} bar" for c, m in bad[:4]) + (
            ", …" if len(bad) > 4 else ""
        )
        out.append(
            f"implausible IMEP for {engine.name!r} (mean over the normal firings, as the table): {shown}, against the engine file's {nominal / PA_PER_BAR:.3g} bar "
            f"(over {IMEP_FACTOR_MAX:g}× it, or over {IMEP_MAX_PA / PA_PER_BAR:g} bar, which no engine reaches): "
            f"is it the engine of this log?"
        )
    rpm = float(np.mean(_time_mean_rpm(ident)))
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


def _speed_check(eng, analysis, given_deg, te, read, bias=None):
    """Check (or find, ``given_deg`` None) TDC from the speed of ``analysis``: the fit on the
    recording's own tooth-error estimate where the given ones are another wheel's."""
    from ..logs.wheel import ToothErrors
    from .phase import NoSignature, check_tdc, tdc_from_speed, tooth_error_mismatch

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
    try:
        fit = tdc_from_speed(eng, fit_on)
    except NoSignature:
        if given_deg is None:
            raise
        return None  # a transient: the given TDC kept, unchecked
    return check_tdc(fit, given_deg, what="the calibration's", tooth_mismatch=te_mismatch, bias=bias)


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
