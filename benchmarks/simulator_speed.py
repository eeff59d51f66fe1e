"""Speed of rotor's simulator against scipy's solve_ivp on the same engine (4chn15).

Measures, does not assert:

1. ``rotor.steady_state`` (1250 rpm, after compile) against ONE cycle (4π) of
   ``solve_ivp(method="RK45", rtol=1e-8)`` with a plain numpy right-hand side, started at
   rotor's steady-state speed and loaded with its balancing torque.
2. A transient of 100 cycles under ``PropellerLoad(1100 N·m, 1250 rpm)`` from 1250 rpm:
   ``rotor.simulate`` (method "closed", picked by "auto"; "grid", fixed-step RK4 at two
   steps per degree, what "auto" picks for loads outside the closed form; and "angle" at
   its default rtol) against ``solve_ivp(method="LSODA")`` at the rtol whose error is about rotor's.
   Error: max |ω(θ) − ω_ref(θ)|/ω_mean over the last cycle at rotor's 1° crank angles,
   and the error of the time at the last of them.

The numpy right-hand side is what a user would write: time domain, θ' = ω,
ω' = (M_gas(θ) − M_load(ω) − ½·I'(θ)·ω²)/I(θ), exact piston kinematics, the pressure
table by ``np.interp(..., period=720)``. Rotor interpolates the table by periodic PCHIP,
so each run is compared with a reference of its own physics:

- scipy: DOP853 (rtol 1e-13) in the angle domain, restarted at every table node, where
  np.interp's kinks are (a plain time-domain DOP853 at rtol 1e-12 is only good to ~1e-8
  here, so it is reported as a cross-check, not used);
- rotor: its solver error against ``method="angle", rtol=1e-14``, and its total error
  (0.25° tables included) against the same segmented DOP853 with the pressure by
  periodic PCHIP (scipy's PchipInterpolator on the table repeated over three periods).

Times are medians of repeats (time.perf_counter); rotor's first call is reported apart
as compile time; scipy is timed without dense output (its error comes from a dense run,
which takes the same steps). Writes benchmarks/results/simulator_speed.json and .png.

    .venv/bin/python benchmarks/simulator_speed.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator

import rotor
from rotor.fileio import atomic_path, write_text_atomic
from rotor.units import RAD_S_PER_RPM

RESULTS = Path(__file__).resolve().parent / "results"
RPM = 1250.0
PROPELLER = (1100.0, 1250.0)  # torque [N·m] at rpm
LSODA_RTOLS = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13)
ATOL = 1e-10


# --------------------------------------------------------------------------- numpy physics
class NumpyEngine:
    """The engine's equation of motion in plain numpy, from the engine's own numbers."""

    def __init__(self, engine, pressure="linear"):
        g = engine.geometry
        self.R, self.L = float(g.crank_radius_m), float(g.rod_length_m)
        self.A = float(g.piston_area_m2)
        self.m = float(engine.masses.reciprocating_kg)
        self.J = float(engine.crankshaft.inertia_kgm2)
        self.tdc = np.deg2rad(np.asarray(engine.tdc_angles_deg, dtype=float))
        self.fire = np.asarray(engine.firing_angles_rad, dtype=float)
        self.cycle = 4 * np.pi
        self.p_deg = np.asarray(engine.pressure.angle_deg, dtype=float)
        self.p_pa = np.asarray(engine.pressure.pressure_pa, dtype=float)
        self.p_cc = float(engine.pressure.crankcase_pa)
        if pressure == "linear":
            self.pressure = lambda deg: np.interp(deg, self.p_deg, self.p_pa, period=720.0)
        else:  # periodic PCHIP, as rotor: interior slopes only, over three periods
            self.pressure = PchipInterpolator(
                np.concatenate([self.p_deg - 720, self.p_deg, self.p_deg + 720]), np.tile(self.p_pa, 3)
            )

    def terms(self, theta):
        """I(θ), I'(θ) and the gas torque M_gas(θ)."""
        R, L = self.R, self.L
        a = theta - self.tdc
        sa, ca = np.sin(a), np.cos(a)
        q = np.sqrt(L * L - R * R * sa * sa)
        ds = R * sa + R * R * sa * ca / q
        d2s = R * ca + R * R * (ca * ca - sa * sa) / q + R**4 * (sa * ca) ** 2 / q**3
        p = self.pressure(np.rad2deg(np.mod(theta - self.fire + 2 * np.pi, self.cycle)))
        return self.J + self.m * np.dot(ds, ds), 2 * self.m * np.dot(ds, d2s), self.A * np.dot(p - self.p_cc, ds)

    def run(self, omega0, load, cycles, method, rtol, dense=False):
        """Time domain, y = (θ, ω), from θ = 0 until θ = cycles·4π (a terminal event)."""
        end = cycles * self.cycle

        def f(t, y):
            theta, omega = y
            inertia, dinertia, m_gas = self.terms(theta)
            return [omega, (m_gas - load(omega) - 0.5 * dinertia * omega * omega) / inertia]

        def reached(t, y):
            return y[0] - end

        reached.terminal, reached.direction = True, 1
        return solve_ivp(
            f,
            (0.0, 3.0 * end / omega0),
            [0.0, omega0],
            method=method,
            rtol=rtol,
            atol=ATOL,
            events=reached,
            dense_output=dense,
        )

    def reference(self, omega0, load, cycles, theta_out):
        """(t, ω) at the sorted angles ``theta_out``: angle domain, y = (ω, t), DOP853 at
        rtol 1e-13 restarted at every table node (where the pressure has kinks)."""

        def f(theta, y):
            inertia, dinertia, m_gas = self.terms(theta)
            return [(m_gas - load(y[0]) - 0.5 * dinertia * y[0] ** 2) / (inertia * y[0]), 1.0 / y[0]]

        nodes = np.unique(np.mod(np.deg2rad(self.p_deg)[:, None] + self.fire - 2 * np.pi, self.cycle).round(12))
        end = max(cycles * self.cycle, theta_out[-1])
        breaks = (nodes[None, :] + self.cycle * np.arange(cycles)[:, None]).ravel()
        breaks = np.append(breaks[(breaks > 0) & (breaks < end)], end)
        a, y, out = 0.0, np.array([omega0, 0.0]), []
        for b in breaks:  # [a, b); the last piece [a, end]
            at = theta_out[(theta_out >= a) & ((theta_out < b) | (b == end))]
            t_eval = at if at.size and at[-1] == b else np.append(at, b)
            sol = solve_ivp(f, (a, b), y, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t_eval)
            out.append(sol.y[:, : at.size])
            a, y = b, sol.y[:, -1]
        omega, t = np.concatenate(out, axis=1)
        return t, omega


def at_angles(sol, theta):
    """(t, ω) of a dense time-domain solution at the crank angles ``theta`` (Newton on θ(t))."""
    t = np.interp(theta, sol.sol(sol.sol.ts)[0], sol.sol.ts)
    for _ in range(6):
        th, om = sol.sol(t)
        t = t - (th - theta) / om
    return t, sol.sol(t)[1]


def last(r):
    """(t, ω) of a rotor result over its last cycle."""
    return np.asarray(r.t[-r.points_per_cycle :]), np.asarray(r.omega[-r.points_per_cycle :])


def errors(t, omega, t_ref, omega_ref):
    """Max |ω − ω_ref|/ω_mean over the samples, and |t − t_ref| at the last one [s]."""
    return {
        "omega_rel": float(np.max(np.abs(omega - omega_ref)) / np.mean(omega_ref)),
        "t_end_s": float(abs(t[-1] - t_ref[-1])),
    }


# --------------------------------------------------------------------------- timing
def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return {"median_s": statistics.median(times), "times_s": times}


def timed_rotor(fn, repeats):
    """Rotor's first call apart (compile), then the median of ``repeats``; and the result."""
    out = {}

    def call():
        out["r"] = fn()
        float(out["r"].delta)  # blocks on JAX

    start = time.perf_counter()
    call()
    return dict(compile_s=time.perf_counter() - start, **median_time(call, repeats)), out["r"]


# --------------------------------------------------------------------------- benchmarks
def bench_steady(engine, ne, repeats):
    rot, ss = timed_rotor(lambda: rotor.steady_state(engine), repeats)
    omega0, m_load = float(ss.omega[0]), float(ss.load_torque_Nm)
    sol = ne.run(omega0, lambda w: m_load, 1, "RK45", 1e-8)
    sp = median_time(lambda: ne.run(omega0, lambda w: m_load, 1, "RK45", 1e-8), repeats)
    sp.update(rtol=1e-8, atol=ATOL, nfev=int(sol.nfev), omega_end_over_start=float(sol.y[1, -1] / omega0))

    # where the steady state's time goes: the tables alone, and the whole at a 1° grid
    def tables():
        rotor.crank_train(engine).values.block_until_ready()

    tables()
    coarse, _ = timed_rotor(lambda: rotor.steady_state(engine, grid_deg=1.0), repeats)
    return {
        "rotor_steady_state": rot,
        "scipy_rk45_one_cycle": sp,
        "omega0_rad_s": omega0,
        "load_torque_Nm": m_load,
        "ratio_scipy_over_rotor": sp["median_s"] / rot["median_s"],
        "rotor_tables_only": median_time(tables, repeats),
        "rotor_steady_state_grid_1deg": coarse,
        "ratio_scipy_over_rotor_grid_1deg": sp["median_s"] / coarse["median_s"],
    }


def bench_transient(engine, cycles, repeats, scipy_repeats):
    load = rotor.PropellerLoad(*PROPELLER)
    w0, w_rated = RPM * RAD_S_PER_RPM, PROPELLER[1] * RAD_S_PER_RPM

    def user_load(w):
        return PROPELLER[0] * (w / w_rated) ** 2

    def sim(**kw):
        return rotor.simulate(engine, rpm=RPM, cycles=cycles, load=load, **kw)

    res = {"cycles": cycles, "rpm": RPM, "load": f"PropellerLoad({PROPELLER[0]:g} N·m, {PROPELLER[1]:g} rpm)"}
    runs = {}
    for name, kw in (
        ("closed", {"method": "auto"}),
        ("grid", {"method": "grid"}),
        ("angle", {"method": "angle", "rtol": 1e-10}),
    ):
        res[f"rotor_{name}"], runs[name] = timed_rotor(lambda kw=kw: sim(**kw), repeats)
        res[f"rotor_{name}"]["method"] = runs[name].method
    theta = np.asarray(runs["closed"].theta[-runs["closed"].points_per_cycle :])
    rotor_ref = last(sim(method="angle", rtol=1e-14))
    exact_lin = NumpyEngine(engine, "linear").reference(w0, user_load, cycles, theta)
    exact_pchip = NumpyEngine(engine, "pchip").reference(w0, user_load, cycles, theta)
    for name, r in runs.items():
        assert np.allclose(np.asarray(r.theta[-r.points_per_cycle :]), theta)
        res[f"rotor_{name}"]["error_solver"] = errors(*last(r), *rotor_ref)
        res[f"rotor_{name}"]["error"] = errors(*last(r), *exact_pchip)
    res["cross_checks"] = {
        "rotor_angle_rtol1e-14_vs_numpy_pchip_reference": errors(*rotor_ref, *exact_pchip),
        "numpy_pchip_vs_numpy_linear_reference": errors(*exact_pchip, *exact_lin),
    }
    ne = NumpyEngine(engine, "linear")
    start = time.perf_counter()
    dop = ne.run(w0, user_load, cycles, "DOP853", 1e-12, dense=True)
    res["cross_checks"]["scipy_dop853_rtol1e-12_time_domain_vs_reference"] = dict(
        errors(*at_angles(dop, theta), *exact_lin), wall_s=time.perf_counter() - start
    )
    ladder = []
    for rtol in LSODA_RTOLS:
        start = time.perf_counter()
        sol = ne.run(w0, user_load, cycles, "LSODA", rtol, dense=True)
        ladder.append(
            {
                "rtol": rtol,
                "wall_s_dense": time.perf_counter() - start,
                "nfev": int(sol.nfev),
                "error": errors(*at_angles(sol, theta), *exact_lin),
            }
        )
    res["lsoda_ladder"] = ladder
    res["lsoda_pick"] = "the loosest rtol whose error ω <= rotor's (total) error ω, else the most accurate one"
    timed = {}
    for name in runs:
        target = res[f"rotor_{name}"]["error"]["omega_rel"]
        good = [x for x in ladder if x["error"]["omega_rel"] <= target]
        pick = good[0] if good else min(ladder, key=lambda x: x["error"]["omega_rel"])
        if pick["rtol"] not in timed:
            timed[pick["rtol"]] = median_time(
                lambda: ne.run(w0, user_load, cycles, "LSODA", pick["rtol"]), scipy_repeats
            )
        res[f"lsoda_vs_{name}"] = dict(pick, **timed[pick["rtol"]], atol=ATOL, meets_rotor_error=bool(good))
        res[f"ratio_lsoda_over_rotor_{name}"] = timed[pick["rtol"]]["median_s"] / res[f"rotor_{name}"]["median_s"]
    return res


# --------------------------------------------------------------------------- output
def versions():
    import diffrax
    import equinox
    import jax
    import jaxlib

    mods = {m.__name__: m.__version__ for m in (rotor, jax, jaxlib, diffrax, equinox, np, scipy)}
    return dict(
        mods,
        python=platform.python_version(),
        platform=platform.platform(),
        cpu_count=os.cpu_count(),
        jax_backend=jax.default_backend(),
    )


def fmt_s(v):
    return f"{v:.3g} s" if v >= 1 else f"{v * 1e3:.3g} ms"


def plot(res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s, tr = res["steady_state"], res["transient"]
    n = tr["cycles"]
    bars = [
        ("rotor\nsteady_state", s["rotor_steady_state"], "C0"),
        ("scipy RK45\none cycle", s["scipy_rk45_one_cycle"], "C1"),
        (f"rotor closed\n{n} cycles", tr["rotor_closed"], "C0"),
        (f"scipy LSODA\nrtol {tr['lsoda_vs_closed']['rtol']:g}", tr["lsoda_vs_closed"], "C1"),
        (f"rotor grid\n{n} cycles", tr["rotor_grid"], "C0"),
        (f"scipy LSODA\nrtol {tr['lsoda_vs_grid']['rtol']:g}", tr["lsoda_vs_grid"], "C1"),
        (f"rotor angle\n{n} cycles", tr["rotor_angle"], "C0"),
        (f"scipy LSODA\nrtol {tr['lsoda_vs_angle']['rtol']:g}", tr["lsoda_vs_angle"], "C1"),
    ]
    fig, ax = plt.subplots(figsize=(11, 4.5))
    x = np.arange(len(bars))
    ax.bar(x, [b[1]["median_s"] for b in bars], color=[b[2] for b in bars])
    for xi, (_, b, _) in zip(x, bars):
        ax.text(xi, b["median_s"] * 1.15, fmt_s(b["median_s"]), ha="center", fontsize=9)
    ax.set_xticks(x, [b[0] for b in bars], fontsize=9)
    ax.set_yscale("log")
    times = [b[1]["median_s"] for b in bars]
    ax.set_ylim(min(times) / 3, max(times) * 3)
    ax.set_ylabel("median wall time [s]")
    ax.set_title("4chn15, 1250 rpm: rotor (after compile) vs scipy solve_ivp with a numpy RHS")
    for xv in (1.5, 3.5, 5.5):
        ax.axvline(xv, color="grey", lw=0.8)
    fig.tight_layout()
    with atomic_path(path) as tmp:  # a temporary file beside path, then os.replace
        fig.savefig(tmp, dpi=120)
    plt.close(fig)


def report(res):
    s, tr, v = res["steady_state"], res["transient"], res["versions"]
    ms = lambda d: f"{d['median_s'] * 1e3:10.2f} ms"  # noqa: E731
    print(f"\n4chn15, {RPM:g} rpm; {v['cpu_count']} CPUs, jax {v['jax']}, diffrax {v['diffrax']}, scipy {v['scipy']}")
    print("\n1. steady state vs ONE cycle of scipy RK45 (rtol 1e-8)")
    rot, sp = s["rotor_steady_state"], s["scipy_rk45_one_cycle"]
    print(f"   rotor.steady_state     {ms(rot)}   (compile {rot['compile_s']:.1f} s)")
    print(f"   scipy RK45, one cycle  {ms(sp)}   ({sp['nfev']} RHS calls)")
    print(f"   ratio scipy/rotor      {s['ratio_scipy_over_rotor']:10.1f} x    (target >= 100)")
    print(f"   of which the tables    {ms(s['rotor_tables_only'])}")
    print(
        f"   steady state at 1° grid{ms(s['rotor_steady_state_grid_1deg'])}   ratio "
        f"{s['ratio_scipy_over_rotor_grid_1deg']:.1f} x"
    )
    print(
        f"\n2. {tr['cycles']}-cycle transient from {RPM:g} rpm, {tr['load']}; error ω: max|ω−ω_ref|/ω_mean, "
        "last cycle; t: at its end"
    )
    print("   run                         median time   error ω   error t [s]  (rotor solver-only ω error)")
    for name, r in (
        ("rotor closed (auto)", tr["rotor_closed"]),
        ("rotor grid (RK4, 0.5°)", tr["rotor_grid"]),
        ("rotor angle (rtol 1e-10)", tr["rotor_angle"]),
        (f"LSODA rtol {tr['lsoda_vs_closed']['rtol']:g}", tr["lsoda_vs_closed"]),
        (f"LSODA rtol {tr['lsoda_vs_grid']['rtol']:g}", tr["lsoda_vs_grid"]),
        (f"LSODA rtol {tr['lsoda_vs_angle']['rtol']:g}", tr["lsoda_vs_angle"]),
    ):
        extra = f"  ({r['error_solver']['omega_rel']:.1e})" if "error_solver" in r else ""
        print(f"   {name:27s} {ms(r)}   {r['error']['omega_rel']:.1e}   {r['error']['t_end_s']:.1e}{extra}")
    for name in ("closed", "grid", "angle"):
        pick = tr[f"lsoda_vs_{name}"]
        note = "" if pick["meets_rotor_error"] else "  (no rtol tried reaches rotor's error; the most accurate shown)"
        print(f"   ratio LSODA/rotor {name:6s}  {tr[f'ratio_lsoda_over_rotor_{name}']:10.1f} x{note}")
    print(
        "   (target >= 30)  LSODA ladder, rtol: error ω = "
        + ", ".join(f"{x['rtol']:g}: {x['error']['omega_rel']:.1e}" for x in tr["lsoda_ladder"])
    )
    c = tr["cross_checks"]
    print("   errors against segmented DOP853 of each run's own physics (np.interp for scipy, PCHIP for rotor)")
    for key, what in (
        ("rotor_angle_rtol1e-14_vs_numpy_pchip_reference", "rotor rtol 1e-14 vs numpy PCHIP ref"),
        ("scipy_dop853_rtol1e-12_time_domain_vs_reference", "plain DOP853 rtol 1e-12 vs ref"),
        ("numpy_pchip_vs_numpy_linear_reference", "PCHIP vs np.interp physics"),
    ):
        print(f"   cross-check {what:36s} ω {c[key]['omega_rel']:.1e}, t {c[key]['t_end_s']:.1e} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats, 20 cycles (under a minute)")
    args = ap.parse_args()
    repeats, scipy_repeats, cycles = (3, 1, 20) if args.quick else (7, 3, 100)
    engine = rotor.load_engine("4chn15")
    res = {
        "quick": args.quick,
        "engine": "4chn15",
        "versions": versions(),
        "notes": __doc__.split("\n\n", 1)[1].rsplit("\n\n", 1)[0],
    }
    res["steady_state"] = bench_steady(engine, NumpyEngine(engine), repeats)
    res["transient"] = bench_transient(engine, cycles, repeats, scipy_repeats)
    RESULTS.mkdir(parents=True, exist_ok=True)
    write_text_atomic(RESULTS / "simulator_speed.json", json.dumps(res, indent=2, ensure_ascii=False))
    plot(res, RESULTS / "simulator_speed.png")
    report(res)
    print(f"\nwrote {RESULTS / 'simulator_speed.json'} and {RESULTS / 'simulator_speed.png'}")


if __name__ == "__main__":
    main()
