"""Flywheel design: the textbook rule, the inertia found by Newton through the steady state
(checked by a bisection with another steady-state method and by a time-domain run), the
lightest disc (checked by a general constrained optimiser) and the command line."""

import json
import math
import re

import numpy as np
import pytest

import rotor
from rotor.design.flywheel import OperatingPoint, with_crankshaft_inertia
from rotor.units import rad_s_to_rpm, rpm_to_rad_s


@pytest.fixture(scope="module")
def six():
    return rotor.load_engine("mwm6")


def _bisect(engine, point, delta, lo, hi, rel=1e-6):
    """[crankshaft] inertia with δ = delta at one point by a bracketing root finder on
    log δ(log J) (Brent's: bisection, sped up by secant steps where they stay inside the
    bracket; to ``rel`` in J), δ from the shooting method (RK4 cycle map + Newton), not the
    closed form or the Newton iteration the design uses."""
    from functools import cache

    from scipy.optimize import brentq

    @cache
    def log_ratio(u):  # log(δ(J)/delta) at J = exp(u): falls through 0 at the root
        d = rotor.steady_state(
            with_crankshaft_inertia(engine, math.exp(u)),
            point.rpm,
            point.load,
            imep_scale=point.imep_scale,
            method="shooting",
        ).delta
        return math.log(float(d) / delta)

    a, b = math.log(lo), math.log(hi)
    assert log_ratio(a) > 0 > log_ratio(b), "the bracket must hold the root"
    return math.exp(brentq(log_ratio, a, b, xtol=rel, rtol=1e-12))


def test_textbook_formulas(diesel):
    tb = rotor.textbook_flywheel(diesel, 0.01, 1250)
    omega = rpm_to_rad_s(1250)
    # the excess work of the textbook total torque, computed independently by engine_summary
    assert tb.excess_work_J == pytest.approx(rotor.engine_summary(diesel, 1250).excess_work_J, rel=2e-3)
    assert tb.total_inertia_kgm2 == pytest.approx(tb.excess_work_J / (0.01 * omega**2), rel=1e-12)
    assert tb.flywheel_kgm2 == pytest.approx(0.85 * tb.total_inertia_kgm2, rel=1e-12)
    assert tb.mean_diameter_m == pytest.approx(2.5 * 0.205)
    assert tb.mass_kg == pytest.approx(4 * tb.flywheel_kgm2 / tb.mean_diameter_m**2, rel=1e-12)
    # J₀ less the pistons' mean inertia, 4·m·R²·(½ + λ²/8) to O(λ⁴) (two-mass, no rotating mass)
    R, lam = 0.1025, 0.1025 / 0.3839
    assert tb.total_inertia_kgm2 - tb.crankshaft_inertia_kgm2 == pytest.approx(
        4 * 9.72 * R**2 * (0.5 + lam**2 / 8), rel=2e-3
    )


@pytest.mark.parametrize(
    "preset, points",
    [
        ("4chn15", [OperatingPoint(600, 0.25), OperatingPoint(900, 0.6), 1250]),
        ("mwm6", [1000, 1600, 2200]),
    ],
)
def test_design_meets_target_and_agrees_with_bisection(preset, points):
    engine = rotor.load_engine(preset)
    target = 0.01
    design = rotor.design_flywheel(engine, target, points)
    J = design.crankshaft_inertia_kgm2
    # every point within the target, the binding one on it
    assert all(p.delta <= target * (1 + 1e-6) for p in design.points)
    assert design.delta_achieved == pytest.approx(target, rel=1e-6)
    assert J == max(p.inertia_kgm2 for p in design.points)
    binding = next(
        p for p in points if (p if isinstance(p, OperatingPoint) else OperatingPoint(p)).rpm == design.binding_rpm
    )
    binding = binding if isinstance(binding, OperatingPoint) else OperatingPoint(binding)
    # δ at the design by another method (shooting on the RK4 cycle map) and in the time domain
    r = rotor.steady_state(
        with_crankshaft_inertia(engine, J), binding.rpm, imep_scale=binding.imep_scale, method="shooting"
    )
    assert float(r.delta) == pytest.approx(target, rel=1e-3)
    run = rotor.simulate(
        with_crankshaft_inertia(engine, J),
        rpm=rad_s_to_rpm(float(r.omega[0])),
        cycles=2,
        method="time",
        load=rotor.ConstantLoad(float(r.load_torque_Nm)),
        combustion=np.full((2, engine.cylinders), binding.imep_scale),
        progress=False,
    )
    assert float(run.delta_per_cycle[-1]) == pytest.approx(target, rel=1e-3)
    # the inertia agrees with a bisection on the simulator (the issue asks 1 %; it is far closer)
    J_bis = _bisect(engine, binding, target, 0.5 * J, 2 * J)
    assert J == pytest.approx(J_bis, rel=1e-3)


def test_design_scales_as_one_over_delta(diesel):
    """δ ∝ 1/(J + mechanism) to first order: halving δ doubles the total inertia."""
    a = rotor.design_flywheel(diesel, 0.01)
    b = rotor.design_flywheel(diesel, 0.005)
    mech = a.textbook.total_inertia_kgm2 - a.textbook.crankshaft_inertia_kgm2
    ratio = (b.crankshaft_inertia_kgm2 + mech) / (a.crankshaft_inertia_kgm2 + mech)
    assert ratio == pytest.approx(2.0, rel=5e-3)
    assert b.crankshaft_inertia_kgm2 > a.crankshaft_inertia_kgm2


def test_textbook_close_at_small_delta_and_worse_at_large(diesel):
    """J₀ = L/(δω²) is the first-order theory: within 1 % at δ = 0.5 %, several % off at 10 %."""
    small = rotor.design_flywheel(diesel, 0.005).textbook_ratio
    large = rotor.design_flywheel(diesel, 0.1).textbook_ratio
    assert abs(small - 1) < 0.01
    assert abs(large - 1) > 2 * abs(small - 1)


def test_lightest_disc_matches_a_general_optimiser():
    from scipy.optimize import minimize

    J, rho, bore, peak, vmax, bmax = 1.0, 7200.0, 0.05, 2300.0, 40.0, 0.15
    disc = rotor.lightest_disc(
        J,
        peak_rpm=peak,
        density_kg_m3=rho,
        bore_m=bore,
        max_rim_speed_m_s=vmax,
        max_width_m=bmax,
        max_outer_diameter_m=0.5,
    )
    assert disc.limited_by == "rim speed"
    assert disc.rim_speed_m_s == pytest.approx(vmax)
    assert disc.inertia_kgm2 == pytest.approx(rho * math.pi * disc.width_m * (disc.outer_diameter_m**4 - bore**4) / 32)
    omega = rpm_to_rad_s(peak)

    def mass(x):
        D, b = x
        return rho * math.pi * b * (D**2 - bore**2) / 4

    cons = [
        {"type": "eq", "fun": lambda x: rho * math.pi * x[1] * (x[0] ** 4 - bore**4) / 32 / J - 1},
        {"type": "ineq", "fun": lambda x: vmax - omega * x[0] / 2},
        {"type": "ineq", "fun": lambda x: 0.5 - x[0]},
        {"type": "ineq", "fun": lambda x: bmax - x[1]},
    ]
    best = minimize(
        mass,
        [0.25, 0.1],
        constraints=cons,
        method="SLSQP",
        bounds=[(0.06, 1.0), (1e-3, 1.0)],
        options={"ftol": 1e-12, "maxiter": 500},
    )
    assert best.success
    assert disc.mass_kg == pytest.approx(best.fun, rel=1e-5)
    assert disc.outer_diameter_m == pytest.approx(best.x[0], rel=1e-4)


def test_lightest_disc_errors():
    with pytest.raises(rotor.EngineError, match="needs a width of"):
        rotor.lightest_disc(50.0, peak_rpm=1250, max_outer_diameter_m=0.5, max_width_m=0.1)
    with pytest.raises(rotor.EngineError, match="max_outer_diameter_m or max_rim_speed_m_s"):
        rotor.lightest_disc(1.0, peak_rpm=1250)
    with pytest.raises(rotor.EngineError, match="must be positive"):
        rotor.lightest_disc(-1.0, peak_rpm=1250, max_outer_diameter_m=0.5)


def test_a_disc_no_limit_allows_is_refused_with_what_would_do(diesel):
    """A design whose disc would break its own limit is refused: the message names the limit,
    the outer diameter that carries the flywheel (a disc no wider than it is across) and the
    δ the largest disc allowed gives, never a disc hundreds of kilometres wide."""
    with pytest.raises(rotor.EngineError) as info:
        rotor.design_flywheel(diesel, 0.01, max_outer_diameter_m=0.3)
    text = str(info.value)
    assert "\n" not in text and "max_outer_diameter_m = 0.3 m" in text
    needed = float(re.search(r"needs max_outer_diameter_m ≥ ([0-9.e+-]+) m", text).group(1))
    looser = float(re.search(r"a δ target of ([0-9.e+-]+) or more", text).group(1))
    # what the message offers is what works: that diameter carries the design, that δ is met
    ok = rotor.design_flywheel(diesel, 0.01, max_outer_diameter_m=needed * 1.001)
    assert ok.disc is not None and ok.disc.width_m <= ok.disc.outer_diameter_m
    assert ok.disc.inertia_kgm2 == pytest.approx(ok.flywheel_kgm2)
    loose = rotor.design_flywheel(diesel, looser * 1.001, max_outer_diameter_m=0.3)
    assert loose.disc is not None and loose.disc.outer_diameter_m == pytest.approx(0.3)
    assert loose.disc.width_m <= 0.3


def test_a_disc_past_its_limit_is_refused_by_lightest_disc_too():
    J, rho = 50.0, 7200.0
    square = (32 * J / (rho * math.pi)) ** 0.2  # the disc as wide as it is across: ρπD⁵/32 = J
    with pytest.raises(rotor.EngineError, match=rf"max_outer_diameter_m = 0.01 m.*≥ {square:.4g} m") as info:
        rotor.lightest_disc(J, peak_rpm=1250, max_outer_diameter_m=0.01)
    assert "\n" not in str(info.value)
    rim = rpm_to_rad_s(1250) * square / 2
    with pytest.raises(rotor.EngineError, match=rf"max_rim_speed_m_s = 5 m/s.*max_rim_speed_m_s ≥ {rim:.4g} m/s"):
        rotor.lightest_disc(J, peak_rpm=1250, max_rim_speed_m_s=5.0)
    wide = rotor.lightest_disc(50.0, peak_rpm=1250, max_outer_diameter_m=0.5, max_width_m=2.0)  # a drum, allowed
    assert wide.width_m == pytest.approx(32 * 50.0 / (7200.0 * math.pi * 0.5**4))


def test_cli_refuses_a_disc_thousands_of_kilometres_wide(capsys):
    from rotor.cli import main

    assert main(["flywheel", "4chn15", "--delta", "0.01", "--max-diameter", "0.01"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "max_outer_diameter_m = 0.01 m" in captured.err and "max_outer_diameter_m ≥ " in captured.err


def test_design_with_disc_and_shaft(diesel):
    d = rotor.design_flywheel(diesel, 0.01, shaft_inertia_kgm2=1.5, max_outer_diameter_m=0.7, max_width_m=0.2)
    assert d.flywheel_kgm2 == pytest.approx(d.crankshaft_inertia_kgm2 - 1.5)
    assert d.disc.inertia_kgm2 == pytest.approx(d.flywheel_kgm2)
    assert d.disc.width_m <= 0.2
    assert "lightest disc" in d.summary()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(delta=0.0), "must lie in"),
        (dict(delta=float("nan")), "must lie in"),
        (dict(delta=0.01, points=[-5.0]), "positive, finite speed"),
        (dict(delta=0.01, points=[]), "no operating points"),
        (dict(delta=0.01, points=[OperatingPoint(1000, -1.0)]), "imep_scale"),
    ],
)
def test_bad_input(diesel, kwargs, match):
    with pytest.raises(rotor.EngineError, match=match):
        rotor.design_flywheel(diesel, **kwargs)


def test_cli_json_and_errors(capsys, tmp_path):
    from rotor.cli import main

    assert (
        main(
            [
                "flywheel",
                "4chn15",
                "--delta",
                "0.01",
                "--rpm",
                "800,1250",
                "--imep-scale",
                "0.4,1",
                "--json",
                "--plot",
                str(tmp_path),
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    for key in ("crankshaft_inertia_kgm2", "textbook_inertia_kgm2", "binding_rpm", "delta_achieved"):
        assert key in out
    assert out["binding_rpm"] in (800.0, 1250.0)
    assert out["delta_achieved"] == pytest.approx(0.01, rel=1e-6)
    assert [p["rpm"] for p in out["points"]] == [800.0, 1250.0]
    assert (tmp_path / "flywheel.png").stat().st_size > 10_000
    # the design is the [crankshaft] value: the engine with it meets the target at the binding point
    engine = rotor.load_engine("4chn15")
    scale = 0.4 if out["binding_rpm"] == 800.0 else 1.0
    r = rotor.steady_state(
        with_crankshaft_inertia(engine, out["crankshaft_inertia_kgm2"]), out["binding_rpm"], imep_scale=scale
    )
    assert float(r.delta) == pytest.approx(0.01, rel=1e-6)

    assert main(["flywheel", "4chn15", "--delta", "0.01", "--rpm", "800,900", "--imep-scale", "1,1,1"]) == 2
    assert "one per --rpm" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["flywheel", "4chn15", "--delta", "0.01", "--rpm", "800,abc"])
    assert "not a number" in capsys.readouterr().err


def test_per_point_targets(diesel):
    """Each point may carry its own target (looser at idle); the binding point meets its own."""
    pts = [OperatingPoint(600, 0.25, None, 0.04), OperatingPoint(1250, 1.0, None, 0.005)]
    d = rotor.design_flywheel(diesel, None, pts)
    alone = [
        rotor.design_flywheel(diesel, p.delta, [OperatingPoint(p.rpm, p.imep_scale)]).crankshaft_inertia_kgm2
        for p in pts
    ]
    assert d.crankshaft_inertia_kgm2 == pytest.approx(max(alone), rel=1e-9)
    for p, target in zip(d.points, (0.04, 0.005)):
        assert p.delta_target == target and p.delta <= target * (1 + 1e-6)
    assert d.delta_achieved == pytest.approx(d.delta_target, rel=1e-6)
    with pytest.raises(rotor.EngineError, match="no δ target"):
        rotor.design_flywheel(diesel, None, [1250])


def test_plot_and_report(diesel):
    import matplotlib.pyplot as plt

    d = rotor.design_flywheel(diesel, 0.01, [OperatingPoint(600, 0.25, None, 0.03), 1250])
    axes = d.plot(n=5)
    assert len(axes) == 2 and len(axes[0].lines) >= 4
    plt.close("all")
    text = d.summary()
    assert "binding" in text and "a shaft of" not in text  # no shaft line when none was given
    mech = float(rotor.mean_reduced_inertia(diesel)) - float(diesel.crankshaft.inertia_kgm2)
    assert d.textbook_total_ratio == pytest.approx(
        d.textbook.total_inertia_kgm2 / (d.crankshaft_inertia_kgm2 + mech), rel=1e-6
    )


def _excess_work(engine, scales, rpm, n=2880):
    """The textbook excess work from the per-cylinder gas torques, fired and motored, at
    each cylinder's fuelling, plus the reciprocating inertia torque (independent of the
    steady-state tables)."""
    import jax.numpy as jnp

    motored = engine.replace(pressure=engine.pressure.motored(engine.strokes))
    th = jnp.arange(n) * (engine.cycle_rad / n)
    fired = np.asarray(rotor.cylinder_gas_torques(engine, th))
    mot = np.asarray(rotor.cylinder_gas_torques(motored, th))
    total = (mot + np.asarray(scales) * (fired - mot)).sum(-1) + np.asarray(
        rotor.reciprocating_inertia_torque(engine, th, rpm_to_rad_s(rpm))
    )
    W = np.cumsum(total - total.mean()) * engine.cycle_rad / n
    return W.max() - W.min()


@pytest.mark.parametrize("scale", [0.3, [1.0, 1.0, 1.0, 0.0], "propeller"])
def test_textbook_excess_work_at_the_points_fuelling(diesel, scale):
    """The textbook diagram is the point's own: part fuelling, one cylinder out, or the
    fuelling solved for a propeller load."""
    load = rotor.PropellerLoad(300.0, 1250.0) if scale == "propeller" else None
    s = 1.0 if scale == "propeller" else scale
    r = rotor.steady_state(diesel, 900, load, imep_scale=s)
    fuel = float(r.fuel_scale) if load is not None else 1.0
    expected = _excess_work(diesel, fuel * np.broadcast_to(np.asarray(s, float), (4,)), 900)
    assert float(r.excess_work_J) == pytest.approx(expected, rel=2e-3)
    tb = rotor.textbook_flywheel(diesel, 0.01, 900, imep_scale=s, load=load)
    assert tb.excess_work_J == pytest.approx(expected, rel=2e-3)


def test_rim_speed_at_the_highest_speed(diesel):
    """The rim speed limit holds at the fastest the flywheel turns: by default the larger of
    [operating] rpm and the points' peak speeds, or max_rpm."""
    d = rotor.design_flywheel(diesel, 0.03, [OperatingPoint(600, 0.25)], max_rim_speed_m_s=50)
    assert d.disc.peak_rpm >= 1250  # the engine runs at 1250 rpm, not only at the idle point
    omega = rpm_to_rad_s(d.disc.peak_rpm)
    assert d.disc.rim_speed_m_s == pytest.approx(50.0) and omega * d.disc.outer_diameter_m / 2 == pytest.approx(50.0)
    d2 = rotor.design_flywheel(diesel, 0.03, [OperatingPoint(600, 0.25)], max_rim_speed_m_s=50, max_rpm=2000)
    assert d2.disc.peak_rpm == 2000 and d2.disc.outer_diameter_m == pytest.approx(
        d.disc.outer_diameter_m * d.disc.peak_rpm / 2000
    )


def test_no_flywheel_needed_and_shaft_alone(diesel):
    with pytest.raises(rotor.EngineError, match="no flywheel is needed"):
        rotor.design_flywheel(rotor.load_engine("v8"), 0.2)
    # a point that needs none next to one that does: the design follows the other
    d = rotor.design_flywheel(
        rotor.load_engine("v8"), None, [OperatingPoint(3000, 1.0, None, 0.2), OperatingPoint(3000, 1.0, None, 0.01)]
    )
    assert d.points[0].inertia_kgm2 == 0.0 and d.binding_index == 1
    big = rotor.design_flywheel(diesel, 0.01, shaft_inertia_kgm2=100.0)
    assert big.flywheel_kgm2 == 0.0 and not big.flywheel_needed and "alone meets the target" in big.summary()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(max_width_m=0.1), "outer-diameter or a rim-speed limit"),
        (dict(shaft_inertia_kgm2=-1.0), "shaft_inertia_kgm2"),
        (dict(diameter_strokes=0.0), "diameter_strokes"),
        (dict(grid_deg=0.0), "grid_deg"),
        (dict(points=[OperatingPoint(1250, [1.0, 1.0])]), "one per cylinder"),
        (dict(points=[OperatingPoint(1250, 1.0, "propeller")]), "propeller"),
        (dict(points=[OperatingPoint(1250, 1.0, 42)]), "is not a load"),
        (dict(max_outer_diameter_m=1e-300), "not larger than the bore"),
    ],
)
def test_bad_design_arguments(diesel, kwargs, match):
    with pytest.raises(rotor.EngineError, match=match):
        rotor.design_flywheel(diesel, 0.01, **kwargs)


def test_design_speaks_the_result_protocol(diesel):
    """The design knows its engine; its JSON is the CLI's, its table has a row per point, and
    its δ sweep (computed by the design, drawn by plotting) meets the design at the points."""
    pts = [OperatingPoint(600, 0.25, None, 0.03), OperatingPoint(1250, [1.0, 1.0, 1.0, 0.9])]
    d = rotor.design_flywheel(diesel, 0.01, pts, shaft_inertia_kgm2=1.0, max_outer_diameter_m=0.7)
    assert d.engine is diesel and d.engine_name == diesel.name
    out = d.to_json_dict()
    assert list(out) == [
        "engine",
        "delta_target",
        "crankshaft_inertia_kgm2",
        "textbook_inertia_kgm2",
        "textbook_ratio",
        "textbook_total_ratio",
        "binding_rpm",
        "delta_achieved",
        "shaft_inertia_kgm2",
        "flywheel_kgm2",
        "flywheel_needed",
        "delta_shaft_alone",
        "note",
        "textbook",
        "fidelity",
        "points",
        "disc",
        "grid_deg",
        "diameter_strokes",
    ]
    assert json.loads(json.dumps(out, allow_nan=False)) == out
    assert out["points"][1]["imep_scale"] == [1.0, 1.0, 1.0, 0.9] and out["disc"]["limited_by"] == "outer diameter"
    df = d.to_pandas()
    assert list(df["rpm"]) == [600.0, 1250.0] and df["binding"].sum() == 1
    assert df["delta_designed"].tolist() == [p.delta for p in d.points]
    assert d.summary().splitlines()[0].startswith(diesel.name) and len(repr(d)) < 300
    # δ of the sweep at a point's own speed and fuelling is the design's δ there
    i = d.binding_index
    s = d.delta_sweep((d.points[i].rpm, d.points[i].rpm), 1)
    assert s.designed[0] == pytest.approx(d.delta_achieved, rel=1e-9)
    s = d.delta_sweep(n=4)
    assert s.rpm.tolist() == pytest.approx(np.linspace(480, 1500, 4).tolist())
    assert s.textbook is not None and np.all(np.isfinite(s.designed)) and np.all(s.designed > 0)
    for bad in [(1000, 500), (0, 1000), "fast"]:
        with pytest.raises(rotor.EngineError, match="rpm_range"):
            d.delta_sweep(bad)
    with pytest.raises(rotor.EngineError, match="number of sweep speeds"):
        d.delta_sweep(n=0)


def test_textbook_and_disc_are_results(diesel):
    tb = rotor.textbook_flywheel(diesel, 0.01, 1250)
    assert f"{tb.total_inertia_kgm2:.4f}" in tb.summary()
    assert tb.to_json_dict()["excess_work_J"] == tb.excess_work_J and len(tb.to_pandas()) == 1
    disc = rotor.lightest_disc(1.0, peak_rpm=1250, max_outer_diameter_m=0.5)
    assert disc.summary().startswith("lightest disc: D = 0.500 m (outer diameter limit)")
    assert disc.to_json_dict()["mass_kg"] == pytest.approx(disc.mass_kg)


def test_solver_outcomes_are_not_input_errors(diesel, monkeypatch):
    """No steady state at a point, or Newton's method finding no inertia, is a SolverError
    (the command line exits 1), not an EngineError (exit 2)."""
    from rotor.design.flywheel import DeltaOfInertia
    from rotor.errors import SolverError

    with monkeypatch.context() as m:  # the crankshaft stops within the cycle at every inertia tried
        m.setattr(DeltaOfInertia, "state", lambda self, J, p: (float("nan"), 0.0))
        with pytest.raises(rotor.NoSteadyStateError, match="no steady state at 1250 rpm") as e:
            rotor.design_flywheel(diesel, 0.01)
        assert not isinstance(e.value, rotor.EngineError)
    with monkeypatch.context() as m:  # Newton stops short of the target
        m.setattr(DeltaOfInertia, "root", lambda self, u0, log_target, p, rtol: (u0, False, 60))
        with pytest.raises(SolverError, match="Newton's method found no crankshaft inertia") as e:
            rotor.design_flywheel(diesel, 0.01)
        assert not isinstance(e.value, rotor.EngineError)
