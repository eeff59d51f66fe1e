"""A recording's phase: the angle from the wheel's gap to TDC and the firing revolution.

TDC is given, or found from a pressure channel (:func:`tdc_from_pressure`: the compression
peak, or a polytropic fit of the compression with the engine's compression ratio and rod
ratio). The firing revolution of a four-stroke comes from the pressure (the revolution
with the compression peak), a cam signal (the first TDC after each cam edge), or the speed
itself (the revolution in which the crank speeds up more after TDC), or is given.
:func:`find_phase` is this stage of :func:`rotor.analyze_log`; :class:`PhaseSource` says
where each came from.
"""

from __future__ import annotations

import dataclasses
import enum
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..errors import LogError
from .digital import digital_edges
from .edges import find_edges
from .reader import Log
from .track import named

if TYPE_CHECKING:
    from .angle import CrankAngle

__all__ = [
    "Phase",
    "PhaseSource",
    "find_phase",
    "tdc_from_pressure",
    "NoCompressionPeak",
    "PEAK_TO_NOISE_MIN",
    "PEAK_WIDTH_MAX_DEG",
]

TWO_PI = 2.0 * np.pi
PEAK_TO_NOISE_MIN = 20.0
"""A compression peak must stand this many times the signal's noise above the median of
the averaged firing revolution [-] (see :func:`tdc_from_pressure`)."""
PEAK_WIDTH_MAX_DEG = 120.0
"""… and the averaged revolution may lie above half the peak's height for at most this
much of it [deg] (a compression peak is narrow: 55–81° on ``tue-single``'s bench recordings, whose peaks stand
100–480 times their noise above the median)."""


class NoCompressionPeak(LogError):
    """A pressure channel without a clear compression peak: not used for TDC."""


class PhaseSource(enum.Enum):
    """Where a recording's TDC or firing revolution came from (a typed state: decisions test
    this, never the words of ``tdc_method`` or ``firing_method``)."""

    GIVEN = "given"
    PRESSURE = "pressure"
    CAM = "cam"
    SPEED = "speed"
    UNKNOWN = "unknown"
    EVERY_REVOLUTION = "every revolution (two-stroke)"


@dataclasses.dataclass(frozen=True)
class Phase:
    """What :func:`find_phase` found: TDC's wheel angle ``tdc`` [rad], how and where from;
    the firing revolution's parity (None for a two-stroke), how and where from; ``base``:
    the wheel angle at which a cycle starts (modulo a cycle) [rad]; the pressure samples
    within the edges (wheel angle [rad], signal), or None; and the notes."""

    tdc: float
    tdc_method: str
    tdc_source: PhaseSource
    parity: int | None
    parity_method: str
    firing_source: PhaseSource
    base: float
    pressure: tuple | None
    notes: tuple[str, ...] = ()


@dataclasses.dataclass(frozen=True)
class PhaseRequest:
    """What :func:`find_phase` is asked: ``strokes``, ``tdc_deg`` (None: from the pressure),
    ``firing`` (``"auto"``, ``"pressure"``, ``"cam"``, ``"speed"``, 0 or 1), the cam's
    ``edge``, and ``compression_ratio`` and ``rod_ratio`` for the polytropic fit."""

    strokes: int
    tdc_deg: float | None
    firing: str | int
    edge: str
    compression_ratio: float | None
    rod_ratio: float | None


@dataclasses.dataclass(frozen=True)
class _PressurePhase:
    """The firing parity the pressure channel gives (or None), whether the channel is used,
    and why not where it has no clear compression peak."""

    parity: int | None
    ok: bool
    no_peak: str = ""


def find_phase(name: str, log: Log, angle: CrankAngle, request: PhaseRequest) -> Phase:
    """TDC and the firing revolution of the recording ``log`` (``name``) whose crank angle
    is ``angle`` (see the module doc)."""
    notes: list[str] = []
    pressure = None
    if "pressure_v" in log and log.kind != "teeth":
        t_s, p_s = log["time"], log["pressure_v"]
        inside = (t_s >= angle.t_of(angle.phi_lo)) & (t_s <= angle.t_of(angle.phi_hi))
        pressure = (angle.phi_of(t_s[inside]), p_s[inside])
    tdc, tdc_method, tdc_source, by_pressure = _tdc(log, pressure, request, notes)
    if request.strokes != 4:
        method = "two-stroke: every revolution"
        return Phase(
            tdc, tdc_method, tdc_source, None, method, PhaseSource.EVERY_REVOLUTION, tdc, pressure, tuple(notes)
        )
    if request.tdc_deg is not None and pressure is not None and request.firing in ("auto", "pressure"):
        try:
            _, p_parity, _ = tdc_from_pressure(*pressure)
            by_pressure = _PressurePhase(p_parity, True)
        except NoCompressionPeak as e:
            by_pressure = _PressurePhase(None, False, str(e))
            notes.append(f"{e}: the firing revolution comes from elsewhere")
    parity, parity_method, firing_source = _firing_revolution(name, log, angle, tdc, request, by_pressure, notes)
    base = tdc + TWO_PI * parity - TWO_PI  # firing TDC at 2π·r + tdc for r of this parity; the cycle starts 2π before
    return Phase(tdc, tdc_method, tdc_source, parity, parity_method, firing_source, base, pressure, tuple(notes))


def _tdc(log, pressure, request: PhaseRequest, notes) -> tuple[float, str, PhaseSource, _PressurePhase]:
    """TDC's wheel angle [rad], how and where from, and what the pressure says of the firing
    revolution: given, from the pressure channel, or unknown (0: the cycles start at the gap)."""
    by_pressure = _PressurePhase(None, pressure is not None)
    if request.tdc_deg is not None:
        return float(np.deg2rad(request.tdc_deg)), "given", PhaseSource.GIVEN, by_pressure
    if pressure is None:
        notes.append(
            "TDC not known: the orders' phases are relative to the gap, not to TDC (give tdc_deg or a pressure channel)"
        )
        method = (
            "unknown: cycles start at the gap" if log.kind != "speed" else "unknown: cycles start at the first sample"
        )
        return 0.0, method, PhaseSource.UNKNOWN, by_pressure
    compression_ratio = request.compression_ratio
    try:
        tdc, p_parity, method = tdc_from_pressure(
            *pressure, compression_ratio=compression_ratio, rod_ratio=request.rod_ratio
        )
    except NoCompressionPeak as e:
        notes.append(f"{e}; TDC not known: the orders' phases are relative to the gap (give tdc_deg)")
        method = "unknown: the pressure channel has no clear compression peak; cycles start at the gap"
        return 0.0, method, PhaseSource.UNKNOWN, _PressurePhase(None, False, str(e))
    if compression_ratio is None:
        notes.append(
            "TDC is the pressure peak, which combustion puts late (13–27° on the tue-single bench's "
            "recordings): the orders' phases and the cycle start are late by as much; give the "
            "compression ratio and rod ratio (compression_ratio=…, rod_ratio=…) for a fit of the "
            "compression, or tdc_deg"
        )
    return tdc, method, PhaseSource.PRESSURE, _PressurePhase(p_parity, True)


def _firing_revolution(name, log, angle, tdc, request: PhaseRequest, by_pressure: _PressurePhase, notes):
    """The firing parity of a four-stroke, how and where from (see the module doc)."""
    firing = request.firing
    if firing in (0, 1):
        return int(firing), "given", PhaseSource.GIVEN
    if firing == "pressure" and by_pressure.no_peak:  # a pressure channel without a clear compression peak
        raise LogError(f"{name}: firing='pressure': {by_pressure.no_peak}; give firing=0 or 1, or a cam channel")
    if firing in ("auto", "pressure") and by_pressure.ok and by_pressure.parity is not None:
        # the revolutions holding the TDC found from the pressure (a given TDC lies in the same compression)
        return by_pressure.parity, "pressure: revolutions with the compression peak", PhaseSource.PRESSURE
    if firing in ("auto", "cam") and ("cam_v" in log or "cam_d" in log):
        cam_parity = _cam_parity(name, log, request.edge, angle, tdc, firing == "cam", notes)
        if cam_parity is not None:
            return cam_parity, "cam: the first TDC after each cam edge", PhaseSource.CAM
    if firing in ("auto", "speed"):
        parity, sep = _speed_parity(angle.omega_of, angle.phi_lo, angle.phi_hi, tdc)
        if sep < 1.0:
            notes.append(
                "the firing revolution is uncertain from the speed alone: the half orders' phases may be off by π"
            )
        method = f"speed: the revolution that speeds up more after TDC (separation {sep:.1f} σ)"
        return parity, method, PhaseSource.SPEED
    raise LogError(
        f"firing={firing!r}: 'auto', 'pressure', 'cam', 'speed', 0 or 1"
        + (" (no such channel in the log)" if firing in ("pressure", "cam") else ""),
        argument="firing",
    )


# ---------------------------------------------------------------------- TDC from the pressure
def _volume_ratio(x, compression_ratio, rod_ratio):
    """V(x)/V_c of a central crank mechanism, x the angle from TDC [rad]."""
    lam = rod_ratio
    s = (1 - np.cos(x)) + (1 - np.sqrt(1 - (lam * np.sin(x)) ** 2)) / lam
    return 1 + 0.5 * (compression_ratio - 1) * s


def tdc_from_pressure(
    phi: ArrayLike,
    p: ArrayLike,
    *,
    compression_ratio: float | None = None,
    rod_ratio: float | None = None,
    window_deg: tuple[float, float] = (-90.0, -10.0),
) -> tuple[float, int, str]:
    """TDC of the compression from a pressure signal sampled at wheel angles.

    **Arguments:** ``phi``: wheel angle of each sample [rad]; ``p``: the pressure signal
    (any unit, gain or offset: only its shape is used); ``compression_ratio`` and
    ``rod_ratio`` (crank radius / rod length): the engine's, for the polytropic fit;
    ``window_deg``: the compression window of the fit, from TDC [deg].

    The compression peaks once every second revolution: the revolutions (windows of one
    revolution centred on the peak's angle) with the higher peaks are the firing ones,
    and their traces are averaged on a 0.25° grid. With the compression ratio and rod
    ratio, TDC comes from a polytropic fit of the compression before ignition,
    log(p + p₀) = c − n·log V(φ − φ_TDC), with φ_TDC, n, c and the signal's offset p₀
    free (the sensor's gain and offset need not be known). Without them, TDC is the
    averaged trace's peak, which combustion puts some degrees late (a motored cycle's
    peak is within a degree of TDC).

    **A clear compression peak** is needed, or :class:`NoCompressionPeak` (a
    :class:`LogError`) is raised and no TDC is given: the averaged firing revolution's peak
    must stand :data:`PEAK_TO_NOISE_MIN` (20) times the signal's noise above its median
    (the noise: the median absolute sample-to-sample difference of the raw signal / 0.954,
    the standard deviation of white noise), and the revolution may lie above half the
    peak's height for at most :data:`PEAK_WIDTH_MAX_DEG` (120°). A flat channel, pure
    noise, or a periodic signal that is not a pressure (a wheel signal) fails.

    **Returns:** (TDC wheel angle modulo 2π [rad], firing parity 0 or 1 of the
    revolutions counted from wheel angle 0 that hold it, the method in words).
    """
    from scipy.optimize import least_squares

    phi = np.asarray(phi, dtype=np.float64)
    p = np.asarray(p, dtype=np.float64)
    if phi.size < 100:
        raise LogError("pressure channel: too few samples within the tooth edges to find TDC")
    i_pk = int(np.argmax(p))
    centre = float(np.mod(phi[i_pk], TWO_PI))
    win = np.floor((phi - centre + np.pi) / TWO_PI).astype(int)  # window k: centre + 2πk ± π
    ks = np.unique(win)
    peaks = np.array([p[win == k].max() for k in ks])
    full = np.array(
        [
            (phi[win == k].min() <= centre + TWO_PI * k - 0.9 * np.pi)
            and (phi[win == k].max() >= centre + TWO_PI * k + 0.9 * np.pi)
            for k in ks
        ]
    )
    ks, peaks = ks[full], peaks[full]
    even, odd = peaks[ks % 2 == 0], peaks[ks % 2 == 1]
    if even.size == 0 or odd.size == 0:
        raise LogError("pressure channel: need at least one whole even and one whole odd revolution")
    parity_win = int(np.mean(odd) > np.mean(even))
    fire = ks[ks % 2 == parity_win]
    step = np.deg2rad(0.25)
    grid = np.arange(-np.pi, np.pi, step)
    sel = np.isin(win, fire)
    x = phi[sel] - centre - TWO_PI * win[sel]
    b = np.clip(np.floor((x + np.pi) / step).astype(int), 0, grid.size - 1)
    sums = np.bincount(b, weights=p[sel], minlength=grid.size)
    cnt = np.bincount(b, minlength=grid.size)
    ok = cnt > 0
    if ok.sum() < grid.size // 4:
        raise LogError("pressure channel: too few samples in the firing revolutions")
    x = grid + step / 2
    avg = np.interp(x, x[ok], sums[ok] / cnt[ok])
    _check_compression_peak(p, avg, step)
    j = int(np.argmax(avg))
    jj = int(np.clip(j, 1, avg.size - 2))
    y0, y1, y2 = avg[jj - 1 : jj + 2]
    curv = y0 - 2 * y1 + y2
    peak = x[jj] + (0.5 * (y0 - y2) / curv * step if curv < 0 else 0.0)
    if compression_ratio is None:
        tdc_rel, method = peak, "pressure: the averaged firing cycle's peak (late by the combustion)"
    else:
        if not (compression_ratio > 1 and rod_ratio is not None and 0 < rod_ratio < 1):
            raise LogError(
                f"compression_ratio = {compression_ratio!r}, rod_ratio = {rod_ratio!r}: need a "
                f"compression ratio > 1 and a rod ratio (crank radius / rod length) between 0 and 1"
            )
        lo_w, hi_w = np.deg2rad(window_deg)
        tdc_rel = peak - np.deg2rad(10.0)
        for _ in range(10):
            m = (x - tdc_rel >= lo_w) & (x - tdc_rel <= hi_w)
            floor = avg[m].min()
            span = avg.max() - floor

            def res(q):
                t0, n, c, off = q
                return np.log(avg[m] - floor + off * span) - (
                    c - n * np.log(_volume_ratio(x[m] - t0, compression_ratio, rod_ratio))
                )

            q0 = [tdc_rel, 1.3, np.log(span), 0.1]
            sol = least_squares(res, q0, bounds=([tdc_rel - 0.35, 1.0, -50, 1e-4], [tdc_rel + 0.35, 1.7, 50, 10.0]))
            moved = abs(sol.x[0] - tdc_rel)
            tdc_rel = float(sol.x[0])
            if moved < np.deg2rad(0.01):
                break
        method = (
            f"pressure: polytropic fit of the compression ({window_deg[0]:g}…{window_deg[1]:g}° from TDC, "
            f"compression ratio {compression_ratio:g}, rod ratio {rod_ratio:.4g}, exponent {sol.x[1]:.3f})"
        )
    tdc_abs = centre + TWO_PI * int(fire[0]) + tdc_rel
    parity = int(np.floor(tdc_abs / TWO_PI)) % 2
    return float(np.mod(tdc_abs, TWO_PI)), parity, method


def _check_compression_peak(p, avg, step):
    """Raise NoCompressionPeak unless ``avg`` (the averaged firing revolution on a grid of
    ``step`` [rad]) has a clear, narrow peak above the noise of the raw signal ``p``."""
    noise = float(np.median(np.abs(np.diff(p)))) / 0.954  # white noise: median |Δ| = 0.954 σ
    med = float(np.median(avg))
    height = float(np.max(avg)) - med
    if not height > PEAK_TO_NOISE_MIN * noise or not height > 1e-9 * max(abs(med), 1e-300):
        raise NoCompressionPeak(
            f"pressure channel: no clear compression peak (the averaged firing revolution peaks "
            f"{height:.3g} above its median, the signal's noise is {noise:.3g}; {PEAK_TO_NOISE_MIN:g}× the "
            f"noise is needed): not used for TDC"
        )
    width = float(np.count_nonzero(avg > med + 0.5 * height)) * np.rad2deg(step)
    if width > PEAK_WIDTH_MAX_DEG:
        raise NoCompressionPeak(
            f"pressure channel: no clear compression peak (the averaged firing revolution lies above half "
            f"its peak's height for {width:.0f}°, a compression peak for under {PEAK_WIDTH_MAX_DEG:g}°: is it "
            f"the pressure column?): not used for TDC"
        )


def _speed_parity(omega_of, phi0, phi1, tdc):
    """Firing parity from the speed: the revolution after whose TDC the crank speeds up more."""
    r0 = int(np.ceil((phi0 - tdc) / TWO_PI))
    r1 = int(np.floor((phi1 - tdc - np.pi) / TWO_PI))
    if r1 - r0 < 1:
        return 0, 0.0
    revs = np.arange(r0, r1 + 1)
    x = tdc + TWO_PI * revs[:, None] + np.linspace(0, np.pi, 61)[None, :]
    w = omega_of(x)
    rise = w.max(axis=1) - w[:, 0]
    even, odd = rise[revs % 2 == 0], rise[revs % 2 == 1]
    if even.size == 0 or odd.size == 0:
        return 0, 0.0
    parity = int(np.mean(odd) > np.mean(even))
    sep = abs(np.mean(odd) - np.mean(even)) / (np.std(rise) + 1e-300)
    return parity, float(sep)


def _cam_parity(name, log, edge, angle, tdc, required, notes):
    """The firing parity from the cam channel (analog ``cam_v`` or digital ``cam_d``): the
    firing TDC is the first TDC after each rising cam edge. ``None`` (and a
    note) where the cam edges do not fall once per cycle and the cam is not ``required``."""
    if "cam_d" in log:
        cam = named(name, digital_edges, log["time"], log["cam_d"], name="cam_d").times
    else:
        cam = find_edges(log["time"], log["cam_v"], name="cam_v").times
    cam_phi = angle.phi_of(cam[(cam >= angle.t_of(angle.phi_lo)) & (cam <= angle.t_of(angle.phi_hi))])
    why = ""
    if cam_phi.size == 0:
        why = "no cam edge within the tooth edges"
    else:
        r = np.ceil((cam_phi - tdc) / TWO_PI)
        parities = np.mod(r, 2).astype(int)
        if np.any(parities != parities[0]) or np.any(np.diff(r) < 2):
            why = "the cam edges do not fall once per cycle (their revolutions alternate irregularly)"
    if why:
        if required:
            raise LogError(f"{name}: {why}")
        notes.append(f"cam channel not used for the firing revolution: {why}")
        return None
    return int(parities[0])
