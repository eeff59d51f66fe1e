"""What the adaptive angle-domain solve (``method="angle"``) spends its time on.

One chunk of ``rotor.simulate(engine, method="angle")`` (4chn15 at its operating point under
the load that balances it, 20 cycles, rtol 1e-9, the chunk's own save points: one per
output step of 1°) solved by diffrax as rotor solves it, and again with one part changed at
a time:

- ``as rotor solves it``: Dopri8 with its stages written out (:mod:`rotor.rungekutta`),
  steps of at most 4°, an event for a stall, the samples saved at the output angles
  (diffrax interpolates its dense output at each);
- ``diffrax's Dopri8``: the same method with diffrax's loop over the stages;
- ``no stall event``;
- ``no save points`` (the end state alone): what saving the samples costs;
- ``neither``;
- ``no largest step`` (``dtmax`` off) and three other step-size controllers (PI with
  diffrax's proportional and integral coefficients as named): whether the steps or the
  rejected steps come down;
- ``rtol 1e-12``: the reference for the end state's error.

For each: the median wall time of ``--repeats`` solves after one that compiles (compile
time kept apart; the cases taken in turn, round after round), the steps taken, accepted and rejected, and the end state's normalised
energy against the reference's. The share of rejected steps shows what the tables'
piecewise-cubic right-hand side (its second derivative jumps at every 0.25° node) costs an
eighth-order error estimate.

    .venv/bin/python benchmarks/angle_solver_parts.py [--repeats 15]   # about 40 s

Writes ``benchmarks/results/angle_solver_parts.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
import warnings
from pathlib import Path

import diffrax as dfx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

sys.path.insert(0, str(Path(__file__).resolve().parent))
from simulator_speed import versions  # noqa: E402

import rotor  # noqa: E402
from rotor.dynamics import adaptive, transient  # noqa: E402
from rotor.fileio import write_text_atomic  # noqa: E402
from rotor.rungekutta import UnrolledDopri8  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


def chunk_arguments(engine):
    """The arguments of the first chunk of a 20-cycle angle run, as rotor passes them."""
    load = rotor.ConstantLoad(rotor.steady_state(engine).load_torque_Nm)
    seen = []
    solve = transient.angle_run

    def record(*args, **kwargs):
        seen.append(args)
        return solve(*args, **kwargs)

    transient.angle_run = record
    try:
        rotor.simulate(engine, cycles=20, method="angle", load=load)
    finally:
        transient.angle_run = solve
    scene, theta0, y0, theta_out, rtol, e_switch, max_steps, _ = seen[0]
    return (scene, theta0, y0, theta_out, rtol, e_switch), max_steps


def variant(max_steps, *, event=True, save=True, dtmax=adaptive.MAX_ANGLE_STEP, p=0.0, i=1.0, rtol=None, looped=False):
    """The angle-domain solve of :func:`rotor.dynamics.adaptive.angle_run` with one part
    changed; returns the end state's normalised energy and the step counts."""

    @jax.jit
    def solve(scene, theta0, y0, theta_out, rtol_run, e_switch):
        E0, t0, z0 = y0
        e_ref, w_ref = E0, jnp.sqrt(2 * E0 / scene.train.mean_inertia)
        tol = rtol_run if rtol is None else rtol
        stall = dfx.Event(lambda t, y, args, **kw: y[0] - e_switch / e_ref, optx.Newton(1e-12, 1e-12), direction=False)
        with adaptive.save_points_checked_on_the_host():
            sol = dfx.diffeqsolve(
                dfx.ODETerm(adaptive.angle_field),
                dfx.Dopri8() if looped else UnrolledDopri8(),
                theta0,
                theta_out[-1],
                None,
                (jnp.ones_like(E0), t0 * w_ref, z0),
                args=(scene, e_ref, w_ref),
                saveat=dfx.SaveAt(ts=theta_out, t1=True) if save else dfx.SaveAt(t1=True),
                stepsize_controller=dfx.PIDController(rtol=tol, atol=tol, pcoeff=p, icoeff=i, dtmax=dtmax),
                event=stall if event else None,
                max_steps=max_steps,
                throw=False,
            )
        stats = sol.stats
        return sol.ys[0][-1], stats["num_steps"], stats["num_accepted_steps"], stats["num_rejected_steps"]

    return solve


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    engine = rotor.load_engine("4chn15")
    arguments, max_steps = chunk_arguments(engine)
    cases = {
        "as rotor solves it": {},
        "diffrax's Dopri8": {"looped": True},
        "no stall event": {"event": False},
        "no save points": {"save": False},
        "neither": {"event": False, "save": False},
        "no largest step": {"dtmax": None},
        "PI 0.4/0.3": {"p": 0.4, "i": 0.3},
        "PI 0.2/0.4": {"p": 0.2, "i": 0.4},
        "I 0.7": {"i": 0.7},
        "rtol 1e-12": {"rtol": 1e-12},
    }
    solves, rows, times = {}, {}, {name: [] for name in cases}
    for name, changes in cases.items():
        solves[name] = variant(max_steps, **changes)
        t0 = time.perf_counter()
        e_end, steps, accepted, rejected = (np.asarray(v).item() for v in solves[name](*arguments))
        rows[name] = {
            "first_call_s": time.perf_counter() - t0,
            "steps": int(steps),
            "accepted": int(accepted),
            "rejected": int(rejected),
            "e_end": float(e_end),
        }
    # the copy of the solve above is rotor's own: its end state equals the kernel's
    _, end, *_ = transient.angle_run(*arguments, max_steps, None)
    own = float(np.asarray(end[1]) / np.asarray(arguments[2][0]))
    assert abs(own - rows["as rotor solves it"]["e_end"]) <= 1e-12, "the benchmark's solve is not rotor's"
    for _ in range(args.repeats):  # the cases in turn, so that the machine's drift is shared
        for name, solve in solves.items():
            t0 = time.perf_counter()
            jax.block_until_ready(solve(*arguments))
            times[name].append(time.perf_counter() - t0)
    for name in cases:
        rows[name]["median_s"] = statistics.median(times[name])
    base = rows["as rotor solves it"]["median_s"]
    reference = rows["rtol 1e-12"]["e_end"]
    print(f"4chn15, 20 cycles, one chunk of method='angle' ({arguments[3].shape[0]} save points), rtol 1e-9:")
    for name, row in rows.items():
        row["relative_time"] = row["median_s"] / base
        row["e_end_error"] = abs(row["e_end"] - reference)
        print(
            f"  {name:20s} {1e3 * row['median_s']:7.1f} ms ({row['relative_time']:.2f}×)  steps {row['steps']:6d} "
            f"(rejected {row['rejected'] / row['steps']:.0%})  end-energy error {row['e_end_error']:.1e}"
        )
    out = {
        "measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "versions": versions(),
        "repeats": args.repeats,
        "save_points": int(arguments[3].shape[0]),
        "rows": rows,
    }
    RESULTS.mkdir(parents=True, exist_ok=True)
    write_text_atomic(RESULTS / "angle_solver_parts.json", json.dumps(out, indent=1))
    print(f"wrote {RESULTS / 'angle_solver_parts.json'}")


if __name__ == "__main__":
    main()
