"""Articulated (master and slave) rods: the slave piston's stroke, TDC and derivatives, the
engine's inertia and torque with slaves, gradients through the geometry, and what is refused."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rotor
from rotor.engine.articulated import SlaveGeometry, slave_piston_motion

R, L, L1 = 0.05, 0.18, 0.14
TH = jnp.linspace(0, 2 * np.pi, 361)


def v2(r1=0.04, knuckle=60.0, bank=60.0, rod=L1):
    return rotor.Engine(
        name="articulated V2",
        strokes=4,
        cylinders=2,
        geometry=rotor.Geometry(bore_m=0.1, stroke_m=2 * R, rod_length_m=L),
        masses=rotor.Masses(reciprocating_kg=0.6, rotating_kg=0.3),
        crankshaft=rotor.Crankshaft(inertia_kgm2=0.05),
        layout=rotor.Layout(throw_angles_deg=[0, 0], bank_angles_deg=[0, bank], firing_order=[1, 2]),
        articulated=rotor.Articulated(
            slaves=[2],
            masters=[1],
            knuckle_radius_m=r1,
            knuckle_angle_deg=knuckle,
            rod_length_m=rod,
            rod_knuckle_kg=0.2,
        ),
    )


def test_zero_knuckle_radius_is_an_ordinary_cylinder():
    """r1 = 0: the slave is an ordinary crank mechanism at its bank angle with rod l1."""
    g = SlaveGeometry(R, L, 0.0, 0.0, np.deg2rad(60), L1, np.deg2rad(60))
    slave = slave_piston_motion(TH + np.deg2rad(60), g)
    plain = rotor.piston_motion(TH, R, L1)
    for a, b in zip(slave, plain):
        assert np.allclose(a, b, atol=1e-12)


def test_slave_stroke_and_tdc_differ_from_the_master():
    """The textbook's articulated rod: with r1 > 0 the slave's kinematics differ (stroke, TDC), which is why
    designers aim for r1 -> 0 and L = L1 + r1."""
    g = SlaveGeometry(R, L, 0.0, 0.04, np.deg2rad(60), L1, np.deg2rad(60))
    s = slave_piston_motion(jnp.linspace(0, 2 * np.pi, 20001), g).s
    assert float(jnp.min(s)) > -1e-10  # TDC found
    stroke = float(jnp.max(s) - jnp.min(s))
    assert 1e-5 < abs(stroke - 2 * R) < 0.2 * R  # a different stroke (here +0.06 %)
    g0 = g._replace(knuckle_radius_m=0.0)
    s0 = slave_piston_motion(jnp.linspace(0, 2 * np.pi, 20001), g0).s
    assert abs(float(jnp.max(s0) - jnp.min(s0)) - 2 * R) < 1e-9


def test_slave_derivatives_match_finite_differences():
    g = SlaveGeometry(R, L, 0.0, 0.04, np.deg2rad(55), L1, np.deg2rad(60))
    h = 1e-5
    f = lambda a: slave_piston_motion(a, g).s  # noqa: E731
    fd = (f(TH + h) - f(TH - h)) / (2 * h)
    fd2 = (f(TH + h) - 2 * f(TH) + f(TH - h)) / h**2
    pm = slave_piston_motion(TH, g)
    assert np.allclose(pm.ds, fd, atol=1e-9)
    assert np.allclose(pm.d2s, fd2, atol=1e-4)


def test_engine_inertia_and_torque_with_a_slave():
    e = v2()
    I = rotor.reduced_inertia(e, TH)
    assert np.all(np.isfinite(I)) and float(jnp.min(I)) > 0.05
    # with r1 -> 0 and zero knuckle mass the slave adds what an ordinary cylinder adds
    e0 = v2(r1=0.0, rod=L)
    plain = rotor.Engine(
        name="V2",
        strokes=4,
        cylinders=2,
        geometry=e0.geometry,
        masses=rotor.Masses(reciprocating_kg=0.6, rotating_kg=0.3),
        crankshaft=e0.crankshaft,
        layout=e0.layout,
    )
    knuckle = 0.2 * R**2  # the knuckle mass then rides on the crank pin
    assert np.allclose(
        rotor.reduced_inertia(e0, TH), rotor.reduced_inertia(plain, TH) - 0.3 * R**2 + knuckle, rtol=1e-11
    )
    # the virtual-work torque of the slave's reciprocating inertia is -1/2 dI_rec/dtheta w^2
    w = 300.0
    tq = rotor.reciprocating_inertia_torque(e, TH, w)
    assert abs(float(jnp.mean(tq[:-1]))) < 1e-9 * float(jnp.max(jnp.abs(tq)))


def test_grad_through_articulated_geometry():
    def mean_I(r1):
        import equinox as eqx

        e = eqx.tree_at(lambda e: e.articulated.knuckle_radius_m, v2(), r1)
        return rotor.mean_reduced_inertia(e)

    g = jax.grad(mean_I)(jnp.asarray(0.04))
    fd = (mean_I(0.04 + 1e-6) - mean_I(0.04 - 1e-6)) / 2e-6
    assert np.isclose(g, fd, rtol=1e-5)


@pytest.mark.parametrize(
    "kwargs,key",
    [
        (dict(rod=0.05), "rod_length_m"),
    ],
)
def test_articulated_validation(kwargs, key):
    with pytest.raises(rotor.EngineError, match=key):
        v2(**kwargs)


def test_slave_must_share_the_master_throw():
    with pytest.raises(rotor.EngineError, match="share the crank throw"):
        rotor.Engine(
            name="bad",
            strokes=4,
            cylinders=2,
            geometry=rotor.Geometry(bore_m=0.1, stroke_m=2 * R, rod_length_m=L),
            masses=rotor.Masses(reciprocating_kg=0.6),
            crankshaft=rotor.Crankshaft(inertia_kgm2=0.05),
            layout=rotor.Layout(throw_angles_deg=[0, 180], bank_angles_deg=[0, 60], firing_order=[1, 2]),
            articulated=rotor.Articulated(
                slaves=[2], masters=[1], knuckle_radius_m=0.04, knuckle_angle_deg=60, rod_length_m=L1
            ),
        )


def test_slave_table_is_refused():
    with pytest.raises(ValueError, match="slave"):
        rotor.crank_table(v2(), cylinder=2)


def test_series_fidelity_is_refused_for_slave_rods():
    with pytest.raises(rotor.EngineError, match="ordinary crank trains"):
        rotor.steady_state(v2(), fidelity="series")
