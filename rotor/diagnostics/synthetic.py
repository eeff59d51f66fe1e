"""A simulated bench recording: rotor's own steady state written as a raw log in the format
of the real single-cylinder bench files (``tue-single``), so that the reading path (:func:`rotor.read_log`,
:func:`rotor.analyze_log`, :func:`rotor.calibrate`, :func:`rotor.diagnose`, ``rotor analyze``,
``rotor diagnose``) runs where the real files are absent.

The file is tab separated, one row per sample: time [s], pressure sensor voltage [V],
encoder voltage [V] (read it with ``columns="time,pressure_v,encoder_v"``, as the real
files). What it holds:

- **Speed**: the periodic steady state of the engine (:func:`rotor.steady_state`, the
  load balanced to the engine's mean torque) at ``rpm``, repeated cycle after cycle; every
  cycle is the same (no cycle-to-cycle variation), so the analysed cycles can be compared
  with the simulator's one.
- **Pressure channel**: cylinder 1's absolute pressure (:func:`rotor.cylinder_pressure`)
  through the bench's calibration, ``V = 5·(0.115 + 0.00385·p[bar])`` (the inverse of
  the data README's ``p[bar] = (V/5 − 0.115)/0.00385``: 0.59 V at 1 bar, 51.95 bar/V),
  plus white noise of a twentieth of ``noise_v`` (0.0005 V, 0.026 bar at the default: the
  real files' noise, 0.0006 V).
- **Encoder channel**: the wheel's analog pulse train, low −0.73 V, high 4.0 V (the
  real files' levels), high for 45 % of each tooth pitch from the tooth's rising edge,
  each edge a linear ramp over 4 samples (40 µs at 100 kHz; the bench's edges rise over
  2–3 samples), timed so that it crosses 32 % of the swing, where
  :func:`rotor.find_edges` times an edge, at the edge's true time, plus white noise of ``noise_v``. The rising
  edges sit at the tooth angles plus a fixed tooth-spacing error per tooth (uniform
  in ±``tooth_error_deg``, zero mean), every revolution the same errors, and every
  recording too, whatever its ``seed``: one wheel, as on a bench, so that tooth errors
  estimated or calibrated on one recording apply to the others
  (:func:`simulated_tooth_errors` gives the true ones). The gap is a plain gap of ``missing`` pitches (the real wheel's narrow, low
  pulse after the gap and the wide one before it are not imitated).
- **imep_scale**: for a Wiebe cycle the whole cycle is scaled, the intake pressure and
  the IMEP by one factor (a throttled spark-ignition engine: ``rotor.diagnose``'s charge
  scaling, so a recording at 0.25 stands in for the bench's no load); for any other
  pressure model the combustion part alone (:func:`rotor.steady_state`'s ``imep_scale``).

The recording starts 36…180° (drawn from ``seed``) before a TDC at the start of intake
and ends 36…180° after the end of the ``cycles``-th cycle from there, so that
:func:`rotor.analyze_log` finds exactly ``cycles`` complete cycles (0 = TDC before intake,
as rotor counts them): 0.49–0.50 s, about 49,000 rows, for the default 12 cycles at
3000 rpm (the real files: 50,000 rows).
"""

from __future__ import annotations

import dataclasses
import io
import math
import os
import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from jaxtyping import ArrayLike

from ..checks import check_size
from ..engine.forces import cylinder_pressure  # compiled once per shape
from ..errors import EngineError
from ..logs.synthetic import wheel_with_layout
from ..logs.wheel import ToothErrors, Wheel, parse_wheel
from ..units import PA_PER_BAR, RPM_PER_RAD_S

if TYPE_CHECKING:
    from ..dynamics.result import SpeedResult
    from ..engine.model import Engine

__all__ = [
    "simulated_recording",
    "simulated_tooth_times",
    "simulated_tooth_time_text",
    "simulated_tooth_errors",
    "BENCH_GAIN_PA_PER_V",
    "BENCH_OFFSET_V",
    "DEFAULT_GAP_DEG",
    "pressure_volts",
]

BENCH_GAIN_PA_PER_V = PA_PER_BAR / (5 * 0.00385)  # the bench's sensor: 51.95 bar per volt
BENCH_OFFSET_V = 5 * 0.115  # the sensor's output at 0 bar [V]
DEFAULT_GAP_DEG = -29.4  # the real bench: TDC 29.4° after the gap (rotor.analyze_log on full_load.txt)
LOW_V, HIGH_V = -0.73, 4.0  # encoder levels of the real files
DUTY = 0.45  # high part of a tooth pitch (the real files: 14–15 of 33 samples)
RAMP_SAMPLES = 4.0  # an edge's linear ramp [samples] (at most a third of the shortest high pulse)
EDGE_LEVEL = 0.32  # a rising edge crosses this fraction of the swing at its true time (rotor.find_edges' level)
WHEEL_SEED = 0  # the wheel's tooth errors: one wheel for every recording, whatever ``seed``
MIN_SAMPLES_PER_PITCH = 10  # below this the pulses get too few samples for the edge finder


SAMPLE_ARRAYS = 12  # float64 arrays of one value per row held at once while writing, for the size check
PRESSURE_POINTS_PER_REV = 2880  # the pressure is computed every 0.125° and interpolated


def _wheel_errors(wheel, tooth_error_deg):
    e = np.random.default_rng(WHEEL_SEED).uniform(-1.0, 1.0, wheel.edges_per_rev) * np.deg2rad(tooth_error_deg)
    return e - e.mean()


def simulated_tooth_errors(wheel: str | Wheel | None = None, tooth_error_deg: float = 0.1) -> ToothErrors:
    """The true tooth-spacing errors of the wheel that :func:`simulated_recording` draws with
    the same ``wheel`` and ``tooth_error_deg`` [deg] (the same for every ``seed``), as a
    :class:`rotor.ToothErrors` (``method="simulated"``) to compare an estimate with, or to
    analyse a simulated recording with its exact correction."""
    w = Wheel(60, 2) if wheel is None else parse_wheel(wheel)
    tooth_error_deg = _number("tooth_error_deg", tooth_error_deg, nonnegative=True)
    return ToothErrors(w.spec, _wheel_errors(w, tooth_error_deg), method="simulated", source="rotor.synthetic")


def pressure_volts(p_pa: ArrayLike) -> np.ndarray:
    """The bench sensor's voltage [V] for an absolute pressure [Pa]: V = 5·(0.115 + 0.00385·p[bar])."""
    return BENCH_OFFSET_V + np.asarray(p_pa, dtype=np.float64) / BENCH_GAIN_PA_PER_V


def _number(name, x, *, positive=False, nonnegative=False):
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise EngineError(f"{name} = {x!r}: must be a number")
    x = float(x)
    if not math.isfinite(x):
        raise EngineError(f"{name} = {x!r}: must be finite")
    if positive and not x > 0:
        raise EngineError(f"{name} = {x!r}: must be positive")
    if nonnegative and not x >= 0:
        raise EngineError(f"{name} = {x!r}: must not be negative")
    return x


def simulated_recording(
    path: str | os.PathLike,
    engine: str | os.PathLike | Engine = "tue-single",
    rpm: float | None = None,
    *,
    cycles: int = 12,
    imep_scale: float = 1.0,
    sample_rate_hz: float = 100_000.0,
    wheel: str | Wheel | None = None,
    gap_deg: float = DEFAULT_GAP_DEG,
    tooth_error_deg: float = 0.1,
    noise_v: float = 0.01,
    seed: int = 0,
    motored_cycles: Sequence[int] = (),
) -> pathlib.Path:
    """Write a simulated raw bench recording (time, pressure voltage, encoder voltage) to ``path``.

    **Arguments:**
    - ``path``: the file to write (str or path-like); written whole or not at all (a
      temporary file in the same folder, then renamed). Its folder must exist.
    - ``engine``: a preset name (``"tue-single"``, default), the path of an engine file, or
      a :class:`rotor.Engine`. The pressure channel is cylinder 1's.
    - ``rpm``: time-mean crank speed [rpm]; default the engine's ``[operating] rpm``.
    - ``cycles``: complete engine cycles recorded [-], 2 or more (default 12, about the
      real files' 0.5 s at 3000 rpm); :func:`rotor.analyze_log` finds this many.
    - ``imep_scale``: IMEP relative to the engine file's [-], > 0 (see the module doc: a
      Wiebe cycle is scaled whole, intake pressure with it; 1 = the file's, the bench's
      full load; about 0.6 and 0.22 stand in for its half and no load).
    - ``sample_rate_hz``: sampling rate [Hz] (default 100 kHz, the bench's); at least 10
      samples per tooth pitch at the fastest point of the cycle.
    - ``wheel``: a :class:`rotor.Wheel` or a spec such as ``"60-2"`` (default 60-2) with a
      gap (missing teeth ≥ 1).
    - ``gap_deg``: crank angle of the gap, i.e. of the first tooth's rising edge after it,
      relative to TDC of cylinder 1 [deg] (the wheel turns with the crank, so every TDC
      sees the same); default −29.4: the gap passes 29.4° before TDC, as on the real bench
      (``analyze_log`` then reports TDC 29.4° after the gap).
    - ``tooth_error_deg``: the wheel's tooth-spacing errors are uniform in ±this [deg]
      (default 0.1; below a quarter of a pitch).
    - ``noise_v``: standard deviation of white noise on the encoder channel [V] (default
      0.01, ten times the real files' 0.001 V; the pressure channel gets a twentieth of it).
    - ``seed``: seeds the noise and where the recording starts; the same arguments give the
      same file. The wheel's tooth errors do not depend on it (one wheel for all recordings).
    - ``motored_cycles``: complete cycles (0 = the first, as :func:`rotor.analyze_log`
      counts them) that do not fire (a motored stretch, an ignition cut): their speed is the
      motored steady state at the same mean speed (the engine driven, as on a dynamometer)
      and their pressure the engine file's motored cycle; the speed switches at the cycle's
      start (TDC before intake) between the fired and the motored periodic solution.

    **Returns:** the path written (:class:`pathlib.Path`).

    **Raises:** :class:`rotor.EngineError` (a ``ValueError``) naming the argument that
    cannot be used; :class:`rotor.NoSteadyStateError` where the engine has no steady state
    at that speed.
    """
    from ..engine.file import load_engine
    from ..engine.model import Engine
    from ..fileio import atomic_path

    path = pathlib.Path(path)
    if not path.parent.is_dir():
        raise EngineError(f"path = {os.fspath(path)!r}: the folder {os.fspath(path.parent)!r} does not exist")
    if isinstance(engine, Engine):
        eng = engine
    elif isinstance(engine, (str, os.PathLike)):
        eng = load_engine(engine)
    else:
        raise EngineError(f"engine = {engine!r}: a preset name, an engine file or a rotor.Engine")
    if isinstance(cycles, bool) or not isinstance(cycles, (int, np.integer)) or cycles < 2:
        raise EngineError(f"cycles = {cycles!r}: a whole number of engine cycles, 2 or more")
    cycles = int(cycles)
    rpm = float(eng.operating.rpm) if rpm is None else _number("rpm", rpm, positive=True)
    imep_scale = _number("imep_scale", imep_scale, positive=True)
    fs = _number("sample_rate_hz", sample_rate_hz, positive=True)
    gap_deg = _number("gap_deg", gap_deg)
    tooth_error_deg = _number("tooth_error_deg", tooth_error_deg, nonnegative=True)
    noise_v = _number("noise_v", noise_v, nonnegative=True)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise EngineError(f"seed = {seed!r}: a whole number")
    try:
        motored_set = {int(c) for c in motored_cycles}
    except (TypeError, ValueError):
        raise EngineError(f"motored_cycles = {motored_cycles!r}: whole cycle numbers") from None
    if any(not 0 <= c < cycles for c in motored_set):
        raise EngineError(f"motored_cycles = {sorted(motored_set)}: cycle numbers in 0 … {cycles - 1}")
    rows = (cycles + 1) * (eng.strokes // 2) * 60.0 / rpm * fs
    check_size(
        rows * 8.0 * SAMPLE_ARRAYS,
        f"a simulated recording of {cycles} cycles at {rpm:g} rpm and {fs:g} Hz ({rows:.3g} rows)",
        "record fewer cycles or sample slower (cycles=, sample_rate_hz=)",
    )
    try:
        w = Wheel(60, 2) if wheel is None else parse_wheel(wheel)
    except ValueError as e:
        raise EngineError(f"wheel = {wheel!r}: {e}") from None
    if w.missing < 1:
        raise EngineError(
            f"wheel = {w.spec!r}: a simulated recording needs a wheel with a gap (e.g. 60-2); an "
            f"index channel is not simulated"
        )
    pitch_deg = 360.0 / w.teeth
    if tooth_error_deg >= pitch_deg / 4:
        raise EngineError(
            f"tooth_error_deg = {tooth_error_deg:g}: must be below a quarter of the {w.spec} wheel's "
            f"pitch ({pitch_deg / 4:g}°)"
        )
    if w.missing > w.teeth - 3:
        raise EngineError(f"wheel = {w.spec!r}: too few teeth for a simulated recording")

    bench = _Bench(
        path, eng, rpm, cycles, imep_scale, fs, w, gap_deg, tooth_error_deg, noise_v, int(seed), frozenset(motored_set)
    )
    eng, comb_scale = _charged(bench.engine, bench.imep_scale)
    rng = np.random.default_rng(bench.seed)
    motion = _crank_motion(eng, bench, comb_scale, rng)
    n = motion.ts.size
    pv = pressure_volts(_pressure(eng, motion, comb_scale, bench.motored)) + rng.normal(0.0, bench.noise_v / 20, n)
    ev = _encoder_volts(bench, motion) + rng.normal(0.0, bench.noise_v, n)
    data = np.column_stack([motion.ts, pv, ev])
    with atomic_path(bench.path) as tmp:
        np.savetxt(tmp, data, fmt=("%.8E", "%.7E", "%.7E"), delimiter="\t")
    return bench.path


@dataclasses.dataclass(frozen=True)
class _Bench:
    """The arguments of :func:`simulated_recording`, checked: the file, the engine, what
    is recorded and how."""

    path: pathlib.Path
    engine: Engine
    rpm: float
    cycles: int
    imep_scale: float
    fs: float
    wheel: Wheel
    gap_deg: float
    tooth_error_deg: float
    noise_v: float
    seed: int
    motored: frozenset[int]


def _charged(eng, imep_scale: float):
    """The engine at ``imep_scale`` (a Wiebe cycle's whole charge scaled), and the scale of
    the combustion part still to apply (1 for a Wiebe cycle)."""
    import equinox as eqx

    from .charge import SIGMA_RANGE

    pressure = eng.pressure
    if not pressure.charge_scalable:
        return eng, imep_scale
    lo, hi = SIGMA_RANGE
    if not lo <= imep_scale <= hi:
        raise EngineError(
            f"imep_scale = {imep_scale:g}: scales this engine's Wiebe cycle whole (intake pressure "
            f"with the IMEP); the physical range is {lo:g} … {hi:g}"
        )
    return eqx.tree_at(lambda e: e.pressure, eng, pressure.scale_charge(imep_scale)), 1.0


@dataclasses.dataclass(frozen=True)
class _Motion:
    """The crank's motion over the recording: t(θ) and θ(t) (splines, θ from the first
    recorded cycle's start), the spline's angle range, the time of the first sample ``t0``
    [s], the samples' times from it ``ts`` [s] and crank angles ``th`` [rad], the cycle
    [rad] and the shortest tooth pitch's time [s]."""

    t_of: Any
    theta_of: Any
    theta_lo: float
    theta_hi: float
    t0: float
    ts: np.ndarray
    th: np.ndarray
    cycle_rad: float
    pitch_s: float


def _crank_motion(eng, bench: _Bench, comb_scale: float, rng) -> _Motion:
    """The steady state (fired, and motored in the motored cycles) laid end to end over the
    recording, and the sampling instants (the start drawn from ``rng``)."""
    from scipy.interpolate import CubicHermiteSpline

    from ..dynamics.steady import steady_state

    rpm, fs, w, cycles, motored_set = bench.rpm, bench.fs, bench.wheel, bench.cycles, bench.motored
    ss = steady_state(eng, rpm, imep_scale=comb_scale)
    period = float(np.asarray(ss.period_s))
    cycle_rad = float(ss.cycle_rad)
    theta1 = np.asarray(ss.theta, dtype=np.float64)
    t1 = np.asarray(ss.t, dtype=np.float64)
    omega1 = np.asarray(ss.omega, dtype=np.float64)
    w_max = float(omega1.max())
    pitch_s = (2 * np.pi / w.teeth) / w_max
    if pitch_s * fs < MIN_SAMPLES_PER_PITCH:
        raise EngineError(
            f"sample_rate_hz = {fs:g}: {pitch_s * fs:.1f} samples per tooth pitch at the "
            f"fastest point ({w_max * RPM_PER_RAD_S:.0f} rpm) of a {w.spec} wheel; need at least "
            f"{MIN_SAMPLES_PER_PITCH} (raise the sampling rate or lower rpm)"
        )
    # the spline covers one cycle more than the recording each side; cycle k of the recording is row k + 1
    n_cyc = cycles + 3
    rows_k = np.arange(-1, n_cyc - 1)
    is_motored = np.isin(rows_k, sorted(motored_set))
    t_rows = np.tile(t1 - t1[0], (n_cyc, 1))
    omega_rows = np.tile(omega1, (n_cyc, 1))
    periods = np.full(n_cyc, period)
    if motored_set:
        ss0 = steady_state(eng, rpm, imep_scale=0.0)
        if not np.allclose(np.asarray(ss0.theta, dtype=np.float64), theta1):
            raise EngineError("motored_cycles: the motored steady state's grid differs from the fired one's")
        t0_1 = np.asarray(ss0.t, dtype=np.float64)
        t_rows[is_motored] = t0_1 - t0_1[0]
        omega_rows[is_motored] = np.asarray(ss0.omega, dtype=np.float64)
        periods[is_motored] = float(np.asarray(ss0.period_s))
    starts = np.concatenate([[0.0], np.cumsum(periods)]) - periods[0]
    theta = (theta1[None, :] + cycle_rad * rows_k[:, None]).ravel()
    t = (t_rows + starts[:-1, None]).ravel()
    omega = omega_rows.ravel()
    theta = np.append(theta, theta[-1] + (theta1[1] - theta1[0]))
    t = np.append(t, starts[-1])
    omega = np.append(omega, omega_rows[-1, 0])
    t_of = CubicHermiteSpline(theta, t, 1.0 / omega)
    theta_of = CubicHermiteSpline(t, theta, omega)
    # from 36…180° (drawn) before the first cycle's start to 36…180° after the last one's end: exactly
    # ``cycles`` complete cycles, with space for the edges around them
    lead_in, lead_out = rng.uniform(0.1, 0.5, 2) * 2 * np.pi
    t0 = float(t_of(-lead_in))
    duration = float(t_of(cycles * cycle_rad + lead_out)) - t0
    n = int(math.floor(duration * fs)) + 1
    ts = np.arange(n) / fs  # the file's time column
    th = theta_of(t0 + ts)  # crank angle of each sample
    return _Motion(t_of, theta_of, float(theta[0]), float(theta[-1]), t0, ts, th, cycle_rad, pitch_s)


def _pressure(eng, motion: _Motion, comb_scale: float, motored_set) -> np.ndarray:
    """Cylinder 1's pressure at the samples [Pa]: on a fine grid of one cycle (one compiled
    call), then a periodic cubic spline; the engine file's motored cycle in the motored cycles."""
    import equinox as eqx
    from scipy.interpolate import CubicSpline

    cycle_rad, th = motion.cycle_rad, motion.th
    revs = round(cycle_rad / (2 * np.pi))
    grid = np.arange(PRESSURE_POINTS_PER_REV * revs) * (cycle_rad / (PRESSURE_POINTS_PER_REV * revs))
    p_grid = np.asarray(cylinder_pressure(eng, grid))[:, 0]
    if comb_scale != 1.0:  # scale the combustion part: fired − motored
        motored = eqx.tree_at(lambda e: e.pressure, eng, eng.pressure.motored(eng.strokes))
        p0 = np.asarray(cylinder_pressure(motored, grid))[:, 0]
        p_grid = p0 + comb_scale * (p_grid - p0)
    p_of = CubicSpline(np.append(grid, cycle_rad), np.append(p_grid, p_grid[0]), bc_type="periodic")
    p = p_of(np.mod(th, cycle_rad))
    if motored_set:
        unfired = eqx.tree_at(lambda e: e.pressure, eng, eng.pressure.motored(eng.strokes))
        pm_grid = np.asarray(cylinder_pressure(unfired, grid))[:, 0]
        pm_of = CubicSpline(np.append(grid, cycle_rad), np.append(pm_grid, pm_grid[0]), bc_type="periodic")
        k_of = np.floor(th / cycle_rad).astype(int)
        m = np.isin(k_of, sorted(motored_set))
        p[m] = pm_of(np.mod(th[m], cycle_rad))
    return p


def _encoder_volts(bench: _Bench, motion: _Motion) -> np.ndarray:
    """The encoder channel at the samples [V], without noise: the wheel's teeth (with their
    errors) passing, each edge a short ramp."""
    w, fs, ts, th = bench.wheel, bench.fs, motion.ts, motion.th
    pitch_s, t_of, t0 = motion.pitch_s, motion.t_of, motion.t0
    E = w.edges_per_rev
    err = _wheel_errors(w, bench.tooth_error_deg)
    pitch = 2 * np.pi / w.teeth
    gap = np.deg2rad(bench.gap_deg)
    # the first edge after the gap at crank angle gap (+ k·2π): relative to TDC before intake, and to firing TDC
    r0 = int(math.floor((th[0] - gap) / (2 * np.pi))) - 1
    r1 = int(math.ceil((th[-1] - gap) / (2 * np.pi))) + 1
    rev = np.arange(r0, r1 + 1)
    rise = (gap + 2 * np.pi * rev[:, None] + pitch * np.arange(E)[None, :] + err[None, :]).ravel()
    fall = rise + DUTY * pitch
    keep = (rise > motion.theta_lo) & (fall < motion.theta_hi)
    rise_t, fall_t = t_of(rise[keep]) - t0, t_of(fall[keep]) - t0
    # high(t) is a sum of boxes [rise, fall); filtered by a box of width R each edge becomes a linear ramp.
    # The sample value is the box average, (H(s + (1 − l)·R) − H(s − l·R))/R with H the high time up to s,
    # evaluated exactly for every sample from the sorted edges; l = EDGE_LEVEL puts a rising edge's crossing of
    # that fraction of the swing (where rotor.find_edges times it) at the edge's true time.
    R = min(RAMP_SAMPLES / fs, DUTY * pitch_s / 3)
    # rise < fall < next rise: the errors are below a quarter pitch, the high part 45 % of one
    knots = np.column_stack([rise_t, fall_t]).ravel()
    level = np.tile([1.0, 0.0], rise_t.size)  # the state after each knot (1 high, 0 low)
    H_knots = np.concatenate([[0.0], np.cumsum(level[:-1] * np.diff(knots))])

    def H(s):
        i = np.searchsorted(knots, s, side="right") - 1
        inside = i >= 0
        ii = np.clip(i, 0, None)
        return np.where(inside, H_knots[ii] + level[ii] * (s - knots[ii]), 0.0)

    frac = (H(ts + (1 - EDGE_LEVEL) * R) - H(ts - EDGE_LEVEL * R)) / R
    return LOW_V + (HIGH_V - LOW_V) * frac


def simulated_tooth_times(
    path: str | os.PathLike,
    run: SpeedResult,
    *,
    wheel: str | Wheel | None = None,
    gap_deg: float = DEFAULT_GAP_DEG,
    tooth_error_deg: float = 0.1,
    jitter_s: float = 20e-9,
    start_deg: float = 0.0,
    end_deg: float | None = None,
    seed: int = 0,
) -> pathlib.Path:
    """Write the tooth edge times of any simulated run (:func:`rotor.simulate`: an ignition
    cut, a coast-down, a load step) as a tooth-time log (one column, ``tooth_time_s`` [s],
    read with ``wheel``), the wheel turning with the crank.

    **Arguments:**
    - ``path``: the file to write (its folder must exist); written whole or not at all.
    - ``run``: a :class:`rotor.SpeedResult` (θ from 0 at cylinder 1's TDC at the start of
      intake; its samples need not be uniform).
    - ``wheel``: a spec or :class:`rotor.Wheel` with a gap (default 60-2).
    - ``gap_deg``: crank angle of the first tooth edge after the gap relative to cylinder 1's
      TDC [deg] (default −29.4: TDC 29.4° after the gap, as on the real bench).
    - ``tooth_error_deg``: the wheel's tooth-spacing errors, uniform in ±this [deg] (the
      same wheel as :func:`simulated_recording`'s; :func:`simulated_tooth_errors`).
    - ``jitter_s``: standard deviation of white timer noise on each edge [s] (default 20 ns).
    - ``start_deg``, ``end_deg``: the crank angles [deg] where the recording starts and
      ends (default: the run's whole span): anywhere in a cycle.
    - ``seed``: seeds the timer noise.

    **Returns:** the path written. Raises :class:`rotor.EngineError` naming an argument
    that cannot be used.
    """
    from ..fileio import write_text_atomic

    path = pathlib.Path(path)
    if not path.parent.is_dir():
        raise EngineError(f"path = {os.fspath(path)!r}: the folder {os.fspath(path.parent)!r} does not exist")
    text = simulated_tooth_time_text(
        run,
        wheel=wheel,
        gap_deg=gap_deg,
        tooth_error_deg=tooth_error_deg,
        jitter_s=jitter_s,
        start_deg=start_deg,
        end_deg=end_deg,
        seed=seed,
    )
    write_text_atomic(path, text)
    return path


def simulated_tooth_time_text(
    run: SpeedResult,
    *,
    wheel: str | Wheel | None = None,
    gap_deg: float = DEFAULT_GAP_DEG,
    tooth_error_deg: float = 0.1,
    jitter_s: float = 20e-9,
    start_deg: float = 0.0,
    end_deg: float | None = None,
    seed: int = 0,
) -> str:
    """The lines :func:`simulated_tooth_times` writes (one tooth edge time [s] per line,
    from 0), for a caller that writes them with more in one file; the arguments as there."""
    from scipy.interpolate import CubicSpline

    try:
        w = Wheel(60, 2) if wheel is None else parse_wheel(wheel)
        if w.missing >= 1:
            w = wheel_with_layout(w, None)  # where its gaps lie: the standard layout, or spread evenly
    except ValueError as e:
        raise EngineError(f"wheel = {wheel!r}: {e}") from None
    if w.missing < 1:
        raise EngineError(f"wheel = {w.spec!r}: a simulated tooth-time log needs a wheel with a gap (e.g. 60-2)")
    gap = np.deg2rad(_number("gap_deg", gap_deg))
    tooth_error_deg = _number("tooth_error_deg", tooth_error_deg, nonnegative=True)
    if tooth_error_deg >= 360.0 / w.teeth / 4:
        raise EngineError(f"tooth_error_deg = {tooth_error_deg:g}: must be below a quarter of the {w.spec} pitch")
    jitter_s = _number("jitter_s", jitter_s, nonnegative=True)
    th = np.asarray(run.theta, dtype=np.float64)
    t = np.asarray(run.t, dtype=np.float64)
    keep = np.concatenate([[True], np.diff(th) > 0])
    th, t = th[keep], t[keep]
    lo = max(float(th[0]), np.deg2rad(_number("start_deg", start_deg)))
    hi = float(th[-1]) if end_deg is None else min(float(th[-1]), np.deg2rad(_number("end_deg", end_deg)))
    if not hi > lo:
        raise EngineError(f"start_deg = {start_deg!r}, end_deg = {end_deg!r}: an empty span of the run")
    err = _wheel_errors(w, tooth_error_deg)
    r0, r1 = int(math.floor((lo - gap) / (2 * np.pi))) - 1, int(math.ceil((hi - gap) / (2 * np.pi))) + 1
    rev = np.arange(r0, r1 + 1)
    ang = (gap + 2 * np.pi * rev[:, None] + w.tooth_angles_rad[None, :] + err[None, :]).ravel()
    ang = ang[(ang >= lo) & (ang <= hi)]
    times = CubicSpline(th, t)(ang) + np.random.default_rng(seed).normal(0.0, jitter_s, ang.size)
    out = io.StringIO()
    np.savetxt(out, times - times[0], fmt="%.10f")
    return out.getvalue()
