"""The calibration record: what :func:`rotor.calibrate` finds and :func:`rotor.diagnose` reuses.

:class:`Calibration` keeps the inertia of everything that turns with the crankshaft, the
angle from the wheel's gap to TDC, the wheel's tooth errors, the pressure sensor's gain
and offset and the charge scale of one recording (how they are found:
:mod:`rotor.diagnostics.calibration`), as JSON (:meth:`Calibration.save` /
:meth:`Calibration.load`). It stores its engine's name, cylinders, strokes and geometry,
and :meth:`Calibration.check_engine` refuses another engine.

**A preset's own calibration**: a preset may ship one beside its TOML
(``rotor/presets/<name>.calibration.json``; ``tue-single``'s from a full-load recording
of its bench, written by ``benchmarks/diagnose_real.py``); :func:`preset_calibration`
finds it.
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import TYPE_CHECKING, Any

import equinox as eqx
import numpy as np

from ..engine.plausible import check_edge, check_inertia_kgm2
from ..errors import EngineError
from ..fileio import load_json, save_json
from ..logs.analysis import LogAnalysis
from ..logs.wheel import ToothErrors
from ..results import Result, json_safe
from ..units import PA_PER_BAR
from .charge import SCALINGS
from .phase import TdcBias

if TYPE_CHECKING:
    from ..engine.model import Engine

__all__ = [
    "Calibration",
    "preset_calibration",
    "engine_geometry",
    "check_argument_types",
    "CALIBRATION_FORMAT",
    "CALIBRATION_VERSION",
    "GEOMETRY_KEYS",
    "PRESETS_DIR",
    "READS_VERSIONS",
    "COVERAGE_RPM_MARGIN",
    "COVERAGE_IMEP_MARGIN",
]

CALIBRATION_FORMAT = "rotor-calibration"
CALIBRATION_VERSION = 2
READS_VERSIONS = (1, 2)  # version 1: no reading, TDC bias, recordings or coverage
GEOMETRY_KEYS = ("bore_m", "stroke_m", "rod_length_m")  # the geometry a calibration stores
COVERAGE_RPM_MARGIN = 0.1
"""A diagnosis whose mean speed lies more than this fraction outside the calibration
recordings' speeds is outside what the calibration covers [-]."""
COVERAGE_IMEP_MARGIN = 0.25
"""… and one whose mean IMEP lies more than this fraction below the lowest or above the
highest calibration recording's [-] (on the tue-4gb10 bench a full-load calibration reads
half load 3 % high and no load 19 % low: the engine file's cycle is not the engine's there)."""
PRESETS_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "presets")


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Calibration(Result):
    """What :func:`rotor.calibrate` found, to reuse on speed-only recordings of the same engine.

    **Fields:** ``engine`` (the engine's name); ``inertia_kgm2``: crankshaft, flywheel and
    all that turns rigidly with them [kg·m²] (the identification inertia, see
    :mod:`rotor.diagnostics.calibration`); ``tdc_after_gap_deg``: from the first tooth edge after the gap to cylinder 1's
    TDC [deg]; ``pressure_gain_pa``: pascal per unit of the pressure signal;
    ``pressure_offset_pa``: absolute pressure = gain·signal + offset [Pa];
    ``loss_torque_Nm``: the mean of friction plus load over the recording [N·m];
    ``scaling``: ``"charge"`` or ``"none"`` (:mod:`rotor.diagnostics.charge`); ``charge_scale``: σ of the
    calibration recording (its IMEP over the engine file's) [-]; ``wheel`` (spec);
    ``tooth_errors``: a :class:`rotor.ToothErrors` or None; ``source``: the recording;
    ``fit``: figures of the fit (energy-balance inertia, residuals, IMEP measured).
    Version 2 adds: ``reading``: how the wheel signal was read (the recording's
    :attr:`rotor.LogAnalysis.reading_record` as JSON; None where unknown), which
    :func:`rotor.diagnose` reads its logs with; ``tdc_bias``: the speed-based TDC's bias as
    the calibration recordings measured it (:class:`rotor.diagnostics.phase.TdcBias`, or
    None); ``recordings``: one dict per calibration recording (``source``, ``mean_rpm``,
    ``imep_measured_pa``, ``pumping_mep_pa``, ``loss_torque_Nm``, ``tdc_after_gap_deg``,
    ``energy_balance_inertia_kgm2``, ``speed_tdc_bias_deg``); from them :meth:`coverage`
    (the speeds and loads covered) and :meth:`outside` (why a diagnosis lies outside them).
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
    reading: dict | None = None
    tdc_bias: TdcBias | None = None
    recordings: tuple = ()

    def __post_init__(self):
        for key in ("inertia_kgm2", "pressure_gain_pa", "charge_scale"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v > 0):
                raise EngineError(f"calibration {key} = {v!r}: must be a positive number")
        for key in ("tdc_after_gap_deg", "pressure_offset_pa", "loss_torque_Nm"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise EngineError(f"calibration {key} = {v!r}: must be a finite number")
        if not -720.0 <= float(self.tdc_after_gap_deg) <= 720.0:
            raise EngineError(
                f"calibration tdc_after_gap_deg = {self.tdc_after_gap_deg!r}: an angle after the gap, -720 … 720 "
                "[deg]; the calibration file is damaged, make it again"
            )
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
                f"not apply; calibrate this engine"
            )

    def coverage(self) -> dict | None:
        """The speeds [rpm] and mean IMEPs [Pa] of the calibration recordings, as
        ``{"rpm": (lo, hi), "imep_pa": (lo, hi), "recordings": n}`` (None for a version-1
        file, which does not state them)."""
        rec = [r for r in self.recordings if isinstance(r, dict)]
        try:
            rpm = [float(r["mean_rpm"]) for r in rec]
            imep = [float(r["imep_measured_pa"]) for r in rec]
        except (KeyError, TypeError, ValueError):
            return None
        if not rec:
            return None
        return {"rpm": (min(rpm), max(rpm)), "imep_pa": (min(imep), max(imep)), "recordings": len(rec)}

    def outside(self, rpm: float, imep_pa: float | None) -> str:
        """Why a diagnosis at mean speed ``rpm`` [rpm] and mean IMEP ``imep_pa`` [Pa] (None: a
        record without firing, whose motored IMEP no calibration's load range bounds) lies
        outside what the calibration covers (:data:`COVERAGE_RPM_MARGIN`,
        :data:`COVERAGE_IMEP_MARGIN`), or "" where it lies inside (or the calibration states
        no coverage)."""
        cov = self.coverage()
        if cov is None:
            return ""
        (r_lo, r_hi), (p_lo, p_hi) = cov["rpm"], cov["imep_pa"]
        why = []
        if not (r_lo * (1 - COVERAGE_RPM_MARGIN) <= rpm <= r_hi * (1 + COVERAGE_RPM_MARGIN)):
            why.append(f"{rpm:.0f} rpm, the calibration's recordings {r_lo:.0f}–{r_hi:.0f} rpm")
        if imep_pa is not None and not (
            p_lo * (1 - COVERAGE_IMEP_MARGIN) <= imep_pa <= p_hi * (1 + COVERAGE_IMEP_MARGIN)
        ):
            why.append(
                f"IMEP {imep_pa / PA_PER_BAR:.3g} bar, the calibration's recordings "
                f"{p_lo / PA_PER_BAR:.3g}–{p_hi / PA_PER_BAR:.3g} bar"
            )
        if not why:
            return ""
        return (
            f"outside what the calibration covers ({'; '.join(why)}): the engine model's error there is not "
            "measured; calibrate on a recording at this operating point too"
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
            "reading": json_safe(self.reading),
            "tdc_bias": None if self.tdc_bias is None else self.tdc_bias.to_json_dict(),
            "recordings": json_safe(list(self.recordings)),
            "coverage": json_safe(self.coverage()),
        }

    @classmethod
    def from_json_dict(cls, d: dict, where: str = "calibration") -> Calibration:
        """Build from :meth:`to_json_dict`'s dict ``d``; errors name ``where`` and the key."""
        if not isinstance(d, dict):
            raise EngineError(f"{where}: not a calibration (a JSON object is needed)")
        if d.get("format") != CALIBRATION_FORMAT:
            raise EngineError(f"{where}: key 'format' must be {CALIBRATION_FORMAT!r} (not a rotor calibration file)")
        if d.get("version") not in READS_VERSIONS or isinstance(d.get("version"), bool):
            raise EngineError(
                f"{where}: key 'version' = {d.get('version')!r}: this rotor reads versions "
                f"{', '.join(str(v) for v in READS_VERSIONS)}"
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
            k in GEOMETRY_KEYS
            and isinstance(v, (int, float))
            and not isinstance(v, bool)
            and math.isfinite(v)
            and v >= 0
            for k, v in geo.items()
        ):
            raise EngineError(f"{where}: key 'geometry' must be an object of numbers ({', '.join(GEOMETRY_KEYS)})")
        # a value that fits another unit better (a gain in bar a unit, an inertia in kg·cm²) refused naming it
        check_inertia_kgm2(
            f"{where}: key 'inertia_kgm2'",
            num("inertia_kgm2", True),
            bore_m=geo.get("bore_m"),
            cylinders=max(whole("cylinders"), 1),
        )
        check_edge(f"{where}: key 'pressure_gain_pa'", num("pressure_gain_pa", True), "pressure_gain_pa")
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
            **_version_2_fields(d, where),
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


def _version_2_fields(d: dict, where: str) -> dict:
    """The keys version 2 added (absent from a version-1 file: their defaults), checked."""
    reading = d.get("reading")
    if reading is not None and not isinstance(reading, dict):
        raise EngineError(f"{where}: key 'reading' must be null or an object (how the wheel was read)")
    bias = d.get("tdc_bias")
    parsed = TdcBias.from_json_dict(bias) if bias is not None else None
    if bias is not None and parsed is None:
        raise EngineError(f"{where}: key 'tdc_bias' must be null or an object with numbers 'kappa' and 'kappa_std'")
    rec = d.get("recordings", [])
    if not isinstance(rec, list) or not all(isinstance(r, dict) for r in rec):
        raise EngineError(f"{where}: key 'recordings' must be a list of objects")
    return {"reading": reading, "tdc_bias": parsed, "recordings": tuple(rec)}


def engine_geometry(engine: Engine) -> dict:
    """The geometry a calibration stores of ``engine`` (:data:`GEOMETRY_KEYS`) [m]."""
    return {k: float(getattr(engine.geometry, k)) for k in GEOMETRY_KEYS}


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


def check_argument_types(fn: str, engine: Any, log: Any, calibration: Any, wheel: Any, tdc_deg: Any) -> None:
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
