"""Losses that depend on speed other than as a + c·ω² (friction's speed-linear term, a
load's) in the steady state: the closed form with a fixed point on them, against shooting."""

import equinox as eqx
import jax
import numpy as np
import pytest

import rotor

DOCS_FRICTION = rotor.Friction(fmep_pa=0.8e5, fmep_per_speed_pa_s_per_m=2000.0)  # the engine-file how-to's


@pytest.fixture(scope="module")
def diesel():
    return rotor.load_engine("4chn15")


def _gap(a, b):
    return float(np.max(np.abs(np.asarray(a.omega) - np.asarray(b.omega))) / np.mean(np.asarray(b.omega)))


@pytest.mark.parametrize(
    ("friction", "load"),
    [
        (DOCS_FRICTION, None),
        (rotor.Friction(fmep_pa=0.8e5, fmep_per_speed_pa_s_per_m=2000.0, fmep_per_speed2_pa_s2_per_m2=50.0), None),
        (DOCS_FRICTION, rotor.PolynomialLoad(a=300.0, b=0.5)),
        (rotor.Friction(fmep_pa=0.8e5), rotor.TableLoad(rpm=[800.0, 1600.0], torque_Nm=[250.0, 400.0])),
    ],
    ids=["speed-linear", "with-square-term", "linear-load", "table-load"],
)
def test_speed_dependent_losses_take_the_closed_form_and_agree_with_shooting(diesel, friction, load):
    closed = rotor.steady_state(diesel, rpm=1100.0, friction=friction, load=load)
    shoot = rotor.steady_state(diesel, rpm=1100.0, friction=friction, load=load, method="shooting")
    assert closed.method == "closed" and closed.note is None
    assert shoot.method == "shooting" and float(shoot.periodicity_error) < 1e-10
    assert _gap(closed, shoot) < 1e-11
    assert float(closed.delta) == pytest.approx(float(shoot.delta), rel=1e-9)
    if load is None:
        assert float(closed.load_torque_Nm) == pytest.approx(float(shoot.load_torque_Nm), rel=1e-11)
    else:
        assert float(closed.fuel_scale) == pytest.approx(float(shoot.fuel_scale), rel=1e-11)
        assert float(closed.load_torque_Nm) == pytest.approx(float(shoot.load_torque_Nm), rel=1e-11)


def test_the_speed_term_is_carried(diesel):
    """The balancing load is the mean engine torque less friction's mean over the cycle, to
    O(δ²) a + b·ω̄: the speed term is there, not dropped."""
    with_term = rotor.steady_state(diesel, rpm=900.0, friction=DOCS_FRICTION)
    constant = rotor.steady_state(diesel, rpm=900.0, friction=rotor.Friction(fmep_pa=0.8e5))
    _, b, _ = (float(v) for v in DOCS_FRICTION.torque_coefficients(diesel))
    w = 900.0 / 9.549296585513721
    drop = float(constant.load_torque_Nm) - float(with_term.load_torque_Nm)
    assert drop == pytest.approx(b * w, rel=1e-4)
    assert _gap(with_term, constant) > 1e-9


def test_friction_too_large_for_the_fixed_point_is_shot_and_says_why(diesel):
    huge = rotor.Friction(fmep_pa=0.8e5, fmep_per_speed_pa_s_per_m=2.0e5)
    r = rotor.steady_state(diesel, rpm=900.0, friction=huge)
    assert r.method == "shooting"
    assert "fixed point" in r.note and "passes" in r.note
    assert "note: found by shooting" in r.summary()
    assert r.to_json_dict()["note"] == r.note
    with pytest.raises(rotor.SolverError, match="fixed point"):
        rotor.steady_state(diesel, rpm=900.0, friction=huge, method="closed")


def test_derivative_through_the_fixed_point_matches_shooting(diesel):
    engine = eqx.tree_at(lambda e: e.friction, diesel, DOCS_FRICTION, is_leaf=lambda x: x is None)
    J0 = float(engine.crankshaft.inertia_kgm2)

    def delta(J, method):
        e = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, engine, J)
        return rotor.steady_state(e, rpm=1250.0, method=method).delta

    g_closed = float(jax.grad(delta)(J0, "auto"))
    g_shoot = float(jax.grad(delta)(J0, "shooting"))
    assert g_closed == pytest.approx(g_shoot, rel=1e-8)
    fd = (float(delta(J0 * (1 + 1e-5), "auto")) - float(delta(J0 * (1 - 1e-5), "auto"))) / (2e-5 * J0)
    assert g_closed == pytest.approx(fd, rel=1e-6)


def test_traced_speed_dependent_friction_takes_the_closed_form(diesel):
    engine = eqx.tree_at(lambda e: e.friction, diesel, DOCS_FRICTION, is_leaf=lambda x: x is None)
    rpm = np.array([900.0, 1250.0, 1800.0])
    batched = jax.jit(jax.vmap(lambda r: rotor.steady_state(engine, rpm=r).delta))(rpm)
    one_by_one = [float(rotor.steady_state(engine, rpm=float(r), method="shooting").delta) for r in rpm]
    np.testing.assert_allclose(np.asarray(batched), one_by_one, rtol=1e-9)


def test_sweep_with_speed_linear_friction_agrees_with_shooting(diesel):
    prepared = rotor.prepare(diesel)
    rpm = np.array([700.0, 1250.0, 2100.0])
    J = np.array([0.6, 1.0, 2.5]) * float(diesel.crankshaft.inertia_kgm2)
    sweep = rotor.steady_sweep(prepared, rpm=rpm, inertia_kgm2=J, friction=DOCS_FRICTION, progress=False)
    assert sweep.converged.all()
    for i in range(3):
        e = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, J[i])
        shot = rotor.steady_state(e, rpm=rpm[i], friction=DOCS_FRICTION, method="shooting")
        assert sweep.delta[i] == pytest.approx(float(shot.delta), rel=1e-9)
        assert sweep.load_torque_Nm[i] == pytest.approx(float(shot.load_torque_Nm), rel=1e-10)
    loaded = rotor.steady_sweep(prepared, rpm=rpm, load_torque_Nm=300.0, friction=DOCS_FRICTION, progress=False)
    for i in range(3):
        shot = rotor.steady_state(
            diesel, rpm=rpm[i], load=rotor.ConstantLoad(300.0), friction=DOCS_FRICTION, method="shooting"
        )
        assert loaded.fuel_scale[i] == pytest.approx(float(shot.fuel_scale), rel=1e-10)
