"""A simulated run written as a wheel log, with its truth beside it.

:func:`record_run` turns a :class:`rotor.SpeedResult` of :func:`rotor.simulate` into the
log a bench would have recorded from a trigger wheel on the crankshaft, so that the run
can be read back with the tools that read real recordings (:func:`rotor.analyze_log`,
:func:`rotor.diagnose`, ``rotor analyze``, ``rotor diagnose``) and their findings checked
against what was simulated.

**The log** (``signal="teeth"``, the one kind so far): one tooth edge time [s] per row
under the header ``tooth_time_s`` (so that no column spec is needed to read it), made by
:func:`rotor.diagnostics.synthetic.simulated_tooth_times` (the wheel's tooth-spacing
errors and the timer's jitter included). Comment lines (``#``) before the header name
the engine, the wheel and where TDC lies, and state the phase in two lines a reader can
use, ``# tdc_after_gap_deg: 29.4`` and ``# firing_parity: 0`` (:func:`stated_phase`;
:func:`rotor.diagnose` takes them where no calibration or option gives TDC).

**Lead-in and lead-out.** A reader counts complete cycles from the first TDC it can place
after the first gap; a run starts at cylinder 1's TDC before intake (crank angle 0). So
that the log's first complete cycle is the run's cycle 1, the log starts one cycle
before the run, that cycle a copy of the run's first; and it ends with a revolution after
it: a copy of the run's last revolution where the engine's torque repeats every revolution
(an even firing order), else of the first revolution of its last cycle (one cylinder, an
uneven firing order: the last revolution would not join on in the phase of the cycle). The
truth says so.

**The truth** (a JSON file beside the log, ``<log stem>.truth.json``): the engine, the
wheel, ``tdc_after_gap_deg`` (cylinder 1's TDC after the gap [deg]), the run's cycles
with each firing's IMEP [Pa] (cycles and cylinders counted from 1, the numbers
``rotor diagnose`` reports), the misfires as (cycle, cylinder) pairs, the operating
point, and the lead-in and lead-out.
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
from typing import Any

import numpy as np

from ..errors import EngineError
from ..units import PA_PER_BAR, RPM_PER_RAD_S
from .stated import stated_phase

__all__ = ["SIGNALS", "record_run", "stated_phase", "truth_path"]

SIGNALS = ("teeth",)
"""The kinds of signal a run can be recorded as: ``"teeth"``, tooth edge times."""


def truth_path(path: str | os.PathLike) -> pathlib.Path:
    """The truth file beside the log ``path``: ``rec.csv`` → ``rec.truth.json``."""
    p = pathlib.Path(path)
    return p.with_name(p.stem + ".truth.json")


def record_run(
    path: str | os.PathLike,
    run: Any,
    *,
    wheel: str = "60-2",
    signal: str = "teeth",
    gap_deg: float | None = None,
    tooth_error_deg: float = 0.0,
    jitter_s: float = 20e-9,
    seed: int = 0,
    misfires: list[tuple[int, int]] | None = None,
    engine_name: str | None = None,
) -> tuple[pathlib.Path, pathlib.Path]:
    """Write the run ``run`` (a :class:`rotor.SpeedResult` of :func:`rotor.simulate` holding
    every sample) as a wheel log at ``path`` and its truth beside it (see the module doc).

    **Arguments:** ``wheel``: a wheel spec with a gap (``"60-2"``, ``"36-1"``);
    ``signal``: ``"teeth"`` (tooth edge times, the one kind so far); ``gap_deg``: crank
    angle of the first tooth edge after the gap relative to cylinder 1's TDC [deg] (default
    −29.4: TDC 29.4° after the gap); ``tooth_error_deg``: the wheel's tooth-spacing errors,
    uniform in ±this [deg] (default 0: a perfect wheel, so that a diagnosis without a
    wheel calibration reads the run as simulated; 0.1 is a real wheel's size); ``jitter_s``: the timer's white noise on each edge [s];
    ``seed``: seeds the jitter; ``misfires``: the (cycle, cylinder) pairs planted, from 1
    (default: the firings whose IMEP lies below a quarter of the median firing's, read from
    ``run.imep_pa``); ``engine_name``: for the truth (default the
    run's).

    **Files:** the log and its truth are written together, each whole, both or neither
    (:func:`rotor.fileio.write_texts_atomic`): both paths are checked before the work, and
    a failure while they are put in place leaves the old files (or none) as they were.

    **Returns:** (the log's path, the truth's path). **Raises:** :class:`rotor.EngineError`
    for a run that cannot be recorded (no complete cycle, samples dropped by
    ``keep_cycles``, a stall) or an argument that cannot be used; an ``OSError`` naming the
    file that cannot be written (a missing folder, a folder's name, a link, a device, …).
    """
    from ..fileio import check_writable_file, json_file_text, write_texts_atomic
    from .synthetic import DEFAULT_GAP_DEG, simulated_tooth_time_text

    if signal not in SIGNALS:
        raise EngineError(f"signal = {signal!r}: one of {', '.join(map(repr, SIGNALS))}")
    if run.kind != "transient" or run.uniform_cycles < 1:
        raise EngineError("run: a transient run (rotor.simulate) with at least one complete cycle")
    if run.first_kept_cycle_index > 0:
        raise EngineError("run: its early cycles' samples were dropped (keep_cycles); record a run that keeps them")
    if run.stalled:
        raise EngineError("run: it stalled; a wheel log of a stopping crankshaft is not written")
    path = pathlib.Path(path)
    truth_file = truth_path(path)
    for target in (path, truth_file):  # both writable before the work: the two are written together
        check_writable_file(target)
    gap = DEFAULT_GAP_DEG if gap_deg is None else float(gap_deg)
    theta = np.asarray(run.theta, dtype=np.float64)
    t = np.asarray(run.t, dtype=np.float64)
    keep = np.concatenate([[True], np.diff(theta) > 0])
    theta, t = theta[keep], t[keep]
    omega = np.asarray(run.omega, dtype=np.float64)[keep]
    if theta[-1] < float(run.cycle_rad) + 2 * np.pi:
        raise EngineError("run: too short to record; it needs more than one cycle and a revolution")
    lead_in, lead_out = float(run.cycle_rad), 2 * np.pi
    # the lead-in repeats the first cycle one cycle earlier, the lead-out a revolution one
    # cycle or one revolution later: the engine's own fluctuation all through, in its phase
    # (:func:`_lead_out_source`), as a reader expects of a log
    cycle = float(run.cycle_rad)
    first = (theta > 0) & (theta < lead_in)
    t_in = float(np.interp(lead_in, theta, t))
    back = _lead_out_source(theta, np.asarray(run.torque, dtype=np.float64)[keep], cycle)
    last = (theta > theta[-1] - back) & (theta < theta[-1] - back + lead_out)
    t_back = float(np.interp(theta[-1] - back, theta, t))
    theta_all = np.concatenate([theta[first] - lead_in, theta, theta[last] + back])
    t_all = np.concatenate([t[first] - t_in, t, t[last] - t_back + t[-1]])
    padded = dataclasses.replace(run, theta=theta_all, t=t_all - t_all[0])
    body = simulated_tooth_time_text(
        padded,
        wheel=wheel,
        gap_deg=gap,
        tooth_error_deg=tooth_error_deg,
        jitter_s=jitter_s,
        seed=seed,
        start_deg=float(np.rad2deg(theta_all[0])),
    )
    name = run.engine_name if engine_name is None else engine_name
    log_text = (
        f"# a run recorded by rotor (record_run): {name}, wheel {wheel}, cylinder 1's TDC {-gap:g}° after the gap; "
        f"tooth edge times [s]; the truth in {truth_file.name}\n"
        f"# tdc_after_gap_deg: {-gap:g}\n"
        "# firing_parity: 0\n"
        "tooth_time_s\n" + body
    )
    imep = np.asarray(run.imep_pa, dtype=np.float64)
    if misfires is None:
        misfires = _low_firings(imep)
    truth = {
        "engine": name,
        "log": path.name,
        "signal": signal,
        "columns": ["tooth_time_s"],
        "wheel": wheel,
        "tdc_after_gap_deg": -gap,
        "tooth_error_deg": tooth_error_deg,
        "jitter_s": jitter_s,
        "cycles": int(run.uniform_cycles),
        "cycles_counted_from": 1,
        "lead_in_deg": float(np.rad2deg(lead_in)),
        "lead_out_deg": float(np.rad2deg(lead_out)),
        "lead_note": "the log starts one cycle before the run (a copy of its first cycle) and ends one revolution "
        "after it (a copy of its last revolution), so that the log's first complete cycle is the run's cycle 1",
        "start_rpm": float(omega[0] * RPM_PER_RAD_S),
        "mean_rpm": float(run.mean_rpm),
        "load_torque_Nm": None if run.load_torque_Nm is None else float(run.load_torque_Nm),
        "fuel_scale": None if run.fuel_scale is None else float(run.fuel_scale),
        "solved_for": run.solved_for,
        "misfires": [list(p) for p in misfires],
        "imep_bar": (imep / PA_PER_BAR).round(6).tolist(),
        "imep_pa": imep.tolist(),
    }
    truth_text = json_file_text(truth_file, truth, what="the truth of the recorded run", error=EngineError)
    write_texts_atomic([(path, log_text), (truth_file, truth_text)])  # both or neither
    return path, truth_file


def _low_firings(imep: np.ndarray) -> list[tuple[int, int]]:
    """(cycle, cylinder) pairs, from 1, of the firings far below the run's usual IMEP: below
    a quarter of the median firing's."""
    typical = float(np.median(imep))
    low = imep < 0.25 * typical if typical > 0 else np.zeros_like(imep, dtype=bool)
    return [(int(k) + 1, int(c) + 1) for k, c in np.argwhere(low)]


def _lead_out_source(theta: np.ndarray, torque: np.ndarray, cycle: float) -> float:
    """How far back [rad] the revolution lies that the lead-out copies: the run's last
    revolution (2π) where the engine's torque repeats every revolution (the median cycle's
    two revolutions alike within 2 % of its range: the even firing orders of the usual
    multi-cylinder engines), so that the speed's drift over the copy is least; else (one
    cylinder, an uneven firing order, a two-stroke's one revolution) one cycle, so that
    the copy is in the phase of the cycle."""
    if cycle <= 2 * np.pi + 1e-9:
        return cycle
    cycles = int(theta[-1] // cycle)
    grid = np.arange(cycles)[:, None] * cycle + np.linspace(0.0, cycle, 720, endpoint=False)[None, :]
    median = np.median(np.interp(grid, theta, torque), axis=0)
    span = float(np.ptp(median))
    alike = span > 0 and float(np.max(np.abs(median[:360] - median[360:]))) <= 0.02 * span
    return 2 * np.pi if alike else cycle
