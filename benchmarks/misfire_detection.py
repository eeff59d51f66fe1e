"""The misfire monitor judged as an OBD monitor: misfire rates over 200- and 1000-revolution
windows, the cylinder named, false flags over fault-free driving, every detector at the same
false alarms on the same runs; and the monitor's throughput and memory.

    .venv/bin/python benchmarks/misfire_detection.py --quick      # a small grid, under 2 minutes
    nice -n 15 .venv/bin/python benchmarks/misfire_detection.py   # the full grid (about an hour)

**The recordings** are simulated here in the angle domain, fast enough for thousands of
cycles per condition: the crank's kinetic energy E = ½·I·ω² follows
dE/dθ = M_gas(θ) + M_d(θ) − c·ω² (a load that grows with speed, so that the mean speed is
stable), M_gas the sum of each firing's work W spread over its expansion stroke and a
zero-mean compression ripple at the firing frequency (twice the mean torque), M_d a
fault-free transient's torque (below). The work's shape over the stroke
(``--work-shape``): ``gas`` (the default, published), W·x·e^(−x/τ)/τ² at x after TDC,
τ = 32°, renormalised over the stroke: nought at TDC and peaking 32° after it, as the
combustion torque of the presets does (42 % of the work done by 45° after TDC, 79 % by
90°, against 43–46 % and 82–83 % in the combustion tables of 4chn15, mwm6 and v8);
``sine``, ½·W·sin x (peaking 90° after TDC). W = IMEP·V_d at the load's IMEP (full load
10 bar; half 50 %; idle 15 %; ``zero_torque`` 8 %, about what friction and pumping take, the
edge of the positive-torque region); a misfire has W = 0. Cylinders of 0.5 l; the crank train
with what it drives 0.4 kg·m² (1 cylinder), 0.5 (3), 0.6 (4), 0.8 (6) or 1.0 kg·m² (8). The
wheel (60-2, 36-1 or 36-2-1: after the two-tooth gap 16 teeth, one missing, 17 teeth) has
tooth-spacing errors uniform in ±0.1° (one wheel of each kind for all runs), the timer 20 ns
of white noise; cylinder 1's TDC lies 30° after the gap.

**Cycle-to-cycle variation from real cycles.** Each firing's work is W·(1 + CoV·z): the
CoV is that of the net IMEP of the 60 consecutive fired cycles of a Yanmar L100V single-
cylinder diesel at 1800 rpm and 18 N·m (the pressure traces of the depcik/heat-release
repository, University of Kansas, read from ``../shared/data/yanmar-l100v``: net IMEP
∮p·dV/V_d over 720° from the engine's bore, stroke, rod and compression ratio), and z is
drawn with replacement from those cycles' standardised IMEP deviations, so that the shape
of the variation (its skew and tails) is the real one too. Where the data folder is
absent the committed figures are used (CoV 1.59 %, normal z). The draws are independent
(the real cycles' lag-one correlation, about 0.2, is not kept); the same CoV is used at
every load and speed.

**The runs of a condition** (speed × load × cylinders × wheel): four fault-free runs, at
steady speed, with a load step (25 % of the mean torque added at the run's middle), with a
speed ramp (a drive torque rising to 30 % of the mean torque: the engine speeds up) and
on a rough road (a driveline torque of four sines at 3, 7, 11 and 17 Hz, 10 % of the mean
torque each); and one run for each misfire pattern: ``random`` (any firing at 2 % of all
the firings), ``single`` (one cylinder's firings, 2 % of all the firings), ``paired`` (events
of two consecutive firings, 2 % of all the firings), ``continuous`` (one cylinder dead).

**The detectors.**

- ``rotor``: :class:`rotor.diagnostics.monitor.MisfireMonitor` without an engine file (its
  index: the change of kinetic energy over each firing's segment against running
  per-cylinder medians, less the deviation common to the next half cycle's firings, over a
  running spread; the loss claimed by a neighbour that lost more than twice as much is not
  flagged). It finds the wheel and the firings itself, on the wheel's nominal angles.
- ``ema_n_of_m``: written from rusEFI's description of its misfire detection (rusEFI
  project documentation, "Misfire detection"): an exponential moving average of the tooth
  period (α = 0.05 a tooth), each tooth's deviation from it, and a misfire where N = 3 of
  M = 5 consecutive teeth in the firing's segment deviate by more than the threshold. On the
  nominal angles (its description has no wheel correction).
- ``angular_acceleration``: the crankshaft's angular acceleration over the firing's
  segment (Plapp, Klenk, Moser, "Methods of on-board misfire detection", SAE 900232): the
  mean speed over the segment after the firing's TDC less that over the segment before it,
  over the time between them.
- ``roughness``: the segment-time running-roughness of the same authors and of Klenk,
  Moser, Müller, Wimmer, "Misfire detection by evaluating crankshaft speed — a means to
  comply with OBDII", SAE 930399: LU = (T_i − T_(i−1))/T_i³ from the times T of
  consecutive firing segments.
- ``…_per_cylinder``: the same two, each firing's score less the median of its cylinder's
  last 8 (the per-cylinder normalisation of the same papers).

The two published baselines are made as strong as their descriptions allow: they read the
edges at the wheel's **true** angles (a wheel profile learnt perfectly, the most that the
papers' learning on a deceleration gives), and each has its own threshold at every
operating point (a speed- and load-dependent threshold map, at its best). Detectors whose
verdicts (every firing flagged on every run) are the same in every condition are one
method (``angular_acceleration = roughness``: a monotone transform of each other).

**One rule for every threshold, on the same runs**: each detector's threshold is set where
its false alarms over all the runs of the condition (the four fault-free ones and the normal
firings of the runs with misfires, the firings after each misfire included) are 1 per 1000
cycles (the score of the ⌊cycles/1000⌋+1-th highest normal firing), so that every detector
is compared at the same false alarms measured on the same firings; the detection rate of
each pattern has a 95 % Wilson interval.

**The windows.** From each detector's per-firing detection rate p_d of a pattern and its
false-alarm rate p_f, the windows of §1968.2(e)(3) (:mod:`rotor.diagnostics.misfire_rate`):
1000 revolutions against the emission rate of 1 %, 200 revolutions against the catalyst
table's rate at the condition's speed and load. A window whose firings misfire at a rate r
(0.5 … 5 % and the threshold's; continuous: the dead cylinder's 100/n %) in the pattern is
drawn 4000 times, each misfire counted with probability p_d and each normal firing with p_f,
independently: the probability that its counted rate reaches the threshold (flagged), with
the interval from p_d's, and that it is flagged with the right code (the dead or misfiring
cylinder's for single and continuous, P0300 for random and paired); the lowest rate whose
windows are flagged in 95 % of cases; and the fault-free windows flagged per 1000 (exact,
binomial, from the fault-free runs' p_f, with the upper end from its interval). A window at
exactly the threshold rate is flagged only where every misfire in it is counted (or false
calls make up the missing ones): the rate at which 95 % of windows are flagged tells more.

Writes ``benchmarks/published/misfire_detection_quick.json`` and ``.png`` (``--quick``,
marked as quick) or ``benchmarks/published/misfire_detection.json`` and ``.png`` (their rows,
several MB, in ``benchmarks/results/…_rows.json``, which ``--replot`` draws from): one row
per detector and condition (threshold, false alarms per run, per pattern the detection rate
and its interval and the windows), the methods, a summary per condition and pattern, the
conditions where rotor's 1000-revolution windows at 1 % are flagged in 95 % of cases and
where no method's are; the throughput (a V8 at 8000 rpm on a 60-2 wheel fed a revolution at
a time, with the windows and codes: margin over real time in wall and CPU time) and the
memory the monitor holds over a long stream. ``--throughput-only`` measures those alone and
puts them into the published JSON (on a shared machine, at a quieter moment).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.signal import lfilter

import rotor
from rotor.diagnostics.monitor import MisfireMonitor
from rotor.logs.wheel import Wheel, parse_wheel

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
PUBLISHED = ROOT / "benchmarks" / "published"
YANMAR = ROOT.parent / "shared" / "data" / "yanmar-l100v"
TDC_DEG = 30.0
CYCLE = 4 * np.pi
SPEEDS = (800.0, 2000.0, 4000.0, 6000.0)
LOADS = {"zero_torque": 0.08, "idle": 0.15, "half": 0.5, "full": 1.0}
CYLINDERS = (1, 3, 4, 6, 8)
WHEELS = ("60-2", "36-1", "36-2-1")
LAYOUTS = {"36-2-1": (16, 17)}
FULL_IMEP_PA = 10e5
VD_M3 = 0.5e-3
INERTIA = {1: 0.4, 3: 0.5, 4: 0.6, 6: 0.8, 8: 1.0}
TOOTH_ERROR_DEG = 0.1
JITTER_S = 20e-9
N_OF_M = (3, 5)
EMA_ALPHA = 0.05
EVENT_RATE = 0.011
PAIR_SHARE = 1 / 3
WHEEL_SEED = 12345
DETECTORS = (
    "rotor",
    "ema_n_of_m",
    "angular_acceleration",
    "roughness",
    "angular_acceleration_per_cylinder",
    "roughness_per_cylinder",
)
COMMITTED_COV = 0.0159  # net IMEP CoV of the 60 Yanmar L100V fired cycles, measured by this script


# ---------------------------------------------------------------------- variation
YANMAR_VD_M3 = np.pi * 0.086**2 / 4 * 0.075
"""The Yanmar L100V's displacement [m³] (bore 86 mm, stroke 75 mm)."""


def yanmar_net_imep(name="fired-18Nm.txt"):
    """The net IMEP [Pa] of each cycle of a Yanmar L100V pressure file (``fired-18Nm.txt``
    or ``motored.txt``), in the order recorded: ∮p·dV/V_d over 720° from the engine's
    bore, stroke, rod and compression ratio; None where the data folder is absent."""
    path = YANMAR / name
    if not path.is_file():
        return None
    d = np.loadtxt(path)
    th = np.deg2rad(d[:, 0])
    p = d[:, 1:] * 1e5
    bore, stroke, rod, cr = 0.086, 0.075, 0.118, 21.2  # the folder's README (the source's input script)
    r = stroke / 2
    area = np.pi * bore**2 / 4
    vd = area * stroke
    v = vd / (cr - 1) + area * (r * (1 - np.cos(th)) + rod - np.sqrt(rod**2 - (r * np.sin(th)) ** 2))
    return np.trapezoid(p * np.gradient(v, th)[:, None], th, axis=0) / vd


def yanmar_variation():
    """The CoV of the net IMEP of the Yanmar fired cycles and their standardised deviations
    (None where the data folder is absent: the committed CoV, normal deviations)."""
    imep = yanmar_net_imep("fired-18Nm.txt")
    if imep is None:
        return {"cov": COMMITTED_COV, "z": None, "source": "committed figure (data folder absent)"}
    z = (imep - imep.mean()) / imep.std(ddof=1)
    return {
        "cov": float(imep.std(ddof=1) / imep.mean()),
        "z": z,
        "source": "computed from ../shared/data/yanmar-l100v/fired-18Nm.txt",
        "cycles": int(imep.size),
        "imep_bar_mean": float(imep.mean() / 1e5),
        "lag1_correlation": float(np.corrcoef(z[:-1], z[1:])[0, 1]),
        "skewness": float(np.mean(z**3)),
    }


# ---------------------------------------------------------------------- simulation
def wheel_layout(spec):
    w = parse_wheel(spec)
    if spec in LAYOUTS:
        w = Wheel(w.teeth, w.missing, w.gaps, LAYOUTS[spec], w.angles_deg)
    return w.teeth, np.asarray(w.positions, dtype=np.int64)


def misfire_pattern(rng, fk, count):
    """Misfire events on about EVENT_RATE of the firings (a third of them pairs); the mask."""
    mis = np.zeros(count, dtype=bool)
    start = np.flatnonzero((rng.random(count) < EVENT_RATE) & (fk >= 1))
    mis[start] = True
    pairs = start[rng.random(start.size) < PAIR_SHARE]
    mis[np.minimum(pairs + 1, count - 1)] = True
    return mis


PATTERNS = ("random", "single", "paired", "continuous")
PATTERN_RATE = 0.02
"""The misfire rate of the runs with faults [-, of all the firings] (continuous: one cylinder's every firing)."""
SINGLE_SLOT = 1  # the cylinder of the single and continuous patterns: the second to fire (cylinder 2)


def pattern_mask(rng, fk, fj, n, pattern, rate=PATTERN_RATE):
    """The misfiring firings of a pattern (firings of cycle 1 on): ``random`` on any firing
    at ``rate``; ``single`` on one cylinder's firings at n·rate (``rate`` of all the firings);
    ``paired``: events at rate/2 of two consecutive firings; ``continuous``: one cylinder's
    every firing (a dead cylinder)."""
    live = fk >= 1
    if pattern == "random":
        return live & (rng.random(fk.size) < rate)
    if pattern == "single":
        return live & (fj == SINGLE_SLOT % n) & (rng.random(fk.size) < min(1.0, n * rate))
    if pattern == "continuous":
        return live & (fj == SINGLE_SLOT % n)
    mis = np.zeros(fk.size, dtype=bool)
    start = np.flatnonzero(live & (rng.random(fk.size) < rate / 2))
    mis[start] = True
    mis[np.minimum(start + 1, fk.size - 1)] = True
    return mis


DISTURBANCES = ("steady", "load_step", "speed_ramp", "rough_road")
ROUGH_ROAD_HZ = (3.0, 7.0, 11.0, 17.0)
"""The frequencies of the rough road's driveline torque [Hz], each 10 % of the mean torque."""


def disturbance_torque(kind, mid, theta0, theta_end, mean_torque, rpm, rng):
    """The torque a fault-free transient adds [N·m] at the angles ``mid``: ``load_step`` a
    load 25 % of the mean torque from the run's middle on; ``speed_ramp`` a drive torque
    rising from 0 to 30 % of the mean torque over the run (the engine speeds up);
    ``rough_road`` a driveline torque of four sines of 10 % of the mean torque each at
    :data:`ROUGH_ROAD_HZ` (at the start speed), random phases."""
    if kind == "steady":
        return 0.0
    if kind == "load_step":
        return -0.25 * mean_torque * (mid > 0.5 * (theta0 + theta_end))
    if kind == "speed_ramp":
        return 0.3 * mean_torque * (mid - theta0) / (theta_end - theta0)
    out = np.zeros(mid.size)
    for f in ROUGH_ROAD_HZ:
        out += 0.1 * mean_torque * np.sin(f * 60.0 / rpm * mid + rng.uniform(0, 2 * np.pi))
    return out


GAS_TAU = math.radians(32.0)  # the gas work shape's peak after TDC


def work_density(x: np.ndarray) -> np.ndarray:
    """The share of a firing's work per radian at ``x`` (0 ≤ x < π) after its TDC, for
    :data:`WORK_SHAPE`; it integrates to 1 over the expansion stroke."""
    if WORK_SHAPE == "sine":
        return 0.5 * np.sin(x)
    u = np.pi / GAS_TAU
    return x * np.exp(-x / GAS_TAU) / (GAS_TAU**2 * (1 - (1 + u) * math.exp(-u)))


WORK_SHAPE = "gas"


def simulate(
    n, rpm, load, cycles, wheel, variation, faults=False, seed=0, substeps=4, work_of=None, disturbance="steady"
):
    """Tooth times of a ``n``-cylinder four-stroke (see the module doc): (times [s], their
    nominal crank angles [rad], firing angles, firing (cycle, slot), misfire mask, their true
    crank angles [rad]). Angles as the monitor counts them: θ = wheel angle − TDC + 2π, cycle k
    from kΘ. ``faults``: False, True (the events of :func:`misfire_pattern`) or a pattern of
    :data:`PATTERNS`; ``disturbance``: one of :data:`DISTURBANCES`. ``work_of``: where given,
    each firing's work [J] (any sign) is ``work_of(cycle, slot)`` (arrays of the firings) in
    place of the drawn variation and misfires (the load is still set by ``load``)."""
    rng = np.random.default_rng(seed)
    teeth, pos = wheel_layout(wheel)
    pitch = 2 * np.pi / teeth
    revs = 2 * cycles + 4
    # one wheel of each kind for every run (its tooth errors are the installation's, the
    # same on the fault-free runs that set the thresholds and on the runs with misfires)
    errors = np.deg2rad(np.random.default_rng(WHEEL_SEED).uniform(-TOOTH_ERROR_DEG, TOOTH_ERROR_DEG, pos.size))
    theta0 = 2 * np.pi - np.deg2rad(TDC_DEG)
    d = pitch / substeps
    fine = theta0 + np.arange(revs * teeth * substeps + 1) * d
    inertia = INERTIA[n]
    w0 = rpm * np.pi / 30
    work_mean = load * FULL_IMEP_PA * VD_M3
    ks = np.arange(int(np.floor(theta0 / CYCLE)), int(np.ceil(fine[-1] / CYCLE)) + 1)
    slots = np.arange(n)
    fire_in_cycle = np.mod(2 * np.pi + slots * CYCLE / n, CYCLE)
    fire = (ks[:, None] * CYCLE + fire_in_cycle[None, :]).ravel()
    fk = np.repeat(ks, n)
    fj = np.tile(slots, ks.size)
    order = np.argsort(fire, kind="stable")  # the firings in the order they come
    fire, fk, fj = fire[order], fk[order], fj[order]
    z = (
        rng.standard_normal(fire.size)
        if variation["z"] is None
        else rng.choice(np.asarray(variation["z"]), size=fire.size, replace=True)
    )
    work = work_mean * (1 + variation["cov"] * z).clip(0)
    if isinstance(faults, str):
        mis = pattern_mask(rng, fk, fj, n, faults)
    else:
        mis = misfire_pattern(rng, fk, fire.size) if faults else np.zeros(fire.size, dtype=bool)
    work[mis] = 0.0
    if work_of is not None:
        work = np.asarray(work_of(fk, fj), dtype=np.float64)
    # gas torque on the fine grid: each firing's work over its expansion stroke in the shape
    # of :func:`work_density` (a point lies within π after at most ⌈π / interval⌉ firings)
    mid = fine[:-1] + d / 2
    M = np.zeros(mid.size)
    last = np.searchsorted(fire, mid, side="right") - 1
    for lag in range(int(math.ceil(np.pi / (CYCLE / n))) + 1):
        i = last - lag
        ok = i >= 0
        after = mid[ok] - fire[i[ok]]
        inside = after < np.pi
        M[np.flatnonzero(ok)[inside]] += work[i[ok][inside]] * work_density(after[inside])
    mean_torque = work_mean * n / CYCLE
    M += 2 * mean_torque * np.sin(n / 2 * (mid - fire_in_cycle[0]) + np.pi)
    M += disturbance_torque(disturbance, mid, fine[0], fine[-1], mean_torque, rpm, rng)
    # dE/dθ = M − c·ω² = M − (2c/I)·E, with c set so that the mean speed is w0
    c = mean_torque / w0**2
    kk = 2 * c / inertia
    E0 = 0.5 * inertia * w0**2
    E = lfilter([d], [1.0, -(1 - kk * d)], M, zi=[(1 - kk * d) * E0])[0]
    E = np.concatenate([[E0], E])
    omega = np.sqrt(2 * np.maximum(E, 1e-9) / inertia)
    t_fine = np.concatenate([[0.0], np.cumsum(d / (0.5 * (omega[:-1] + omega[1:])))])
    # the tooth edges: nominal positions with the wheel's errors, at their true angles
    base = theta0 + 2 * np.pi * np.arange(revs)[:, None] + pitch * pos[None, :]
    edge_true = (base + errors[None, :]).ravel()
    edge_nominal = base.ravel()
    ok = edge_true < fine[-1]
    t = np.interp(edge_true[ok], fine, t_fine) + rng.normal(0, JITTER_S, int(ok.sum()))
    return t, edge_nominal[ok], fire, fk, fj, mis, edge_true[ok]


# ---------------------------------------------------------------------- detectors
def rotor_scores(t, n, wheel):
    """(cycle, slot) → −index of the monitor where its neighbours do not claim the loss (the
    monitor's own rule: not flagged where a neighbouring firing lost more than twice as
    much), −inf where they do: a misfire where the score exceeds the threshold."""
    m = MisfireMonitor(wheel, tdc_deg=TDC_DEG, cylinders=n, threshold=1e9)
    rev = parse_wheel(wheel).edges_per_rev
    out = []
    for i in range(0, t.size, rev):
        out += m.feed(t[i : i + rev])
    out += m.close()
    idx = np.array([v.index for v in out])
    prev = np.concatenate([[np.inf], idx[:-1]])
    nxt = np.concatenate([idx[1:], [np.inf]])
    spill = idx > 0.5 * np.minimum(prev, nxt)
    return {(v.cycle, v.cylinder - 1): (-np.inf if sp else -v.index) for v, sp in zip(out, spill)}


def ema_scores(t, theta, fire, fk, fj, n, teeth):
    """(cycle, slot) → the N-of-M score: the N-th largest of M consecutive tooth-period
    deviations from their moving average, the largest such over the firing's segment."""
    span = np.round(np.diff(theta) / (2 * np.pi / teeth))
    p = np.diff(t) / span
    ema = lfilter([EMA_ALPHA], [1.0, -(1 - EMA_ALPHA)], p, zi=[(1 - EMA_ALPHA) * p[0]])[0]
    dev = np.empty_like(p)
    dev[0] = 0.0
    dev[1:] = p[1:] / ema[:-1] - 1.0
    N, Mw = N_OF_M
    win = np.sort(sliding_window_view(dev, Mw), axis=1)[:, -N]  # the window ending at tooth i + Mw − 1
    th_end = theta[1:][np.arange(Mw - 1, dev.size)]
    seg = min(CYCLE / n, np.pi)
    lo = np.searchsorted(th_end, fire)
    hi = np.searchsorted(th_end, fire + seg)
    ok = (hi > lo) & (hi < th_end.size) & (fk >= 1)
    # the largest over each segment: a running maximum read at the segment's windows
    score = np.full(fire.size, -np.inf)
    for i in np.flatnonzero(ok):
        score[i] = win[lo[i] : hi[i]].max()
    return {(int(k), int(j)): float(s) for k, j, s, g in zip(fk, fj, score, ok) if g}


def segment_times(t, theta, fire, n):
    """Times and angles of the segment before and after each firing's TDC (the firing
    interval, at most 180°), their ends on the nearest tooth edge; NaN where outside."""
    seg = min(CYCLE / n, np.pi)
    marks = np.stack([fire - seg, fire, fire + seg], axis=1)
    i = np.clip(np.searchsorted(theta, marks), 1, theta.size - 1)
    i = np.where(theta[i] - marks > marks - theta[i - 1], i - 1, i)
    inside = (marks >= theta[0]) & (marks <= theta[-1])
    tt = np.where(inside, t[i], np.nan)
    th = np.where(inside, theta[i], np.nan)
    return np.diff(tt, axis=1), np.diff(th, axis=1), seg


def acceleration_scores(t, theta, fire, fk, fj, n):
    """(cycle, slot) → the deceleration over the firing: (ω before − ω after) / time."""
    dt, dth, _ = segment_times(t, theta, fire, n)
    w = dth / dt
    score = (w[:, 0] - w[:, 1]) / (0.5 * (dt[:, 0] + dt[:, 1]))
    ok = np.isfinite(score) & (fk >= 1)
    return {(int(k), int(j)): float(s) for k, j, s, g in zip(fk, fj, score, ok) if g}


def roughness_scores(t, theta, fire, fk, fj, n):
    """(cycle, slot) → the running roughness LU = (T_i − T_(i−1)) / T_i³ of the segment
    times (each scaled to the nominal segment angle)."""
    dt, dth, seg = segment_times(t, theta, fire, n)
    T = dt[:, 1] * seg / dth[:, 1]  # the segment after each TDC, firing by firing
    prev = np.concatenate([[np.nan], T[:-1]])
    score = (T - prev) / T**3
    ok = np.isfinite(score) & (fk >= 1)
    return {(int(k), int(j)): float(s) for k, j, s, g in zip(fk, fj, score, ok) if g}


PER_CYLINDER_HISTORY = 8
"""Firings of a cylinder whose median score the per-cylinder baselines take off."""


def per_cylinder(sc):
    """The scores ``sc`` less the median of the same cylinder's last
    :data:`PER_CYLINDER_HISTORY` scores (a firing with fewer than three before it left out)."""
    out = {}
    for j in {j for _, j in sc}:
        keys = sorted(key for key in sc if key[1] == j)
        x = np.array([sc[key] for key in keys])
        pad = np.concatenate([np.full(PER_CYLINDER_HISTORY, np.nan), x[:-1]])
        hist = sliding_window_view(pad, PER_CYLINDER_HISTORY)[: x.size]
        have = np.isfinite(hist).sum(axis=1)
        with np.errstate(all="ignore"):
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                med = np.nanmedian(hist, axis=1)
        for key, v, m, h in zip(keys, x, med, have):
            if h >= 3 and np.isfinite(v):
                out[key] = float(v - m)
    return out


def scores(name, run, n, wheel):
    """(cycle, slot) → the detector's score (a misfire where it exceeds the threshold). The
    baselines other than ``ema_n_of_m`` read the edges at their true angles: a wheel profile
    learnt perfectly (the most that learning it on a deceleration gives)."""
    t, theta, fire, fk, fj, _, true = run
    if name == "rotor":
        return rotor_scores(t, n, wheel)
    if name == "ema_n_of_m":
        return ema_scores(t, theta, fire, fk, fj, n, wheel_layout(wheel)[0])
    base = name.removesuffix("_per_cylinder")
    fn = acceleration_scores if base == "angular_acceleration" else roughness_scores
    sc = fn(t, true, fire, fk, fj, n)
    return per_cylinder(sc) if name.endswith("_per_cylinder") else sc


# ---------------------------------------------------------------------- the rule
def wilson(k, n, z=1.96):
    if n == 0:
        return [None, None]
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return [max(0.0, c - h), min(1.0, c + h)]


WINDOW_DRAWS = 4000
"""Windows drawn for each window probability (its own sampling error about ±0.01)."""
RATES_PCT = (0.5, 1.0, 2.0, 3.0, 5.0)
"""The misfire rates [% of the firings] at which the windows are judged."""


def window_kinds(rpm, load):
    """(kind, revolutions, threshold [%]) of the two windows at this speed and load."""
    from rotor.diagnostics.misfire_rate import (
        CATALYST_REVOLUTIONS,
        DEFAULT_CATALYST_TABLE,
        EMISSION_RATE_PCT,
        EMISSION_REVOLUTIONS,
    )

    return (
        ("emission", EMISSION_REVOLUTIONS, EMISSION_RATE_PCT),
        ("catalyst", CATALYST_REVOLUTIONS, DEFAULT_CATALYST_TABLE.rate_at(rpm, load)),
    )


def window_probability(n, revolutions, threshold_pct, rate_pct, pattern, p_d, p_f, rng):
    """The probability that a window of ``revolutions`` whose firings misfire at ``rate_pct``
    in ``pattern`` is flagged (the misfires counted, true and false, at least
    ``threshold_pct`` of its firings), and that it is flagged with the right code (the
    cylinder of a single or continuous pattern; P0300 for random and paired misfires of an
    engine of two or more cylinders): each misfire counted with probability ``p_d``, each
    normal firing with ``p_f``, independently (the per-firing rates measured on the runs)."""
    from rotor.diagnostics.misfire_rate import MIN_SHARE

    per_cyl = int(round(revolutions / 2)) if n else 0  # a four-stroke cylinder fires every other revolution
    N = per_cyl * n
    need = math.ceil(threshold_pct / 100 * N - 1e-9)
    one = pattern in ("single", "continuous")
    slot = SINGLE_SLOT % n
    if pattern == "continuous":
        M = np.zeros((WINDOW_DRAWS, n), dtype=np.int64)
        M[:, slot] = per_cyl
    elif one:
        M = np.zeros((WINDOW_DRAWS, n), dtype=np.int64)
        M[:, slot] = min(per_cyl, int(round(rate_pct / 100 * N)))
    else:
        M = rng.multinomial(int(round(rate_pct / 100 * N)), [1 / n] * n, size=WINDOW_DRAWS)
        M = np.minimum(M, per_cyl)
    counts = rng.binomial(M, p_d) + rng.binomial(per_cyl - M, p_f)
    total = counts.sum(axis=1)
    flagged = total >= max(need, 1)
    share = (counts > 0) & (counts >= MIN_SHARE * total[:, None])
    named = share.sum(axis=1)
    right = (named == 1) & share[:, slot] if one or n == 1 else named >= 2
    return float(flagged.mean()), float((flagged & right).mean())


def false_flags_per_1000(n, revolutions, threshold_pct, p_f):
    """Fault-free windows flagged per 1000: the false calls of a window's firings (each with
    probability ``p_f``) reaching ``threshold_pct`` of them (exact, binomial)."""
    from scipy.stats import binom

    N = int(round(revolutions / 2)) * n
    need = max(math.ceil(threshold_pct / 100 * N - 1e-9), 1)
    return 1000.0 * float(binom.sf(need - 1, N, p_f))


def condition_eval(n, rpm, load_name, wheel, sizes, seed, variation):
    """Every detector on the runs of one condition (see the module doc, **The windows**):
    its threshold set on the normal firings of all the runs at 1 false alarm per 1000 cycles,
    its per-firing detection of each pattern, and the windows that follow."""
    load = LOADS[load_name]
    cond = {"rpm": rpm, "load": load_name, "cylinders": n, "wheel": wheel}
    runs = {}
    for k, dist in enumerate(DISTURBANCES):
        cycles = sizes["steady_cycles"] if dist == "steady" else sizes["transient_cycles"]
        runs[("fault_free", dist)] = simulate(n, rpm, load, cycles, wheel, variation, False, seed + k, disturbance=dist)
    for k, pat in enumerate(PATTERNS):
        if n == 1 and pat in ("single", "continuous"):
            continue  # one cylinder: single is random, continuous does not run
        cycles = max(sizes["faulty_firings"] // n, 200)
        runs[("faults", pat)] = simulate(n, rpm, load, cycles, wheel, variation, pat, seed + 10 + k)
    truth = {}
    for key, run in runs.items():
        _, _, _, fk, fj, mis, _ = run
        truth[key] = {(int(a), int(b)) for a, b, m in zip(fk, fj, mis) if m}
    rng = np.random.default_rng(seed)
    out = []
    for name in DETECTORS:
        sc = {key: scores(name, run, n, wheel) for key, run in runs.items()}
        normal = np.concatenate([[v for f, v in s.items() if f not in truth[key]] for key, s in sc.items()])
        cycles_all = sum(len({k for k, _ in s}) for s in sc.values())
        allowed = cycles_all // 1000
        ranked = np.sort(normal)[::-1]
        thr = float(ranked[allowed]) if ranked.size > allowed else math.inf
        flagged = {key: frozenset(f for f, v in s.items() if v > thr) for key, s in sc.items()}
        false = {key: len(flagged[key] - truth[key]) for key in sc}
        cyc = {key: len({k for k, _ in s}) for key, s in sc.items()}
        ff = [key for key in sc if key[0] == "fault_free"]
        nf_clean = sum(len(sc[key]) for key in ff)
        fa_clean = sum(false[key] for key in ff)
        p_f0 = fa_clean / max(nf_clean, 1)
        p_f = sum(false.values()) / max(normal.size, 1)
        row = {
            "detector": name,
            "condition": cond,
            "threshold": thr if math.isfinite(thr) else None,
            "false_alarms_per_1000_cycles": 1000 * sum(false.values()) / max(cycles_all, 1),
            "false_alarms_per_1000_cycles_by_run": {
                f"{a}:{b}": 1000 * false[(a, b)] / max(cyc[(a, b)], 1) for a, b in sc
            },
            "cycles": cycles_all,
            "verdicts": hashlib.sha1(repr(sorted((k, sorted(v)) for k, v in flagged.items())).encode()).hexdigest(),
            "patterns": {},
        }
        for key in sc:
            if key[0] != "faults":
                continue
            pat = key[1]
            judged = [f for f in truth[key] if f in sc[key]]
            hits = sum(1 for f in judged if sc[key][f] > thr)
            p_d = hits / len(judged) if judged else 0.0
            lo, hi = wilson(hits, len(judged)) if judged else (0.0, 0.0)
            pr = {"misfires": len(judged), "detection_rate": p_d, "detection_rate_ci95": [lo, hi], "windows": {}}
            for kind, revs, limit in window_kinds(rpm, load):
                lim = round(limit, 3)
                rates = (100.0 / n,) if pat == "continuous" else tuple(sorted({*RATES_PCT, lim}))
                at = {}
                for r in rates:
                    f, named = window_probability(n, revs, limit, r, pat, p_d, p_f, rng)
                    f_lo, _ = window_probability(n, revs, limit, r, pat, lo, p_f, rng)
                    f_hi, _ = window_probability(n, revs, limit, r, pat, hi, p_f, rng)
                    at[f"{r:g}"] = {"flagged": f, "flagged_ci95": [f_lo, f_hi], "right_code": named}
                flag_at = None if pat == "continuous" else lim
                pr["windows"][kind] = {
                    "revolutions": revs,
                    "threshold_pct": round(limit, 3),
                    "at_rate_pct": at,
                    "flagged_at_threshold": None if flag_at is None else at[f"{flag_at:g}"]["flagged"],
                    "lowest_rate_pct_flagged_95": next((r for r in rates if at[f"{r:g}"]["flagged"] >= 0.95), None),
                }
            row["patterns"][pat] = pr
        row["false_flags_per_1000_fault_free_windows"] = {
            kind: false_flags_per_1000(n, revs, limit, p_f0) for kind, revs, limit in window_kinds(rpm, load)
        }
        row["false_flags_per_1000_fault_free_windows_ci95_upper"] = {
            kind: false_flags_per_1000(n, revs, limit, wilson(fa_clean, max(nf_clean, 1))[1])
            for kind, revs, limit in window_kinds(rpm, load)
        }
        out.append(row)
    return out


# ---------------------------------------------------------------------- throughput
def _feed_all(m, t, size=58):
    verdicts = 0
    for i in range(0, t.size, size):
        verdicts += len(m.feed(t[i : i + size]))
    return verdicts + len(m.close())


def _feed_all_open(m, t, size=58):
    """Feed without keeping the verdicts or the windows, as a consumer that hands them on does
    (the monitor's memory alone)."""
    for i in range(0, t.size, size):
        m.feed(t[i : i + size])
        m.pop_windows()


def python_loop_ns(repeats=15):
    """This machine's pure-Python speed, measured beside the monitor: the median time of one
    iteration of ``for x in xs: s += x * x`` over 1000 floats [ns]. The monitor's work a
    revolution is a few whole-chunk NumPy calls and Python per firing, so its margin over
    real time scales with this figure from machine to machine."""
    import timeit

    timer = timeit.Timer("s = 0.0\nfor x in xs: s += x * x", setup="xs = [1.0] * 1000")
    return 1e9 * float(np.median([timer.timeit(200) / 200 / 1000 for _ in range(repeats)]))


def throughput(variation, cycles=2000, repeats=15):
    """A V8 at 8000 rpm on 60-2, fed one revolution at a time: wall and CPU time, the margin
    over real time; and the memory the monitor's allocations hold at their peak, after the
    first tenth of the stream and over the rest (tracemalloc, in a separate pass)."""
    import tracemalloc

    t = simulate(8, 8000.0, 0.5, cycles, "60-2", variation, False, seed=7)[0]
    walls, cpus = [], []
    verdicts = 0
    _feed_all(MisfireMonitor("60-2", tdc_deg=TDC_DEG, cylinders=8), t[: t.size // 10])  # warm the code paths
    for _ in range(repeats):
        m = MisfireMonitor("60-2", tdc_deg=TDC_DEG, cylinders=8)
        w0, c0 = time.perf_counter(), time.process_time()
        verdicts = _feed_all(m, t)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    # the same without the misfire-rate windows and codes, measured beside it: their cost
    bare_cpus = []
    for _ in range(repeats):
        m = MisfireMonitor("60-2", tdc_deg=TDC_DEG, cylinders=8, windows=False)
        c0 = time.process_time()
        _feed_all(m, t)
        bare_cpus.append(time.process_time() - c0)
    real = float(t[-1] - t[0])
    wall, cpu = float(np.median(walls)), float(np.median(cpus))
    # the same stream with an engine file (the v8 preset): each firing's IMEP from the model too
    MisfireMonitor("60-2", tdc_deg=TDC_DEG, engine="v8", check_fit=False)  # its tables built once
    engine_cpus = []
    for _ in range(repeats):
        m = MisfireMonitor("60-2", tdc_deg=TDC_DEG, engine="v8", check_fit=False)
        c0 = time.process_time()
        _feed_all(m, t)
        engine_cpus.append(time.process_time() - c0)
    m = MisfireMonitor("60-2", tdc_deg=TDC_DEG, cylinders=8)
    cut = (t.size // 10) // 58 * 58
    tracemalloc.start()
    _feed_all_open(m, t[:cut])
    first_current, first_peak = tracemalloc.get_traced_memory()
    tracemalloc.reset_peak()
    _feed_all_open(m, t[cut:])
    rest_current, rest_peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {
        "case": "V8, 8000 rpm, 60-2 wheel, chunks of one revolution (58 edges), one process on one core, with "
        "the misfire-rate windows and codes (the default)",
        "edges": int(t.size),
        "verdicts": verdicts,
        "log_seconds": real,
        "wall_s": wall,
        "cpu_s": cpu,
        "margin_over_real_time_wall": real / wall,
        "margin_over_real_time_cpu": real / cpu,
        "margin_over_real_time_cpu_best": real / min(cpus),
        "margin_over_real_time_wall_best": real / min(walls),
        "edges_per_s_cpu": t.size / cpu,
        "cpu_us_per_revolution": 1e6 * cpu / (t.size / 58),
        "without_windows": {
            "case": "the same stream, the monitor made with windows=False (no misfire-rate windows or codes)",
            "cpu_s": float(np.median(bare_cpus)),
            "margin_over_real_time_cpu": real / float(np.median(bare_cpus)),
            "windows_cost_share": cpu / float(np.median(bare_cpus)) - 1.0,
        },
        "with_engine": {
            "case": "the same stream with engine='v8' (the preset's firing angles and model IMEP of every firing)",
            "cpu_s": float(np.median(engine_cpus)),
            "margin_over_real_time_cpu": real / float(np.median(engine_cpus)),
            "margin_over_real_time_cpu_best": real / min(engine_cpus),
        },
        "python_loop_ns": python_loop_ns(),
        "wall_s_runs": walls,
        "cpu_s_runs": cpus,
        "memory": {
            "method": "tracemalloc: the monitor's allocations after the first tenth of the stream "
            "(cycles), and their peak over the other nine tenths",
            "first_tenth_cycles": int(cut / 58 / 2),
            "rest_cycles": int((t.size - cut) / 58 / 2),
            "after_first_tenth_bytes": int(first_current),
            "peak_first_tenth_bytes": int(first_peak),
            "peak_rest_bytes": int(rest_peak),
            "end_bytes": int(rest_current),
            "peak_growth_bytes": int(rest_peak - first_peak),
            "buffer_edges_at_end": int(m.buffer_length),
        },
    }


# ---------------------------------------------------------------------- summary, figure
def merge_methods(rows):
    """Detectors whose verdicts (every firing flagged, on every run) are the same in every
    condition are one method: {detector: the method's name (its detectors joined by ' = ')}."""
    by = {}
    for r in rows:
        by.setdefault(r["detector"], []).append((json.dumps(r["condition"], sort_keys=True), r["verdicts"]))
    groups: list[list[str]] = []
    for name in DETECTORS:
        for g in groups:
            if sorted(by[g[0]]) == sorted(by[name]):
                g.append(name)
                break
        else:
            groups.append([name])
    return {name: " = ".join(g) for g in groups for name in g}


def compare(rows, methods):
    """Per condition and pattern: the methods' detection at their equal false alarms; whether
    their false alarms are within 2× or 1 per 1000 cycles of each other; a method above rotor
    by more than 0.02 beyond both 95 % intervals; where rotor's 1000-revolution windows at the
    emission rate are flagged in 95 % of cases, and where no method's are."""
    by = {}
    for r in rows:
        if methods[r["detector"]].split(" = ")[0] != r["detector"]:
            continue  # a merged method: its first detector stands for it
        by.setdefault(json.dumps(r["condition"], sort_keys=True), {})[methods[r["detector"]]] = r
    out = []
    for key, d in by.items():
        fa = [r["false_alarms_per_1000_cycles"] for r in d.values()]
        rot = d["rotor"]
        for pat in rot["patterns"]:
            above = []
            for name, r in d.items():
                if name == "rotor" or pat not in r["patterns"]:
                    continue
                excess = r["patterns"][pat]["detection_rate_ci95"][0] - rot["patterns"][pat]["detection_rate_ci95"][1]
                if excess > 0.02:
                    above.append({"method": name, "excess_beyond_intervals": excess})
            emission = {
                name: r["patterns"][pat]["windows"]["emission"]["flagged_at_threshold"]
                for name, r in d.items()
                if pat in r["patterns"]
            }
            out.append(
                {
                    "condition": json.loads(key),
                    "pattern": pat,
                    "detection_rate": {name: r["patterns"][pat]["detection_rate"] for name, r in d.items()},
                    "false_alarms_per_1000_cycles": {name: r["false_alarms_per_1000_cycles"] for name, r in d.items()},
                    "false_alarms_equal": bool(max(fa) - min(fa) <= 1.0 or max(fa) <= 2 * min(fa)),
                    "above_rotor_beyond_intervals": above,
                    "emission_window_flagged_at_threshold": emission,
                }
            )
    return out


def figure(rows, methods, path, title):
    """Per method (columns: the wheels) the lowest random misfire rate whose 1000-revolution
    windows are flagged in 95 % of cases, over speed (columns) and cylinders × load (rows)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [m for m in dict.fromkeys(methods.values())]
    first = {m: m.split(" = ")[0] for m in names}
    conds = [json.loads(c) for c in sorted({json.dumps(r["condition"], sort_keys=True) for r in rows})]
    wheels = [w for w in WHEELS if any(c["wheel"] == w for c in conds)]
    speeds = sorted({c["rpm"] for c in conds})
    ylab = [(n, ld) for n in CYLINDERS for ld in LOADS if any(c["cylinders"] == n and c["load"] == ld for c in conds)]
    low = {}
    for r in rows:
        p = r["patterns"].get("random")
        if p is not None:
            low[(r["detector"], json.dumps(r["condition"], sort_keys=True))] = p["windows"]["emission"][
                "lowest_rate_pct_flagged_95"
            ]
    fig, axes = plt.subplots(
        len(names), len(wheels), figsize=(3.4 * len(wheels) + 1, 0.3 * len(ylab) * len(names) + 1.6), squeeze=False
    )
    for a, m in enumerate(names):
        for b, w in enumerate(wheels):
            img = np.full((len(ylab), len(speeds)), np.nan)
            for i, (n, ld) in enumerate(ylab):
                for j, s in enumerate(speeds):
                    key = json.dumps({"rpm": s, "load": ld, "cylinders": n, "wheel": w}, sort_keys=True)
                    v = low.get((first[m], key), "absent")
                    img[i, j] = np.nan if v == "absent" else (10.0 if v is None else v)
            ax = axes[a, b]
            ax.imshow(img, vmin=0.5, vmax=5.0, cmap="RdYlGn_r", aspect="auto")
            for i in range(len(ylab)):
                for j in range(len(speeds)):
                    if np.isfinite(img[i, j]):
                        ax.text(j, i, ">5" if img[i, j] > 5 else f"{img[i, j]:g}", ha="center", va="center", fontsize=6)
            ax.set_xticks(range(len(speeds)), [f"{s:.0f}" for s in speeds], fontsize=7)
            ax.set_yticks(range(len(ylab)), [f"{n} cyl {ld}" for n, ld in ylab], fontsize=6)
            ax.set_title(f"{m}, {w}", fontsize=7)
            if a == len(names) - 1:
                ax.set_xlabel("rpm", fontsize=7)
    fig.suptitle(title, fontsize=8, wrap=True)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.5 / fig.get_figheight()))
    fig.savefig(path, dpi=110)
    plt.close(fig)


FIGURE_TITLE = (
    "lowest random misfire rate [%] whose 1000-revolution windows are flagged in 95 % of cases,\nevery detector at "
    "1 false alarm per 1000 cycles ({grid} grid; >5: none up to 5 %)"
)


def print_throughput(tp):
    print(
        f"throughput: {tp['edges']} edges ({tp['log_seconds']:.1f} s of log) in {tp['wall_s']:.2f} s wall, "
        f"{tp['cpu_s']:.2f} s CPU: {tp['margin_over_real_time_wall']:.0f}x real time (wall), "
        f"{tp['margin_over_real_time_cpu']:.0f}x (CPU), medians of {len(tp['cpu_s_runs'])} runs; the fastest run "
        f"{tp['margin_over_real_time_wall_best']:.0f}x (wall), {tp['margin_over_real_time_cpu_best']:.0f}x (CPU)"
    )
    print(f"this machine's Python: {tp['python_loop_ns']:.0f} ns an iteration of a float loop, measured beside it")
    bare = tp["without_windows"]
    print(
        f"without the windows and codes: {bare['margin_over_real_time_cpu']:.0f}x real time (CPU, median): the "
        f"windows cost {100 * bare['windows_cost_share']:+.0f} %"
    )
    eng = tp["with_engine"]
    print(
        f"with an engine file (model IMEP): {eng['margin_over_real_time_cpu']:.0f}x real time (CPU, median), "
        f"{eng['margin_over_real_time_cpu_best']:.0f}x the fastest"
    )
    mem = tp["memory"]
    print(
        f"memory: {mem['after_first_tenth_bytes'] / 1024:.1f} KiB held after {mem['first_tenth_cycles']} cycles, "
        f"peak {mem['peak_rest_bytes'] / 1024:.1f} KiB over the next {mem['rest_cycles']} cycles "
        f"(growth of the peak {mem['peak_growth_bytes'] / 1024:+.1f} KiB)"
    )


def _condition(task):
    return condition_eval(*task)


def print_condition(r):
    c = r[0]["condition"]
    print(
        f"{c['wheel']:6s} {c['cylinders']} cyl {c['rpm']:5.0f} rpm {c['load']:11s}: "
        + "  ".join(
            f"{x['detector'][:12]} "
            + "/".join(f"{p['detection_rate']:.2f}" for p in x["patterns"].values())
            + f" ({x['false_alarms_per_1000_cycles']:.1f})"
            for x in r
        ),
        flush=True,
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the small grid (under 2 minutes), marked as quick")
    ap.add_argument("--speeds", type=str, default=None, help="rpm, comma separated (default the full grid's)")
    ap.add_argument("--loads", type=str, default=None, help="zero_torque,idle,half,full (default all)")
    ap.add_argument("--cylinders", type=str, default=None, help="1,3,4,6,8 (default all)")
    ap.add_argument("--wheels", type=str, default=None, help="60-2,36-1,36-2-1 (default all)")
    ap.add_argument("--no-throughput", action="store_true", help="skip the throughput and memory measurement")
    ap.add_argument("--jobs", type=int, default=1, help="conditions evaluated in parallel processes (default 1)")
    ap.add_argument(
        "--work-shape",
        choices=("gas", "sine"),
        default="gas",
        help="each firing's work over its expansion stroke: gas (peaks 32° after TDC, the default, published) or "
        "sine (½·W·sin, peaks 90° after TDC)",
    )
    ap.add_argument(
        "--throughput-only",
        action="store_true",
        help="measure the throughput and memory alone and put them into the published JSON (a run of its own, "
        "for a quieter moment of a shared machine)",
    )
    ap.add_argument("--replot", action="store_true", help="draw the figure again from the published JSON")
    args = ap.parse_args()
    if args.replot:
        path = PUBLISHED / ("misfire_detection_quick.json" if args.quick else "misfire_detection.json")
        d = json.loads(path.read_text())
        rows_path = _rows_path(path)
        if not rows_path.is_file():
            sys.exit(f"{rows_path.relative_to(ROOT)} is not here: the figure is drawn from a run's rows (run the grid)")
        methods = {name: m for m in d["methods"] for name in m.split(" = ")}
        figure(
            json.loads(rows_path.read_text()), methods, path.with_suffix(".png"), FIGURE_TITLE.format(grid=d["grid"])
        )
        print(f"drew {path.with_suffix('.png').relative_to(ROOT)}")
        return
    global WORK_SHAPE
    WORK_SHAPE = args.work_shape
    t0 = time.perf_counter()
    variation = yanmar_variation()
    if args.throughput_only:
        tp = throughput(variation)
        tp["measured"] = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()) + ", a run of its own"
        print_throughput(tp)
        path = PUBLISHED / "misfire_detection.json"
        out = json.loads(path.read_text()) if path.is_file() else {}
        out["throughput"] = tp
        PUBLISHED.mkdir(parents=True, exist_ok=True)
        write_published(path, out)
        print(f"wrote the throughput into {path.relative_to(ROOT)}")
        return
    print(f"cycle-to-cycle variation: CoV {100 * variation['cov']:.2f} % of IMEP ({variation['source']})", flush=True)
    if args.quick:
        grid = {
            "speeds": [800.0, 4000.0, 6000.0],
            "loads": ["zero_torque", "full"],
            "cylinders": [4, 8],
            "wheels": ["60-2"],
        }
        sizes = {"steady_cycles": 600, "transient_cycles": 300, "faulty_firings": 3000}
    else:
        grid = {"speeds": list(SPEEDS), "loads": list(LOADS), "cylinders": list(CYLINDERS), "wheels": list(WHEELS)}
        sizes = {"steady_cycles": 2000, "transient_cycles": 600, "faulty_firings": 6000}
    for name, conv in (("speeds", float), ("loads", str), ("cylinders", int), ("wheels", str)):
        given = getattr(args, name)
        if given:
            grid[name] = [conv(x) for x in given.split(",")]
    tasks = [
        (n, rpm, load, wheel, sizes, 100 + 20 * i, variation)
        for i, (wheel, n, rpm, load) in enumerate(
            (w, n, r, ld)
            for w in grid["wheels"]
            for n in grid["cylinders"]
            for r in grid["speeds"]
            for ld in grid["loads"]
        )
    ]
    rows = []
    if args.jobs > 1:
        import multiprocessing

        with multiprocessing.get_context("fork").Pool(args.jobs) as pool:
            results = pool.imap(_condition, tasks)
            for r in results:
                rows += r
                print_condition(r)
    else:
        for task in tasks:
            r = condition_eval(*task)
            rows += r
            print_condition(r)
    methods = merge_methods(rows)
    summary = compare(rows, methods)
    for r in rows:
        r.pop("verdicts")
    full = grid == {"speeds": list(SPEEDS), "loads": list(LOADS), "cylinders": list(CYLINDERS), "wheels": list(WHEELS)}
    random = [s for s in summary if s["pattern"] == "random"]
    meets = [s["condition"] for s in random if (s["emission_window_flagged_at_threshold"]["rotor"] or 0) >= 0.95]
    none = [
        s["condition"]
        for s in random
        if not any((v or 0) >= 0.95 for v in s["emission_window_flagged_at_threshold"].values())
    ]
    out = {
        "grid": "quick" if args.quick else ("full" if full else "part of the full grid"),
        "grid_run": grid,
        "sizes": sizes,
        "work_shape": WORK_SHAPE,
        "rule": "each detector's threshold: the score of the (floor(cycles/1000)+1)-th highest normal firing of all "
        "the runs of a condition (fault-free steady, load step, speed ramp, rough road, and the runs with each "
        "pattern): 1 false alarm per 1000 cycles for every detector on the same runs; windows from the per-firing "
        "rates, each firing counted independently",
        "patterns": f"random, single (one cylinder), paired, at {100 * PATTERN_RATE:g} % of all the firings; "
        "continuous: one cylinder dead",
        "cycle_to_cycle_variation": {k: v for k, v in variation.items() if k != "z"},
        "methods": sorted(set(methods.values()), key=list(methods.values()).index),
        "rows": rows,
        "summary": summary,
        "conditions": len(random),
        "false_alarms_equal_in_every_condition": all(s["false_alarms_equal"] for s in summary),
        "rotor_meets_1pct_emission_windows": meets,
        "no_method_meets_1pct_emission_windows": none,
        "above_rotor_beyond_intervals": [s for s in summary if s["above_rotor_beyond_intervals"]],
    }
    print(
        f"methods: {out['methods']}; rotor's 1000-revolution windows at 1 % (random misfires) flagged in 95 % "
        f"in {len(meets)} of {len(random)} conditions, no method's in {len(none)}; a method above rotor by more "
        f"than 0.02 beyond the intervals in {len(out['above_rotor_beyond_intervals'])} condition-patterns "
        f"({sorted({s['pattern'] for s in out['above_rotor_beyond_intervals']})})",
        flush=True,
    )
    if not args.no_throughput:
        tp = throughput(variation)
        out["throughput"] = tp
        print_throughput(tp)
    out.update(
        {
            "seconds": time.perf_counter() - t0,
            "cpu_seconds_this_process": time.process_time(),
            "jobs": args.jobs,
            "rotor": rotor.__version__,
            "numpy": np.__version__,
            "python": platform.python_version(),
            "machine": platform.machine(),
        }
    )
    if WORK_SHAPE != "gas":
        RESULTS.mkdir(parents=True, exist_ok=True)
        path = RESULTS / f"misfire_detection_{WORK_SHAPE}.json"
    else:
        PUBLISHED.mkdir(parents=True, exist_ok=True)
        path = PUBLISHED / ("misfire_detection_quick.json" if args.quick else "misfire_detection.json")
        figure(
            rows,
            methods,
            path.with_suffix(".png"),
            FIGURE_TITLE.format(grid=out["grid"]),
        )
    write_published(path, out)


def _rows_path(path: Path) -> Path:
    """Where a run's rows (every detector × condition, several MB) go: the results folder, which
    the repository does not keep; the published JSON keeps the summaries."""
    return RESULTS / f"{path.stem}_rows.json"


def write_published(path: Path, out: dict) -> None:
    """``out`` at ``path`` without its rows, and the rows beside the other results."""
    rows = out.get("rows")
    kept = {k: v for k, v in out.items() if k != "rows"}
    if rows is not None:
        RESULTS.mkdir(parents=True, exist_ok=True)
        _rows_path(path).write_text(json.dumps(rows, separators=(",", ":"), allow_nan=False) + "\n")
        kept["rows_written_to"] = str(_rows_path(path).relative_to(ROOT))
    path.write_text(json.dumps(kept, indent=1, allow_nan=False) + "\n")
    print(
        f"wrote {path.relative_to(ROOT)}" + (f" and {_rows_path(path).relative_to(ROOT)}" if rows is not None else "")
    )


if __name__ == "__main__":
    main()
