"""Accuracy figures of the simulator that the README quotes (the tests hold the limits).

    .venv/bin/python benchmarks/simulator_accuracy.py

1. Free coasting (tue-single without gas pressure, 1000 rpm): largest relative change
   of ½·I(θ)·ω² (exact I) per method at default settings.
2. Formulations against scipy DOP853 (rtol 1e-12, exact physics, ``reference.py``):
   largest |ω − ω_ref|/ω_mean over the last of 4 cycles and the relative error of the
   time at its start, for 4chn15 and mwm6 under a propeller load, per method.
3. Steady state of 4chn15: periodicity of the shooting solution, closed vs shooting,
   δ against a run of 300 cycles that settles under a propeller load.
4. jax.grad of the steady-state δ with respect to the crankshaft inertia against a
   central difference.
5. The table grid: the steady-state δ and ω at 0.25°, 0.5° and 1° against 0.125°.
6. The adaptive angle method's error over two cycles for rtol 1e-3 … 1e-13.

Writes ``benchmarks/results/simulator_accuracy.json``.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from reference import scipy_angle_reference

import rotor
from rotor.units import RPM_PER_RAD_S as RPM

OUT = Path(__file__).parent / "results"


def coasting():
    engine = rotor.load_engine("tue-single").replace(pressure=rotor.NoPressure())
    out = {}
    for method, cycles in (("closed", 1000), ("grid", 100), ("angle", 100), ("time", 20)):
        r = rotor.simulate(engine, rpm=1000.0, cycles=cycles, method=method)
        ke = 0.5 * rotor.reduced_inertia(engine, r.theta) * r.omega**2
        out[method] = {
            "cycles": cycles,
            "max_relative_energy_change": float(jnp.max(jnp.abs(ke / ke[0] - 1))),
            "delta": float(r.delta),
        }
    return out


def formulations():
    out = {}
    for preset, load in (("4chn15", rotor.PropellerLoad(1100.0, 1250.0)), ("mwm6", rotor.PropellerLoad(400.0, 2200.0))):
        engine = rotor.load_engine(preset)
        cycles, rpm = 4, 0.95 * float(engine.operating.rpm)
        runs = {
            m: rotor.simulate(engine, rpm=rpm, cycles=cycles, load=load, method=m)
            for m in ("closed", "grid", "angle", "time")
        }
        P = runs["closed"].points_per_cycle
        last = slice((cycles - 1) * P, cycles * P)
        theta = np.asarray(runs["closed"].theta[last])
        w_ref, t_ref = scipy_angle_reference(engine, rpm, cycles, float(load.c), theta)
        out[preset] = {
            m: {
                "omega_error": float(np.max(np.abs(np.asarray(r.omega[last]) - w_ref)) / np.mean(w_ref)),
                "time_error": float(abs(float(r.t[last][0]) - t_ref[0]) / t_ref[0]),
            }
            for m, r in runs.items()
        }
    return out


def steady():
    engine = rotor.load_engine("4chn15")
    closed = rotor.steady_state(engine)
    shoot = rotor.steady_state(engine, method="shooting")
    prop = rotor.PropellerLoad(1100.0, 1250.0)
    ss = rotor.steady_state(engine, load=prop)
    fuel = float(ss.fuel_scale)
    run = rotor.simulate(engine, rpm=1150.0, cycles=300, load=prop, combustion=np.full((300, 4), fuel))
    return {
        "shooting_periodicity_error": float(shoot.periodicity_error),
        "closed_vs_shooting_omega": float(jnp.max(jnp.abs(shoot.omega / closed.omega - 1))),
        "delta_vs_settled_run": float(run.delta_per_cycle[-1] / ss.delta - 1),
        "mean_rpm_of_settled_run": float(run.cycle_mean_omega[-1] * RPM),
    }


def grid_convergence():
    """Relative change of the steady-state δ and ω against a 0.125° table grid."""
    out = {}
    for preset in ("4chn15", "mwm6", "tue-single"):
        engine = rotor.load_engine(preset)
        ref = rotor.steady_state(engine, grid_deg=0.125)
        out[preset] = {}
        for g in (0.25, 0.5, 1.0):
            r = rotor.steady_state(engine, grid_deg=g)
            w_ref = np.asarray(ref.omega)[:: int(round(g / 0.125))]
            out[preset][str(g)] = {
                "delta": float(r.delta / ref.delta - 1),
                "omega": float(np.max(np.abs(np.asarray(r.omega) - w_ref)) / np.mean(w_ref)),
            }
    return out


def rtol_sweep():
    """Error in ω over two cycles of the adaptive angle method against the closed form on a
    0.125° grid (itself 3e-11 from the 0.25° one), per rtol."""
    engine = rotor.load_engine("4chn15")
    load = rotor.PropellerLoad(1100.0, 1250.0)
    ref = rotor.simulate(engine, rpm=1200.0, cycles=2, load=load, method="closed", grid_deg=0.125)
    out = {}
    for rtol in (1e-3, 1e-6, 1e-8, 1e-9, 1e-10, 1e-12, 1e-13):
        r = rotor.simulate(engine, rpm=1200.0, cycles=2, load=load, method="angle", rtol=rtol)
        err = float(jnp.max(jnp.abs(r.omega / ref.omega - 1)))
        out[str(rtol)] = {"omega_error": err, "error_over_rtol": err / rtol, "steps": r.solver_steps}
    return out


def gradient():
    engine = rotor.load_engine("4chn15")

    def f(J):
        return rotor.steady_state(eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, J)).delta

    g = float(jax.grad(f)(10.2))
    fd = float((f(10.2 + 1e-3) - f(10.2 - 1e-3)) / 2e-3)
    return {"grad": g, "central_difference": fd, "relative_difference": g / fd - 1}


def main() -> int:
    results = {
        "coasting": coasting(),
        "formulations": formulations(),
        "steady": steady(),
        "gradient": gradient(),
        "grid_convergence": grid_convergence(),
        "rtol_sweep": rtol_sweep(),
        "versions": {"jax": jax.__version__, "rotor": rotor.__version__},
    }
    OUT.mkdir(exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=OUT, suffix=".json")
    with os.fdopen(fd, "w") as f:
        json.dump(results, f, indent=2)
    os.replace(tmp, OUT / "simulator_accuracy.json")
    print(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
