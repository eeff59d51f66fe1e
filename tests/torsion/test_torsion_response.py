"""The torsional forced response, sweep and transient against their invariants:

(a) very stiff shafts reproduce the rigid model's steady state (δ, the speed orders, ω(θ));
(b) a free chain without damping conserves its energy over 1000 periods;
(c) the forced response (harmonic balance) agrees with a time-domain run (diffrax) that
    settles onto it from a perturbed start;
(d) bad input is refused in one line.

One compiled harmonic-balance kernel (the MWM six's nine masses on the 0.25° grid) serves
(a) and (c); the fixtures are module-scoped."""

from __future__ import annotations

import numpy as np
import pytest

import rotor
from rotor.errors import EngineError
from rotor.torsion.model import TorsionalChain, torsional_chain
from rotor.torsion.response import torsional_response, torsional_sweep
from rotor.torsion.transient import torsional_simulate
from rotor.units import RPM_PER_RAD_S

RPM = 1500.0


@pytest.fixture(scope="module")
def mwm() -> rotor.Engine:
    return rotor.load_engine("mwm6")


@pytest.fixture(scope="module")
def chain(mwm):
    return torsional_chain(mwm)


@pytest.fixture(scope="module")
def stiff(mwm, chain):
    """The MWM chain with 10⁶ times stiffer shafts and no damping (the rigid model has none)."""
    return TorsionalChain(
        chain.inertias_kgm2,
        chain.stiffnesses_Nm_per_rad * 1e6,
        names=chain.names,
        throw_masses=chain.throw_masses,
        load_mass=chain.load_mass,
    )


@pytest.fixture(scope="module")
def response(mwm):
    """The real, damped chain at 1500 rpm."""
    return torsional_response(mwm, RPM)


# ----------------------------------------------------------------------------- (a) the rigid limit
def test_very_stiff_shafts_reproduce_the_rigid_steady_state(mwm, stiff, response):
    rigid = rotor.steady_state(mwm, RPM)  # the same fidelity: exact variable inertia I(θ)
    tors = torsional_response(mwm, RPM, chain=stiff)
    w_m = RPM / RPM_PER_RAD_S
    for mass in ("flywheel", "damper"):  # the reference mass and the far end of the chain
        sr = tors.speed_result(mass)
        assert abs(float(sr.delta) - float(rigid.delta)) < 1e-6  # measured 3e-9
        o_t, o_r = sr.orders(max_order=12), rigid.orders(max_order=12)
        assert (
            np.max(np.abs(np.asarray(o_t.speed_amplitude_rad_s) - np.asarray(o_r.speed_amplitude_rad_s))) < 1e-6 * w_m
        )
        assert np.max(np.abs(np.asarray(sr.omega) - np.asarray(rigid.omega))) < 1e-6 * w_m
    assert np.max(np.abs(np.asarray(tors.t) - np.asarray(rigid.t))) < 1e-6 * float(rigid.period_s)
    assert tors.load_torque_Nm == pytest.approx(float(rigid.load_torque_Nm), rel=1e-6)
    # and the test can fail: the real chain's flywheel and front end differ from the rigid model
    real = response.speed_result("damper")
    assert abs(float(real.delta) - float(rigid.delta)) > 1e-2


# ----------------------------------------------------------------------------- (b) energy
def test_free_vibration_conserves_energy_over_1000_periods():
    """Two disks on a shaft (openTorsion's textbook example, 176.1 Hz), twisted and let go:
    Dopri8 at rtol 1e-13 keeps ½·ΣJ·ω² + ½·k·twist² to 1e-9 while the energy sloshes between
    kinetic and elastic (its error grows with the steps: rtol 1e-12 drifts 1.5e-9, 1e-14 3e-11)."""
    chain = TorsionalChain([211.4, 8.3], [9.775e6])
    f = float(np.asarray(rotor.torsional_modes(chain).natural_frequencies_hz)[0])
    run = torsional_simulate(chain, duration_s=1000 / f, initial=([0.0, 1e-3], [0.0, 0.0]), rtol=1e-13, samples=4001)
    assert run.solver == "dopri8"
    assert run.energy_drift < 1e-9  # measured 2.0e-10
    kinetic = 0.5 * np.sum(np.asarray(chain.inertias_kgm2) * np.asarray(run.omega) ** 2, axis=1)
    assert np.ptp(kinetic) > 0.5 * float(run.energy_J[0])  # not trivially constant


# ----------------------------------------------------------------------------- (c) vs the time domain
def test_forced_response_agrees_with_a_settled_time_domain_run(mwm, chain, response):
    """From the response's state with the shafts twisted by up to 0.05 mrad more and the masses'
    speeds stirred (no change in angular momentum), the damped chain settles back onto the
    response within three cycles (Dopri8, rtol 1e-10)."""
    a0 = np.asarray(response.angle_rad)[:, 0].copy()
    w0 = np.asarray(response.omega)[:, 0].copy()
    a0[:-1] += 5e-5 * np.sin(np.arange(8))  # the flywheel (reference) keeps its angle
    J = np.asarray(chain.inertias_kgm2)
    dw = 0.025 * np.cos(np.arange(9))
    w0 += dw - np.sum(J * dw) / np.sum(J)
    run = torsional_simulate(mwm, RPM, cycles=3, initial=(a0, w0), load=response.load_torque_Nm, rtol=1e-10)
    assert run.solver == "dopri8"  # the real chain is not stiff at this speed
    P, w_m = response.points_per_cycle, RPM / RPM_PER_RAD_S
    w = np.asarray(run.omega)
    first = np.max(np.abs(w[:P].T - np.asarray(response.omega))) / w_m
    last = np.max(np.abs(w[-P:].T - np.asarray(response.omega))) / w_m
    assert first > 1e-4  # the start was off the periodic state (measured 2e-3)
    assert last < 1e-6  # measured 2.5e-7 (1.4e-7 of it the 0.25° grid's collocation error)
    torque = np.asarray(run.torque_Nm)[-P:].T
    assert np.max(np.abs(torque - np.asarray(response.torque_Nm))) < 1e-5 * np.max(np.abs(response.torque_Nm))


def test_sweep_gives_the_response_at_each_speed(mwm, response):
    sweep = torsional_sweep(mwm, [RPM], grid_deg=0.25)
    assert sweep.converged.all()
    np.testing.assert_allclose(sweep.torque_pp_Nm[0], response.torque_pp_Nm, rtol=1e-8)
    np.testing.assert_allclose(sweep.load_torque_Nm[0], response.load_torque_Nm, rtol=1e-9)
    # the vibratory torque by order rebuilds its peak-to-peak scale
    assert sweep.torque_order_Nm.shape == (1, 8, 24)
    assert np.all(sweep.torque_order_Nm[0].sum(axis=1) >= 0.5 * sweep.torque_pp_Nm[0])


def test_response_figures(response):
    """The mean shaft torque grows throw by throw to the load (each throw adds its
    cylinder's mean torque); the damper's sections carry none."""
    mean = response.torque_mean_Nm
    assert abs(mean[0]) < 1.0 and abs(mean[1]) < 1.0
    assert mean[-1] == pytest.approx(response.load_torque_Nm, rel=2e-2)
    assert np.all(np.diff(mean[1:]) > 0)
    d = response.to_json_dict()
    assert d["converged"] and len(d["masses"]) == 9 and len(d["sections"]) == 8


# ----------------------------------------------------------------------------- (d) bad input
@pytest.mark.parametrize(
    "call,fragment",
    [
        (lambda e, c: torsional_response(rotor.load_engine("4chn15"), 1250), "has no [torsion] table; add one"),
        (lambda e, c: torsional_response(e, -5), "must be a positive, finite speed"),
        (lambda e, c: torsional_response(e, float("nan")), "must be a positive, finite speed"),
        (lambda e, c: torsional_response(e, 1500, imep_scale=[1, 2]), "one per cylinder (6)"),
        (lambda e, c: torsional_response(e, 1500, grid_deg=7), "must divide the 720° cycle"),
        (
            lambda e, c: torsional_response(
                e, 1500, load=rotor.LoadStep(rotor.ConstantLoad(1), rotor.ConstantLoad(2), 0.1)
            ),
            "does not change in time",
        ),
        (
            lambda e, c: torsional_response(e, 1500, chain=TorsionalChain(c.inertias_kgm2, c.stiffnesses_Nm_per_rad)),
            "throw_masses = [] names 0 crank throws, engine 'MWM six-cylinder diesel' has 6",
        ),
        (
            lambda e, c: torsional_response(
                e,
                1500,
                chain=TorsionalChain(c.inertias_kgm2 * 0.1, c.stiffnesses_Nm_per_rad, throw_masses=c.throw_masses),
            ),
            "less than the mean inertia of the rods and pistons on it",
        ),
        (lambda e, c: torsional_sweep(e, [1000, -1]), "is not a speed between"),
        (lambda e, c: torsional_simulate(c), "needs duration_s"),
        (lambda e, c: torsional_simulate(e, 1500, solver="euler"), "'auto', 'kvaerno5', 'dopri8'"),
        (lambda e, c: torsional_simulate(e, 1500, initial=([0.0], [1.0])), "need 9 finite numbers each"),
        (lambda e, c: torsional_simulate(e, 1500, rtol=1.0), "rtol) = 1.0: must lie between"),
    ],
)
def test_bad_input_is_one_line(mwm, chain, call, fragment):
    with pytest.raises(EngineError) as err:
        call(mwm, chain)
    text = str(err.value)
    assert fragment in text and "\n" not in text


def test_wrong_types_name_the_call(mwm):
    with pytest.raises(TypeError, match=r"torsional_response\(engine\): expected a rotor.Engine \(load it first"):
        torsional_response("mwm6", 1500)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"torsional_simulate\(initial\)"):
        torsional_simulate(mwm, 1500, initial="rest")


# ----------------------------------------------------------------------------- (e) derivatives
def test_gradients_through_the_response_match_central_differences(mwm, chain):
    """``jax.grad`` (reverse mode: the implicit function theorem's adjoint solve through the
    harmonic balance) of the flywheel's mean-square speed fluctuation with respect to every
    cylinder's ``imep_scale`` and every shaft's stiffness factor, against central differences
    (step 1e-4; 2° grid, to compile quickly). Tolerance 1e-6 of the largest derivative: the
    difference's truncation error is O(h²)·f''' (measured 3e-9 at h = 1e-3), its rounding
    ~1e-16/h, the Newton solve is converged far past NEWTON_TOL and the adjoint solve is at
    rtol 1e-9; measured agreement about 1e-10. (lineax's GMRES used to stop the reverse
    solve with a false "stagnation": this is its test.)"""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    spread = np.array([1.00, 1.08, 0.92, 1.04, 0.96, 1.00])
    k0 = chain.stiffnesses_Nm_per_rad

    def flywheel_ms(p):
        ch = eqx.tree_at(lambda c: c.stiffnesses_Nm_per_rad, chain, k0 * p[6:])
        r = torsional_response(mwm, RPM, chain=ch, imep_scale=p[:6], grid_deg=2.0)
        w = jnp.asarray(r.omega)[r.reference_mass]
        return jnp.mean((w - jnp.mean(w)) ** 2)

    p0 = jnp.asarray(np.concatenate([spread, np.ones(8)]))
    grad = np.asarray(jax.grad(flywheel_ms)(p0))
    h = 1e-4
    fd = np.array([(flywheel_ms(p0.at[i].add(h)) - flywheel_ms(p0.at[i].add(-h))) / (2 * h) for i in range(p0.size)])
    assert np.all(np.isfinite(grad)) and np.max(np.abs(grad)) > 0
    assert np.max(np.abs(grad - fd)) < 1e-6 * np.max(np.abs(grad))
    # every cylinder's combustion matters, and at least some shafts' stiffness does
    assert np.all(np.abs(grad[:6]) > 1e-3 * np.max(np.abs(grad)))
