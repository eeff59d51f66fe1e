"""Work-precision study of rotor's simulator against scipy's solve_ivp and a numba RK4.

Scene, per preset (tue-single, 4chn15, mwm6, v8) and horizon (10, 100, 1000, 10,000
cycles): start at 0.95 × the operating speed under ``PropellerLoad(T, operating rpm)``, T
the engine's mean gas torque (a + c·ω²: the closed form applies). Error ω: max|ω − ω_ref|
/ mean ω_ref at the 1° crank angles of the last cycle (the subset a coarse run saves);
error t: |t − t_ref| / t_ref at the start of the last cycle. Times: medians of 2–7
repeats (one for runs over 10 s; 1–3 with --quick), rotor's and numba's first calls apart
as compile time. Run with ROTOR_COMPILATION_CACHE=off for cold compile times (the
script sets it unless given).

- rotor ``simulate``: ``closed`` (grid_deg 1 … 0.125; also saving every 4° as "rotor closed
  4°", the output density of the numba run at 180 steps per cycle), ``grid`` (RK4, 90 … 2880 steps per
  cycle, step_deg 720/steps below 720), ``angle`` (rtol 1e-3 … 1e-12), ``time`` (rtol
  1e-4 … 1e-10); and ``closed`` at fidelity "series"/"coefficients"/"constant" (shortest horizon):
  their "error" against the variable-inertia reference is MODEL error, not solver error.
- scipy ``solve_ivp`` RK45, DOP853, LSODA (rtol 1e-3 … 1e-12, atol 1e-10), a plain numpy
  right-hand side in the time domain, y = (θ, ω), as a user would write it; timed without
  dense output (the error comes from a dense run, which takes the same steps).
- numba: fixed-step RK4 in the angle domain (energy form dE/dθ = M_gas − c·ω², dt/dθ =
  1/ω), 90 … 2880 steps per cycle, I and M_gas evaluated twice per step.

Physics. scipy and numba share one numpy physics: exact kinematics with pin offset, the
two-mass split, I(θ) = J + Σ(m_rot·R² + m_rec·s′²), and a periodic PCHIP pressure on a
uniform grid: the engine's table for table engines (as rotor, so I and M_gas are asserted
to match rotor's to 1e-9) and, for Wiebe engines, ``engine.pressure`` tabulated once at
0.25° (the gas torque's max difference from rotor's is reported). Each run is measured
against a reference of ITS OWN physics: rotor against ``closed`` at grid_deg 0.0625
(checked against ``angle`` rtol 1e-13 on the same tables up to 1000 cycles, and at the
shortest horizon against scipy DOP853 on rotor's exact physics, benchmarks/reference.py);
scipy and numba against the numba RK4 at 11,520 steps per cycle, aligned with the pressure
nodes (checked against 5,760 steps, and at the shortest horizon against DOP853 rtol 1e-13
on the numpy physics; unsegmented, DOP853 is good to ~1e-9 across the PCHIP nodes). The
two references' difference (the physics difference) is recorded; --quick skips the checks.

A run is skipped, recorded with its predicted time, when the same setting at a shorter
horizon (scaled by the horizon) or a looser one at this horizon predicts more than --cap
seconds (default 60); nothing predicted is reported as measured. scipy runs up to
--scipy-max-cycles (default 1000).

    .venv/bin/python benchmarks/work_precision.py --quick   # 4chn15, tue-single; 10, 100 cycles; < 2 min
    .venv/bin/python benchmarks/work_precision.py           # everything, --cap 60: about 3 hours
    .venv/bin/python benchmarks/work_precision.py --cap 20  # what benchmarks/README.md quotes: about 1.5 h
    .venv/bin/python benchmarks/work_precision.py --presets 4chn15 --horizons 100,1000 --cap 10

Writes benchmarks/results/work_precision.json (work_precision_quick.json with --quick) and
a log-log figure per preset and horizon, <stem>_<preset>_<cycles>.png; prints, at error
ω ≤ 1e-6, the fastest rotor, scipy and numba settings and the ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import jax
import numba
import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator

sys.path.insert(0, str(Path(__file__).parent))
os.environ.setdefault("ROTOR_COMPILATION_CACHE", "off")  # compile times as in a first run
from reference import scipy_angle_reference  # noqa: E402

import rotor  # noqa: E402
from rotor.fileio import atomic_path, write_text_atomic  # noqa: E402
from rotor.units import RAD_S_PER_RPM  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
TARGET = 1e-6
ATOL = 1e-10
REF_SPC = 11520  # numba reference: 1/16°, a divisor of every pressure node spacing
RTOLS = [10.0**-k for k in range(3, 13)]
FULL = {
    "closed": [1.0, 0.5, 0.25, 0.125],
    "grid": [90, 180, 360, 720, 1440, 2880],
    "angle": RTOLS,
    "time": [1e-4, 1e-6, 1e-8, 1e-10],
    "scipy": RTOLS,
    "numba": [90, 180, 360, 720, 1440, 2880],
}
QUICK = {
    "closed": [1.0, 0.25],
    "grid": [720],
    "angle": [1e-8],
    "time": [1e-6],
    "scipy": [1e-4, 1e-6],
    "numba": [180, 720],
}
SCIPY = ("RK45", "DOP853", "LSODA")


# --------------------------------------------------------------------------- numpy / numba physics
class Physics:
    """The equation of motion in plain numpy (see the module doc), and its numba form."""

    def __init__(self, engine):
        g, src = engine.geometry, engine.pressure
        self.cycle = float(engine.cycle_rad)
        self.shift = 2 * np.pi if engine.strokes == 4 else 0.0
        self.tdc = np.deg2rad(np.asarray(engine.tdc_angles_deg, dtype=float))
        self.fire = np.asarray(engine.firing_angles_rad, dtype=float)
        self.R, self.L, self.k = float(g.crank_radius_m), float(g.rod_length_m), float(g.pin_offset_m)
        self.A, self.p_cc = float(g.piston_area_m2), float(src.crankcase_pa)
        self.J = float(engine.crankshaft.inertia_kgm2)
        self.m_rec, self.m_rot = (float(m) for m in engine.masses.two_mass_split(g.rod_length_m))
        C = np.rad2deg(self.cycle)
        if isinstance(src, rotor.PressureTable):
            x, p = np.asarray(src.angle_deg, float), np.asarray(src.pressure_pa, float)
            self.pressure_note = "the engine's pressure table, periodic PCHIP (as rotor)"
        else:
            x = np.arange(0.0, C, 0.25)
            p = np.asarray(src(np.deg2rad(x), g, engine.strokes), float)
            self.pressure_note = "engine.pressure tabulated at 0.25°, periodic PCHIP"
        self.h = x[1] - x[0]
        assert x[0] == 0 and np.allclose(np.diff(x), self.h) and np.isclose(x[-1] + self.h, C), "uniform grid"
        n = x.size
        self.pchip = PchipInterpolator(np.concatenate([x - C, x, x + C]), np.tile(p, 3))
        self.coef = np.ascontiguousarray(self.pchip.c[:, n : 2 * n])  # the middle period's cubics
        self.nb = (
            self.R,
            self.L,
            self.k,
            self.A,
            self.m_rec,
            self.m_rot,
            self.J,
            self.p_cc,
            self.tdc,
            self.fire,
            self.shift,
            C,
            self.h,
            self.coef,
        )

    def terms(self, theta):
        """I(θ), I′(θ), M_gas(θ) at one angle, numpy."""
        R, L, a = self.R, self.L, theta - self.tdc
        sa, ca = np.sin(a), np.cos(a)
        sb = (R * sa - self.k) / L
        cb = np.sqrt(1 - sb * sb)
        ds = R * (sa * cb + ca * sb) / cb
        d2s = R * (ca * cb - sa * sb) / cb + L * (R * ca / (L * cb)) ** 2 / cb
        p = self.pchip(np.rad2deg(np.mod(theta - self.fire + self.shift, self.cycle)))
        return (
            self.J + np.sum(self.m_rot * R * R + self.m_rec * ds * ds),
            2 * self.m_rec * np.dot(ds, d2s),
            self.A * np.dot(p - self.p_cc, ds),
        )


@numba.njit(cache=False)
def nb_terms(theta, P):
    R, L, k, A, m_rec, m_rot, J, p_cc, tdc, fire, shift, C, h, coef = P
    inertia, m_gas = J, 0.0
    for i in range(tdc.size):
        a = theta - tdc[i]
        sa, ca = np.sin(a), np.cos(a)
        sb = (R * sa - k) / L
        cb = np.sqrt(1.0 - sb * sb)
        ds = R * (sa * cb + ca * sb) / cb
        inertia += m_rot * R * R + m_rec * ds * ds
        phi = np.rad2deg((theta - fire[i] + shift) % (2 * np.pi * C / 360.0))
        j = min(int(phi / h), coef.shape[1] - 1)
        x = phi - j * h
        m_gas += (((coef[0, j] * x + coef[1, j]) * x + coef[2, j]) * x + coef[3, j] - p_cc) * A * ds
    return inertia, m_gas


@numba.njit(cache=False)
def nb_rk4(omega0, c, cycles, spc, every, P):
    """Fixed-step RK4 in θ on (E, t); ω and t every ``every`` steps and at the end."""
    h = 2 * np.pi * P[11] / 360.0 / spc
    n = cycles * spc
    omega, t_out = np.empty(n // every + 1), np.empty(n // every + 1)
    i0, m0 = nb_terms(0.0, P)
    E, t = 0.5 * i0 * omega0 * omega0, 0.0
    for s in range(n):
        th = s * h
        if s % every == 0:
            omega[s // every], t_out[s // every] = np.sqrt(2 * E / i0), t
        i1, m1 = nb_terms(th + 0.5 * h, P)
        i2, m2 = nb_terms(th + h, P)
        w = np.sqrt(2 * E / i0)
        k1e, k1t = m0 - c * w * w, 1 / w
        w = np.sqrt(2 * (E + 0.5 * h * k1e) / i1)
        k2e, k2t = m1 - c * w * w, 1 / w
        w = np.sqrt(2 * (E + 0.5 * h * k2e) / i1)
        k3e, k3t = m1 - c * w * w, 1 / w
        w = np.sqrt(2 * (E + h * k3e) / i2)
        k4e, k4t = m2 - c * w * w, 1 / w
        E += h / 6 * (k1e + 2 * k2e + 2 * k3e + k4e)
        t += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t)
        i0, m0 = i2, m2
    omega[-1], t_out[-1] = np.sqrt(2 * E / i0), t
    return omega, t_out


def scipy_time(ph, omega0, c, cycles, method, rtol, dense=False):
    """Time domain, y = (θ, ω), from θ = 0 to θ = cycles·Θ (a terminal event)."""
    end = cycles * ph.cycle

    def f(t, y):
        inertia, dinertia, m_gas = ph.terms(y[0])
        return [y[1], (m_gas - c * y[1] ** 2 - 0.5 * dinertia * y[1] ** 2) / inertia]

    def reached(t, y):
        return y[0] - end

    reached.terminal, reached.direction = True, 1
    sol = solve_ivp(
        f,
        (0.0, 3 * end / omega0),
        [0.0, omega0],
        method=method,
        rtol=rtol,
        atol=ATOL,
        events=reached,
        dense_output=dense,
    )
    if sol.status != 1:
        raise RuntimeError(f"solve_ivp did not reach the end: {sol.message}")
    return sol


def scipy_last_cycle(sol, theta):
    """(θ, t, ω) of a dense time-domain solution at the crank angles ``theta`` (Newton on θ(t))."""
    t = np.interp(theta, sol.y[0], sol.t)
    for _ in range(6):
        th, om = sol.sol(t)
        t = t - (th - theta) / om
    return theta, t, sol.sol(t)[1]


def numpy_dop853(ph, omega0, c, cycles, theta):
    """Confirmation of the numba reference: angle domain, energy form, DOP853 rtol 1e-13."""

    def f(th, y):
        inertia, _, m_gas = ph.terms(th)
        w = np.sqrt(2 * y[0] / inertia)
        return [m_gas - c * w * w, 1 / w]

    e0 = 0.5 * ph.terms(0.0)[0] * omega0**2
    sol = solve_ivp(
        f, (0.0, cycles * ph.cycle), [e0, 0.0], method="DOP853", rtol=1e-13, atol=[1e-13 * e0, 1e-15], t_eval=theta
    )
    return theta, sol.y[1], np.sqrt(2 * sol.y[0] / np.array([ph.terms(x)[0] for x in theta]))


# --------------------------------------------------------------------------- errors and timing
def last_cycle(theta, t, omega, start, step=np.pi / 180):
    """{index of the 1° angle in the last cycle: (t, ω)} for samples on those angles."""
    theta, t, omega = (np.asarray(a, dtype=float) for a in (theta, t, omega))
    k = np.rint((theta - start) / step)
    on = (k >= 0) & (np.abs(theta - start - k * step) < 1e-9 * max(1.0, start))
    return k[on].astype(int), t[on], omega[on]


def error(run, ref):
    k, t, w = run
    kr, tr, wr = ref
    assert np.array_equal(kr, np.arange(kr.size)) and k.size and k[0] == 0, "last cycle incomplete"
    return {
        "omega_rel": float(np.max(np.abs(w - wr[k])) / np.mean(wr)),
        "t_rel": float(abs(t[0] - tr[0]) / tr[0]),
        "points": int(k.size),
    }


def repeats_for(seconds, quick):
    if quick:
        return 3 if seconds < 1 else 1
    return 7 if seconds < 0.2 else 5 if seconds < 1 else 2 if seconds < 10 else 1


def measure(fn, quick, compiled, hint=None):
    """Median wall time of ``fn``; a first call apart (compile) when ``compiled``."""
    out = {}

    def call():
        start = time.perf_counter()
        out["r"] = fn()
        return time.perf_counter() - start

    first = call() if compiled else None
    times = [] if hint else [call()]
    times += [call() for _ in range(repeats_for(hint or times[0], quick) - len(times))]
    med = statistics.median(times)
    res = {"median_s": med, "times_s": times, "repeats": len(times)}
    if compiled:
        res["first_call_s"], res["compile_s"] = first, max(first - med, 0.0)
    return res, out["r"]


# --------------------------------------------------------------------------- one preset, one horizon
class Bench:
    def __init__(self, name, quick, cap, first, scipy_max=1000, families=None):
        self.name, self.quick, self.cap, self.first, self.scipy_max = name, quick, cap, first, scipy_max
        self.families = families
        self.settings = QUICK if quick else FULL
        self.engine = e = rotor.load_engine(name)
        self.rpm, self.torque = float(e.operating.rpm), float(rotor.mean_gas_torque(e))
        self.load = rotor.PropellerLoad(self.torque, self.rpm)
        self.c, self.rpm0, self.ph = float(self.load.c), 0.95 * self.rpm, Physics(e)
        self.omega0 = self.rpm0 * RAD_S_PER_RPM
        self.history = {}  # key → (cycles, median_s) of the last measured run
        start = time.perf_counter()
        self.numba(1, 720)  # compiles nb_rk4 (and nb_terms) on the first preset; later ones reuse it
        self.numba_first_call_s = time.perf_counter() - start
        self.checks = self.check_physics()

    def check_physics(self):
        e, ph = self.engine, self.ph
        th = (np.arange(2000) + 0.37) * ph.cycle / 2000  # off the pressure nodes
        ours = np.array([ph.terms(x) for x in th])
        nb = np.array([nb_terms(x, ph.nb) for x in th])
        d_inertia = np.max(np.abs(ours[:, 0] - np.asarray(rotor.reduced_inertia(e, th)))) / ph.J
        m_ref = np.asarray(rotor.gas_torque(e, th))
        d_gas = np.max(np.abs(ours[:, 2] - m_ref)) / np.max(np.abs(m_ref))
        d_numba = max(
            np.max(np.abs(nb[:, 0] - ours[:, 0])) / ph.J, np.max(np.abs(nb[:, 1] - ours[:, 2])) / np.max(np.abs(m_ref))
        )
        assert d_inertia < 1e-9 and d_numba < 1e-9, (d_inertia, d_numba)
        if isinstance(e.pressure, rotor.PressureTable):
            assert d_gas < 1e-9, d_gas
        return {
            "pressure": ph.pressure_note,
            "inertia_vs_rotor_max_rel": float(d_inertia),
            "gas_torque_vs_rotor_max_rel_to_peak": float(d_gas),
            "numba_vs_numpy_max_rel": float(d_numba),
        }

    def wanted(self, family):
        return self.families is None or any(family.startswith(f) for f in self.families)

    def predict(self, key, cycles, looser):
        """A predicted time over the cap → the reason to skip, else None."""
        guesses = []
        if key in self.history:
            n, s = self.history[key]
            guesses.append((s * cycles / n, f"{s:.3g} s measured at {n} cycles × {cycles}/{n}"))
        slow = looser and (looser.get("median_s") or looser.get("predicted_s") or 0)
        if slow and slow > self.cap:
            guesses.append((slow, "a looser setting at this horizon took (or was predicted to take) as long"))
        over = [g for g in guesses if g[0] > self.cap]
        return {"skipped": True, "predicted_s": over[0][0], "basis": over[0][1]} if over else None

    def runs(self, family, key_fmt, settings, cycles, go):
        """Run ``go(setting)`` → (timing, error) for each setting, loosest first, honouring the cap."""
        out, looser = [], None
        for s in settings:
            key = (family, key_fmt(s))
            row = {"family": family, "setting": key_fmt(s)}
            skip = self.predict(key, cycles, looser)
            if skip:
                row.update(skip)
            else:
                try:
                    row.update(go(s))
                    self.history[key] = (cycles, row["median_s"])
                except Exception as exc:  # a setting that fails is a result too
                    row.update(failed=f"{type(exc).__name__}: {exc}"[:300])
            print(
                f"  {cycles:>6} {family:18s} {row['setting']:>12s}  "
                + (
                    f"{row['median_s']:9.4f} s  ω {row['error']['omega_rel']:.1e}  t {row['error']['t_rel']:.1e}"
                    if "median_s" in row
                    else f"skipped, predicted {row['predicted_s']:.0f} s"
                    if "skipped" in row
                    else row["failed"][:80]
                ),
                flush=True,
            )
            out.append(row)
            looser = row
        return out

    def horizon(self, cycles):
        e, ph, q = self.engine, self.ph, self.quick
        start = (cycles - 1) * ph.cycle
        theta = start + np.deg2rad(np.arange(721.0))
        res = {"cycles": cycles}

        def sim(**kw):
            return rotor.simulate(e, rpm=self.rpm0, cycles=cycles, load=self.load, **kw)

        def rotor_lc(r):
            return last_cycle(r.theta, r.t, r.omega, start)

        # references
        t0 = time.perf_counter()
        ref_r = rotor_lc(sim(method="closed", grid_deg=0.0625))
        ref_n = last_cycle(*self.numba(cycles, REF_SPC), start)
        refs = {
            "rotor": "closed, grid_deg 0.0625",
            "numpy": f"numba RK4, {REF_SPC} steps per cycle",
            "numpy_vs_rotor_reference (physics difference)": error(ref_n, ref_r),
        }
        if cycles <= 1000 and not q:
            refs["rotor_angle_rtol1e-13_same_tables"] = error(
                rotor_lc(sim(method="angle", rtol=1e-13, grid_deg=0.0625)), ref_r
            )
        if not q:
            refs[f"numba_{REF_SPC // 2}_steps"] = error(last_cycle(*self.numba(cycles, REF_SPC // 2), start), ref_n)
        if cycles == self.first and not q:  # the DOP853 cross-checks: slow, short horizon only
            w, t = scipy_angle_reference(e, self.rpm0, cycles, self.c, theta, rtol=1e-12)
            refs["scipy_dop853_exact_physics (benchmarks/reference.py)"] = error(last_cycle(theta, t, w, start), ref_r)
            refs["numpy_dop853_rtol1e-13_angle_domain"] = error(
                last_cycle(*numpy_dop853(ph, self.omega0, self.c, cycles, theta), start), ref_n
            )
        refs["seconds"] = time.perf_counter() - t0
        res["references"] = refs
        print(
            f"  {cycles:>6} references ({refs['seconds']:.1f} s): "
            + ", ".join(f"{k.split(' ')[0]} {v['omega_rel']:.1e}" for k, v in refs.items() if isinstance(v, dict))
        )

        def rotor_go(**kw):
            timing, r = measure(lambda: _block(sim(**kw)), q, compiled=True)
            return dict(timing, error=error(rotor_lc(r), ref_r), method=r.method)

        grid_deg, rtol, spc = (lambda g: f"grid {g:g}°"), (lambda r: f"rtol {r:.0e}"), (lambda n: f"{n}/cycle")
        models = ("series", "coefficients", "constant") if cycles == self.first and not q else ()
        rows = []
        for family, fmt, settings, kw in [
            ("rotor closed", grid_deg, self.settings["closed"], lambda g: dict(method="closed", grid_deg=g)),
            (
                "rotor closed 4°",
                grid_deg,
                self.settings["closed"],
                lambda g: dict(method="closed", grid_deg=g, step_deg=4.0),
            ),
            (
                "rotor grid",
                spc,
                self.settings["grid"],
                lambda n: dict(method="grid", steps_per_cycle=n, step_deg=max(1.0, 720 / n)),
            ),
            ("rotor angle", rtol, self.settings["angle"], lambda r: dict(method="angle", rtol=r)),
            ("rotor time", rtol, self.settings["time"], lambda r: dict(method="time", rtol=r)),
        ] + [
            (f"model {f}", grid_deg, [0.25], lambda g, f=f: dict(method="closed", grid_deg=g, fidelity=f))
            for f in models
        ]:
            if self.wanted(family):
                rows += self.runs(family, fmt, settings, cycles, lambda x, kw=kw: rotor_go(**kw(x)))

        def numba_go(n):
            timing, run = measure(lambda: self.numba(cycles, n), q, compiled=True)
            return dict(timing, error=error(last_cycle(*run, start), ref_n))

        if self.wanted("numba RK4"):
            rows += self.runs("numba RK4", spc, self.settings["numba"], cycles, numba_go)
        for method in [m for m in SCIPY if self.wanted(f"scipy {m}")] if cycles <= self.scipy_max else ():

            def go(rtol, method=method):
                t0 = time.perf_counter()
                sol = scipy_time(ph, self.omega0, self.c, cycles, method, rtol, dense=True)
                dense_s = time.perf_counter() - t0
                timing, sol2 = measure(
                    lambda: scipy_time(ph, self.omega0, self.c, cycles, method, rtol), q, compiled=False, hint=dense_s
                )
                return dict(
                    timing,
                    dense_run_s=dense_s,
                    nfev=int(sol2.nfev),
                    error=error(last_cycle(*scipy_last_cycle(sol, theta), start), ref_n),
                )

            rows += self.runs(f"scipy {method}", rtol, self.settings["scipy"], cycles, go)
        res["runs"] = rows
        res["summary"] = summarize(rows)
        return res

    def numba(self, cycles, spc):
        """(θ, t, ω) of the numba RK4, saved every max(1°, one step)."""
        every = max(1, spc // 720)
        w, t = nb_rk4(self.omega0, self.c, cycles, spc, every, self.ph.nb)
        return self.ph.cycle / spc * every * np.arange(w.size), t, w


def _block(r):
    jax.block_until_ready((r.omega, r.t))
    return r


def summarize(rows):
    """Fastest measured setting per group at error ω ≤ TARGET, and the ratios."""
    groups = {
        "rotor": ("rotor closed", "rotor grid", "rotor angle", "rotor time"),
        "rotor_4deg_samples": ("rotor closed 4°",),
        "scipy": tuple(f"scipy {m}" for m in SCIPY),
        "numba": ("numba RK4",),
    }
    out = {"target_omega_rel": TARGET}
    for g, fams in groups.items():
        ok = [r for r in rows if r["family"] in fams and "median_s" in r and r["error"]["omega_rel"] <= TARGET]
        best = min(ok, key=lambda r: r["median_s"]) if ok else None
        out[g] = None if best is None else {k: best[k] for k in ("family", "setting", "median_s", "error")}
    s, r, n = (out[g] and out[g]["median_s"] for g in ("scipy", "rotor", "numba"))
    r4 = out["rotor_4deg_samples"] and out["rotor_4deg_samples"]["median_s"]
    out["ratio_rotor_4deg_over_numba"] = r4 / n if r4 and n else None
    out["ratio_scipy_over_rotor"] = s / r if s and r else None
    out["ratio_rotor_over_numba"] = r / n if r and n else None
    out["targets (at 1000 cycles)"] = {
        "scipy/rotor >= 30": s and r and s / r >= 30,
        "rotor/numba <= 3": r and n and r / n <= 3,
    }
    compile_s = [x["compile_s"] for x in rows if x["family"].startswith("rotor") and "compile_s" in x] or [0.0]
    out["rotor_compile_s"] = {"min": min(compile_s), "median": statistics.median(compile_s), "max": max(compile_s)}
    return out


# --------------------------------------------------------------------------- output
def versions():
    import diffrax
    import equinox
    import jaxlib

    mods = {m.__name__: m.__version__ for m in (rotor, jax, jaxlib, diffrax, equinox, np, scipy, numba)}
    return dict(
        mods,
        python=platform.python_version(),
        platform=platform.platform(),
        cpu_count=os.cpu_count(),
        jax_backend=jax.default_backend(),
    )


def import_time(repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import rotor"], check=True)
        times.append(time.perf_counter() - start)
    return {"median_s": statistics.median(times), "times_s": times, "note": "python -c 'import rotor', whole process"}


def plot(name, res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    fams = list(dict.fromkeys(r["family"] for r in res["runs"]))
    markers = dict(zip(fams, "os^vDP*XhpH<>"))
    for i, fam in enumerate(fams):
        pts = [
            (max(r["error"]["omega_rel"], 1e-16), r["median_s"])
            for r in res["runs"]
            if r["family"] == fam and "median_s" in r
        ]
        if pts:
            x, y = zip(*pts)
            ls = ":" if fam.startswith("model") else "-"
            ax.plot(x, y, ls, marker=markers[fam], color=f"C{i % 10}", label=fam, ms=5)
    ax.axvline(TARGET, color="grey", lw=0.8, ls="--")
    ax.set(
        xscale="log",
        yscale="log",
        xlabel="error ω: max|ω − ω_ref|/mean ω, last cycle",
        ylabel="median wall time [s]",
        title=f"{name}, {res['cycles']} cycles (each against its own physics)",
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def print_summary(out):
    print(f"\nat error ω ≤ {TARGET:g}; fastest per group (median wall time, after compile)")
    print(f"{'preset':11s} {'cycles':>6s}  {'rotor':32s} {'scipy':32s} {'numba':28s} scipy/rotor rotor/numba")
    for name, p in out["presets"].items():
        for n, res in p["horizons"].items():
            s = res["summary"]
            cell = lambda b: f"{b['family'].split()[-1]} {b['setting']} {b['median_s']:.3g}s" if b else "none"  # noqa
            ratio = lambda v: f"{v:11.1f}" if v else f"{'—':>11s}"  # noqa
            print(
                f"{name:11s} {n:>6s}  {cell(s['rotor']):32s} {cell(s['scipy']):32s} {cell(s['numba']):28s}"
                f"{ratio(s['ratio_scipy_over_rotor'])} {ratio(s['ratio_rotor_over_numba'])} "
                f"{ratio(s.get('ratio_rotor_4deg_over_numba'))} (4° samples)   rotor compile "
                f"{s['rotor_compile_s']['min']:.1f}–{s['rotor_compile_s']['max']:.1f} s"
            )
    print(f"import rotor {out['import_rotor']['median_s']:.2f} s; numba compile {out['numba_compile_s']:.2f} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="4chn15 and tue-single, 10 and 100 cycles, few settings")
    ap.add_argument("--presets", help="comma-separated presets (default: all four)")
    ap.add_argument("--horizons", help="comma-separated cycle counts (default 10,100,1000,10000)")
    ap.add_argument("--cap", type=float, default=60.0, help="skip runs predicted to take longer [s]")
    ap.add_argument(
        "--families", help="comma-separated family prefixes to run (default all), e.g. 'rotor closed,numba'"
    )
    ap.add_argument("--stem", help="output name in benchmarks/results (default work_precision[_quick])")
    ap.add_argument(
        "--scipy-max-cycles",
        type=int,
        default=1000,
        help="longest horizon scipy runs at (default 1000: beyond, its runs are minutes long)",
    )
    args = ap.parse_args()
    presets = (args.presets or ("4chn15,tue-single" if args.quick else "tue-single,4chn15,mwm6,v8")).split(",")
    horizons = sorted(int(h) for h in (args.horizons or ("10,100" if args.quick else "10,100,1000,10000")).split(","))
    stem = args.stem or ("work_precision_quick" if args.quick else "work_precision")
    RESULTS.mkdir(parents=True, exist_ok=True)
    wall = time.perf_counter()
    notes = __doc__.split("\n\n", 1)[1].rsplit("\n\n", 2)[0]
    out = {
        "quick": args.quick,
        "cap_s": args.cap,
        "scipy_max_cycles": args.scipy_max_cycles,
        "versions": versions(),
        "import_rotor": import_time(1 if args.quick else 3),
        "notes": notes,
        "presets": {},
    }
    print(f"import rotor: {out['import_rotor']['median_s']:.2f} s")
    for name in presets:
        b = Bench(
            name,
            args.quick,
            args.cap,
            horizons[0],
            args.scipy_max_cycles,
            args.families.split(",") if args.families else None,
        )
        load = f"PropellerLoad({b.torque:.6g} N·m, {b.rpm:g} rpm), c = {b.c:.6g} N·m·s²"
        p = out["presets"][name] = {
            "rpm_operating": b.rpm,
            "rpm_start": b.rpm0,
            "load": load,
            "physics": b.checks,
            "horizons": {},
        }
        out.setdefault("numba_compile_s", b.numba_first_call_s)  # nb_rk4's first call, one cycle
        p["numba_first_call_s"] = b.numba_first_call_s
        print(f"\n{name}: {p['load']}; numpy physics: {b.checks}; numba first call {b.numba_first_call_s:.2f} s")
        for n in horizons:
            p["horizons"][str(n)] = res = b.horizon(n)
            plot(name, res, RESULTS / f"{stem}_{name}_{n}.png")
            out["elapsed_s"] = time.perf_counter() - wall
            write_text_atomic(RESULTS / f"{stem}.json", json.dumps(out, indent=1, ensure_ascii=False))
    print_summary(out)
    print(f"\nwrote {RESULTS / (stem + '.json')} and its figures in {time.perf_counter() - wall:.0f} s")


if __name__ == "__main__":
    main()
