"""Misfire detection limits of the streaming monitor against three detectors written from
their published descriptions, at one false alarm per 1000 cycles; and the monitor's
throughput and memory.

    .venv/bin/python benchmarks/misfire_detection.py --quick      # a small grid, under 2 minutes
    nice -n 15 .venv/bin/python benchmarks/misfire_detection.py   # the full grid, published

**The recordings** are simulated here in the angle domain, fast enough for thousands of
cycles per condition: the crank's kinetic energy E = ½·I·ω² follows
dE/dθ = M_gas(θ) − c·ω² (a load that grows with speed, so that the mean speed is
stable), M_gas the sum of each firing's work W spread over its expansion stroke and a
zero-mean compression ripple at the firing frequency (twice the mean torque). The work's
shape over the stroke (``--work-shape``): ``gas`` (the default, published), W·x·e^(−x/τ)/τ²
at x after TDC, τ = 32°, renormalised over the stroke: nought at TDC and peaking 32°
after it, as the combustion torque of the presets does (42 % of the work done by 45°
after TDC, 79 % by 90°, against 43–46 % and 82–83 % in the combustion tables of 4chn15,
mwm6 and v8); ``sine``, ½·W·sin x (the figures published before, peaking 90° after TDC:
15 % of the work by 45°, 50 % by 90°). W = IMEP·V_d at the load's IMEP (full load 10 bar,
idle 15 % of it, half 50 %); a misfire has W = 0. Cylinders of 0.5 l; the crank train with
what it drives 0.4 kg·m² (1 cylinder), 0.6 (4), 0.8 (6) or 1.0 kg·m² (8). The wheel
(60-2, 36-1 or 36-2-1: after the two-tooth gap 16 teeth, one missing, 17 teeth) has
tooth-spacing errors uniform in ±0.1° (one wheel of each kind for all runs), the timer
20 ns of white noise; cylinder 1's TDC lies 30° after the gap.

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

**Misfires.** On the runs with faults, misfire events fall at random on 1.1 % of the
firings, two in three a single misfire and one in three a pair (two consecutive firings),
about 1.5 % of the firings in all; the detection rate is given over all misfires and
apart for singles and pairs.

**The detectors.**

- ``rotor``: :class:`rotor.diagnostics.monitor.MisfireMonitor` without an engine file
  (its index: the change of kinetic energy over each firing's segment against running
  per-cylinder medians, less the deviation common to the next half cycle's firings, over a
  running spread; the loss claimed by a neighbour that lost more than twice as much is not
  flagged). It finds the wheel and the firings itself.
- ``ema_n_of_m``: written from rusEFI's description of its misfire detection (rusEFI
  project documentation, "Misfire detection"): an exponential moving average of the tooth
  period (α = 0.05 a tooth), each tooth's deviation from it, and a misfire where N = 3 of
  M = 5 consecutive teeth in the firing's segment deviate by more than the threshold
  (the score: the largest over the segment of the N-th largest deviation of M teeth).
- ``angular_acceleration``: the crankshaft's angular acceleration over the firing's
  segment (Plapp, Klenk, Moser, "Methods of on-board misfire detection", SAE 900232):
  the mean speed over the segment after the firing's TDC less that over the segment
  before it, over the time between them; a misfire where the deceleration exceeds the
  threshold.
- ``roughness``: the segment-time running-roughness of the same authors and of Klenk,
  Moser, Müller, Wimmer, "Misfire detection by evaluating crankshaft speed — a means to
  comply with OBDII", SAE 930399: LU = (T_i − T_(i−1))/T_i³ from the times T of
  consecutive firing segments, against a threshold that is a map over speed and load (here
  one threshold per operating point, each set by the rule below).

The segments of the baselines are the firing interval (at most 180°) from TDC, their ends
on the nearest tooth edge; the baselines are given the true angle of every edge (the
synchronisation a controller has from its cam signal).

**One rule for every threshold**: on a separate fault-free run (3000 cycles in the full
grid), the threshold is set where the false alarms are 1 per 1000 cycles (the score of the
⌊cycles/1000⌋+1-th most extreme firing); the detection rate is measured on the runs with
misfires, with a 95 % Wilson interval, and the false alarms per 1000 cycles counted on
those runs' normal firings (out of sample).

Writes (``--quick``) ``benchmarks/results/misfire_detection_quick.json`` or (the full grid,
or what ``--speeds``/``--loads``/``--cylinders``/``--wheels`` select)
``benchmarks/published/misfire_detection.json`` and ``.png``: one row per detector and
condition, ``detector``, ``condition`` (a dict), ``detection_rate``,
``detection_rate_ci95``, ``false_alarms_per_1000_cycles``, and the threshold, the counts,
the single and pair rates; the throughput (a V8 at 8000 rpm on a 60-2 wheel fed a
revolution at a time: margin over real time in wall and CPU time) and the memory the
monitor holds over a long stream. ``--throughput-only`` measures those alone and puts them
into the published JSON (on a shared machine, at a quieter moment).
"""

from __future__ import annotations

import argparse
import json
import math
import platform
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
LOADS = {"idle": 0.15, "half": 0.5, "full": 1.0}
CYLINDERS = (1, 4, 6, 8)
WHEELS = ("60-2", "36-1", "36-2-1")
LAYOUTS = {"36-2-1": (16, 17)}
FULL_IMEP_PA = 10e5
VD_M3 = 0.5e-3
INERTIA = {1: 0.4, 4: 0.6, 6: 0.8, 8: 1.0}
TOOTH_ERROR_DEG = 0.1
JITTER_S = 20e-9
N_OF_M = (3, 5)
EMA_ALPHA = 0.05
EVENT_RATE = 0.011
PAIR_SHARE = 1 / 3
WHEEL_SEED = 12345
DETECTORS = ("rotor", "ema_n_of_m", "angular_acceleration", "roughness")
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


GAS_TAU = math.radians(32.0)  # the gas work shape's peak after TDC


def work_density(x: np.ndarray) -> np.ndarray:
    """The share of a firing's work per radian at ``x`` (0 ≤ x < π) after its TDC, for
    :data:`WORK_SHAPE`; it integrates to 1 over the expansion stroke."""
    if WORK_SHAPE == "sine":
        return 0.5 * np.sin(x)
    u = np.pi / GAS_TAU
    return x * np.exp(-x / GAS_TAU) / (GAS_TAU**2 * (1 - (1 + u) * math.exp(-u)))


WORK_SHAPE = "gas"


def simulate(n, rpm, load, cycles, wheel, variation, faults=False, seed=0, substeps=4, work_of=None):
    """Tooth times of a ``n``-cylinder four-stroke (see the module doc): (times [s], their
    nominal crank angles [rad], firing angles, firing (cycle, slot), misfire mask). Angles
    as the monitor counts them: θ = wheel angle − TDC + 2π, cycle k from kΘ. ``work_of``:
    where given, each firing's work [J] (any sign) is ``work_of(cycle, slot)`` (arrays of
    the firings) in place of the drawn variation and misfires (the load is still set by
    ``load``)."""
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
    return t, edge_nominal[ok], fire, fk, fj, mis


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


def scores(name, run, n, wheel):
    t, theta, fire, fk, fj, _ = run
    if name == "rotor":
        return rotor_scores(t, n, wheel)
    if name == "ema_n_of_m":
        return ema_scores(t, theta, fire, fk, fj, n, wheel_layout(wheel)[0])
    if name == "angular_acceleration":
        return acceleration_scores(t, theta, fire, fk, fj, n)
    return roughness_scores(t, theta, fire, fk, fj, n)


# ---------------------------------------------------------------------- the rule
def wilson(k, n, z=1.96):
    if n == 0:
        return [None, None]
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return [max(0.0, c - h), min(1.0, c + h)]


def condition_rows(n, rpm, load_name, wheel, clean_cycles, faulty_cycles, seed, variation):
    load = LOADS[load_name]
    cond = {"rpm": rpm, "load": load_name, "cylinders": n, "wheel": wheel}
    clean = simulate(n, rpm, load, clean_cycles, wheel, variation, False, seed)
    faulty = simulate(n, rpm, load, faulty_cycles, wheel, variation, True, seed + 1)
    _, _, _, fk, fj, mis = faulty
    truth = {(int(k), int(j)) for k, j, m in zip(fk, fj, mis) if m}
    order = {(int(k), int(j)): i for i, (k, j) in enumerate(zip(fk, fj))}
    # a misfire is "single" where both neighbouring firings fired, else part of a pair
    kind = {}
    for key in truth:
        i = order[key]
        kind[key] = "pair" if (i > 0 and mis[i - 1]) or (i + 1 < mis.size and mis[i + 1]) else "single"
    rows = []
    for name in DETECTORS:
        s_clean = scores(name, clean, n, wheel)
        s_fault = scores(name, faulty, n, wheel)
        cycles_clean = len({k for k, _ in s_clean})
        allowed = cycles_clean // 1000
        ranked = np.sort(np.asarray(list(s_clean.values())))[::-1]
        thr = float(ranked[allowed]) if ranked.size > allowed else math.inf
        judged = [key for key in truth if key in s_fault]
        hit = {key: s_fault[key] > thr for key in judged}
        normal = [v for key, v in s_fault.items() if key not in truth]
        fa = sum(1 for v in normal if v > thr)
        cycles_f = len({k for k, _ in s_fault})
        rate = {}
        for what in ("single", "pair"):
            keys = [key for key in judged if kind[key] == what]
            rate[what] = (sum(hit[key] for key in keys) / len(keys)) if keys else None
        n_hit = sum(hit.values())
        rows.append(
            {
                "detector": name,
                "condition": cond,
                "detection_rate": n_hit / len(judged) if judged else None,
                "detection_rate_ci95": wilson(n_hit, len(judged)),
                "false_alarms_per_1000_cycles": 1000 * fa / max(cycles_f, 1),
                "threshold": thr if math.isfinite(thr) else None,
                "misfires": len(judged),
                "detection_rate_single": rate["single"],
                "detection_rate_pair": rate["pair"],
                "fault_free_cycles": cycles_clean,
                "cycles_with_faults": cycles_f,
                "false_alarms": fa,
            }
        )
    return rows


# ---------------------------------------------------------------------- throughput
def _feed_all(m, t, size=58):
    verdicts = 0
    for i in range(0, t.size, size):
        verdicts += len(m.feed(t[i : i + size]))
    return verdicts + len(m.close())


def _feed_all_open(m, t, size=58):
    """Feed without keeping the verdicts (the monitor's memory alone)."""
    for i in range(0, t.size, size):
        m.feed(t[i : i + size])


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
        "case": "V8, 8000 rpm, 60-2 wheel, chunks of one revolution (58 edges), one process on one core",
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
def compare(rows):
    """Per condition: does rotor reach 95 % at 1/1000; does any detector; the largest margin
    by which a baseline's detection rate exceeds rotor's at no more false alarms."""
    by = {}
    for r in rows:
        by.setdefault(json.dumps(r["condition"], sort_keys=True), {})[r["detector"]] = r
    out = []
    for key, d in by.items():
        rot = d["rotor"]
        worse = []
        for name, r in d.items():
            if name == "rotor" or r["detection_rate"] is None or rot["detection_rate"] is None:
                continue
            if r["false_alarms_per_1000_cycles"] <= rot["false_alarms_per_1000_cycles"]:
                worse.append(r["detection_rate"] - rot["detection_rate"])
        out.append(
            {
                "condition": json.loads(key),
                "rotor_detection_rate": rot["detection_rate"],
                "rotor_reaches_95": bool(rot["detection_rate"] is not None and rot["detection_rate"] >= 0.95),
                "any_reaches_95": any(
                    r["detection_rate"] is not None and r["detection_rate"] >= 0.95 for r in d.values()
                ),
                "best_baseline": max(
                    (n for n in d if n != "rotor"), key=lambda n: d[n]["detection_rate"] or 0.0, default=None
                ),
                "baseline_excess_at_no_more_false_alarms": max(worse) if worse else None,
            }
        )
    return out


def figure(rows, path, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    conds = sorted({json.dumps(r["condition"], sort_keys=True) for r in rows})
    conds = [json.loads(c) for c in conds]
    wheels = [w for w in WHEELS if any(c["wheel"] == w for c in conds)]
    speeds = sorted({c["rpm"] for c in conds})
    ylab = [(n, ld) for n in CYLINDERS for ld in LOADS if any(c["cylinders"] == n and c["load"] == ld for c in conds)]
    rate = {(r["detector"], json.dumps(r["condition"], sort_keys=True)): r["detection_rate"] for r in rows}
    fig, axes = plt.subplots(
        len(DETECTORS), len(wheels), figsize=(3.2 * len(wheels) + 1, 0.32 * len(ylab) * len(DETECTORS) + 1.5)
    )
    axes = np.atleast_2d(axes).reshape(len(DETECTORS), len(wheels))
    for a, det in enumerate(DETECTORS):
        for b, w in enumerate(wheels):
            img = np.full((len(ylab), len(speeds)), np.nan)
            for i, (n, ld) in enumerate(ylab):
                for j, s in enumerate(speeds):
                    key = json.dumps({"rpm": s, "load": ld, "cylinders": n, "wheel": w}, sort_keys=True)
                    v = rate.get((det, key))
                    img[i, j] = np.nan if v is None else v
            ax = axes[a, b]
            ax.imshow(img, vmin=0, vmax=1, cmap="RdYlGn", aspect="auto")
            for i in range(len(ylab)):
                for j in range(len(speeds)):
                    if np.isfinite(img[i, j]):
                        ax.text(j, i, f"{img[i, j]:.2f}", ha="center", va="center", fontsize=6)
            ax.set_xticks(range(len(speeds)), [f"{s:.0f}" for s in speeds], fontsize=7)
            ax.set_yticks(range(len(ylab)), [f"{n} cyl {ld}" for n, ld in ylab], fontsize=6)
            ax.set_title(f"{det}, {w}", fontsize=8)
            if a == len(DETECTORS) - 1:
                ax.set_xlabel("rpm", fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def print_throughput(tp):
    print(
        f"throughput: {tp['edges']} edges ({tp['log_seconds']:.1f} s of log) in {tp['wall_s']:.2f} s wall, "
        f"{tp['cpu_s']:.2f} s CPU: {tp['margin_over_real_time_wall']:.0f}x real time (wall), "
        f"{tp['margin_over_real_time_cpu']:.0f}x (CPU), medians of {len(tp['cpu_s_runs'])} runs; the fastest run "
        f"{tp['margin_over_real_time_wall_best']:.0f}x (wall), {tp['margin_over_real_time_cpu_best']:.0f}x (CPU)"
    )
    print(f"this machine's Python: {tp['python_loop_ns']:.0f} ns an iteration of a float loop, measured beside it")
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the small grid (under 2 minutes), to benchmarks/results")
    ap.add_argument("--speeds", type=str, default=None, help="rpm, comma separated (default the full grid's)")
    ap.add_argument("--loads", type=str, default=None, help="idle,half,full (default all)")
    ap.add_argument("--cylinders", type=str, default=None, help="1,4,6,8 (default all)")
    ap.add_argument("--wheels", type=str, default=None, help="60-2,36-1,36-2-1 (default all)")
    ap.add_argument("--clean-cycles", type=int, default=None, help="fault-free cycles a condition (default 3000)")
    ap.add_argument("--faulty-firings", type=int, default=None, help="firings with faults a condition (default 6000)")
    ap.add_argument("--no-throughput", action="store_true", help="skip the throughput and memory measurement")
    ap.add_argument(
        "--work-shape",
        choices=("gas", "sine"),
        default="gas",
        help="each firing's work over its expansion stroke: gas (peaks 32° after TDC, the default, published) or "
        "sine (½·W·sin, peaks 90° after TDC, as published before)",
    )
    ap.add_argument(
        "--throughput-only",
        action="store_true",
        help="measure the throughput and memory alone and put them into the published JSON (a run of its own, "
        "for a quieter moment of a shared machine)",
    )
    args = ap.parse_args()
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
        path.write_text(json.dumps(out, indent=1, allow_nan=False) + "\n")
        print(f"wrote the throughput into {path.relative_to(ROOT)}")
        return
    print(f"cycle-to-cycle variation: CoV {100 * variation['cov']:.2f} % of IMEP ({variation['source']})", flush=True)
    if args.quick:
        grid = {"speeds": [800.0, 4000.0, 6000.0], "loads": ["idle", "full"], "cylinders": [4, 8], "wheels": ["60-2"]}
        clean_cycles, faulty_firings = 1000, 4000
    else:
        grid = {"speeds": list(SPEEDS), "loads": list(LOADS), "cylinders": list(CYLINDERS), "wheels": list(WHEELS)}
        clean_cycles, faulty_firings = 3000, 6000
    if args.speeds:
        grid["speeds"] = [float(x) for x in args.speeds.split(",")]
    if args.loads:
        grid["loads"] = args.loads.split(",")
    if args.cylinders:
        grid["cylinders"] = [int(x) for x in args.cylinders.split(",")]
    if args.wheels:
        grid["wheels"] = args.wheels.split(",")
    clean_cycles = args.clean_cycles or clean_cycles
    faulty_firings = args.faulty_firings or faulty_firings
    rows = []
    seed = 100
    for wheel in grid["wheels"]:
        for n in grid["cylinders"]:
            for rpm in grid["speeds"]:
                for load in grid["loads"]:
                    rows += condition_rows(
                        n, rpm, load, wheel, clean_cycles, max(faulty_firings // n, 200), seed, variation
                    )
                    seed += 2
                    r = rows[-len(DETECTORS) :]
                    print(
                        f"{wheel:6s} {n} cyl {rpm:5.0f} rpm {load:5s}: "
                        + "  ".join(
                            f"{x['detector']} {x['detection_rate']:.3f} ({x['false_alarms_per_1000_cycles']:.1f})"
                            for x in r
                        ),
                        flush=True,
                    )
    summary = compare(rows)
    full = (
        grid["speeds"] == list(SPEEDS)
        and grid["loads"] == list(LOADS)
        and grid["cylinders"] == list(CYLINDERS)
        and grid["wheels"] == list(WHEELS)
    )
    out = {
        "grid": "quick" if args.quick else ("full" if full else "part of the full grid"),
        "grid_run": grid,
        "work_shape": WORK_SHAPE,
        "fault_free_cycles_per_condition": clean_cycles,
        "firings_with_faults_per_condition": faulty_firings,
        "rule": "each detector's threshold: the score of the (floor(cycles/1000)+1)-th most extreme firing of a "
        "separate fault-free run (1 false alarm per 1000 cycles); detection and false alarms on runs with misfires",
        "cycle_to_cycle_variation": {k: v for k, v in variation.items() if k != "z"},
        "misfires": f"events on {EVENT_RATE:.1%} of the firings, {PAIR_SHARE:.0%} of them pairs",
        "rows": rows,
        "summary": summary,
        "conditions": len(summary),
        "rotor_reaches_95": sum(s["rotor_reaches_95"] for s in summary),
        "none_reaches_95": [s["condition"] for s in summary if not s["any_reaches_95"]],
        "baseline_exceeds_rotor_by_more_than_0.02": [
            s
            for s in summary
            if s["baseline_excess_at_no_more_false_alarms"] is not None
            and s["baseline_excess_at_no_more_false_alarms"] > 0.02
        ],
    }
    print(
        f"rotor reaches 95 % at 1/1000 in {out['rotor_reaches_95']} of {len(summary)} conditions; "
        f"no detector does in {len(out['none_reaches_95'])}; a baseline above rotor by > 0.02 at no more "
        f"false alarms in {len(out['baseline_exceeds_rotor_by_more_than_0.02'])}",
        flush=True,
    )
    if not args.no_throughput:
        tp = throughput(variation)
        out["throughput"] = tp
        print_throughput(tp)
    out.update(
        {
            "seconds": time.perf_counter() - t0,
            "rotor": rotor.__version__,
            "numpy": np.__version__,
            "python": platform.python_version(),
            "machine": platform.machine(),
        }
    )
    if args.quick or WORK_SHAPE != "gas":
        RESULTS.mkdir(parents=True, exist_ok=True)
        path = RESULTS / ("misfire_detection_quick.json" if args.quick else f"misfire_detection_{WORK_SHAPE}.json")
    else:
        PUBLISHED.mkdir(parents=True, exist_ok=True)
        path = PUBLISHED / "misfire_detection.json"
        figure(
            rows,
            path.with_suffix(".png"),
            f"misfire detection rate at 1 false alarm per 1000 fault-free cycles ({out['grid']})",
        )
    path.write_text(json.dumps(out, indent=1, allow_nan=False) + "\n")
    print(f"wrote {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
