"""Reduced inertia: closed forms, an independent kinetic-energy check, the form of
Anisimov, Yelenich and Melnyk ("Modelling a piston engine by the irregularity of its
crankshaft's rotation"), articulated rods, and gradients."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import two_mass_engine

import rotor
from rotor.units import RAD_S_PER_RPM

TH = jnp.linspace(0, 2 * np.pi, 512, endpoint=False)


@pytest.mark.parametrize("lam", [0.15, 0.2, 0.25, 0.3])
def test_mean_inertia_closed_form(lam):
    R, m = 0.1025, 9.72
    e = two_mass_engine(lam=lam, R=R, m_rec=m, m_rot=0.0, J=1e-9)
    closed = 1e-9 + m * R**2 * (0.5 + lam**2 / 8)
    mean = float(rotor.mean_reduced_inertia(e))
    assert abs(mean - closed) / closed < 0.002


def test_derivative_closed_form_two_mass():
    e = two_mass_engine(m_rot=3.0, J=0.5)
    g = e.geometry
    pm = rotor.piston_motion(TH, g.crank_radius_m, g.rod_length_m)
    closed = 2 * 9.72 * pm.ds * pm.d2s
    assert np.allclose(rotor.reduced_inertia_derivative(e, TH), closed, atol=1e-13)


def test_inertia_torque_is_minus_half_dI_omega_squared_and_has_zero_mean(diesel):
    omega = 1250 * RAD_S_PER_RPM
    th = jnp.linspace(0, 4 * np.pi, 4096, endpoint=False)
    tq = rotor.reciprocating_inertia_torque(diesel, th, omega)
    assert np.allclose(tq, -0.5 * rotor.reduced_inertia_derivative(diesel, th) * omega**2, atol=1e-9)
    assert abs(float(jnp.mean(tq))) < 1e-9 * float(jnp.max(jnp.abs(tq)))


def test_full_rod_equivalent_to_two_mass_split():
    """A rod whose own inertia is m*a*(L-a) is dynamically two point masses: identical I(theta)."""
    R, L, m, a = 0.05, 0.17, 0.8, 0.05
    base = two_mass_engine(lam=R / L, R=R, m_rec=0.5, m_rot=0.2, J=0.1)
    full = eqx.tree_at(
        lambda e: e.masses,
        base,
        rotor.Masses(
            reciprocating_kg=0.5, rotating_kg=0.2, rod_kg=m, rod_cg_from_big_end_m=a, rod_inertia_kgm2=m * a * (L - a)
        ),
    )
    split = eqx.tree_at(
        lambda e: e.masses, base, rotor.Masses(reciprocating_kg=0.5 + m * a / L, rotating_kg=0.2 + m * (L - a) / L)
    )
    assert np.allclose(rotor.reduced_inertia(full, TH), rotor.reduced_inertia(split, TH), rtol=1e-13)


def test_full_rod_against_finite_difference_kinetic_energy():
    """Independent check: velocities of the rod's centre of mass by finite differences of positions."""
    R, L, k, m, a, Ig = 0.05, 0.17, 0.008, 0.8, 0.06, 0.003
    e = two_mass_engine(lam=R / L, R=R, m_rec=0.5, m_rot=0.0, J=1e-9, k=k)
    e = eqx.tree_at(
        lambda e: e.masses,
        e,
        rotor.Masses(reciprocating_kg=0.5, rod_kg=m, rod_cg_from_big_end_m=a, rod_inertia_kgm2=Ig),
    )
    th = np.linspace(0, 2 * np.pi, 97)
    h = 1e-5

    def positions(t):
        c = np.array([R * np.cos(t), R * np.sin(t)])
        sb = (R * np.sin(t) - k) / L
        p = np.array([R * np.cos(t) + L * np.sqrt(1 - sb**2), k + 0 * t])
        return p, c + a * (p - c) / L, np.arcsin(sb)

    (p1, g1, b1), (p0, g0, b0) = positions(th + h), positions(th - h)
    vp, vg, vb = (p1 - p0) / (2 * h), (g1 - g0) / (2 * h), (b1 - b0) / (2 * h)
    I_fd = 1e-9 + 0.5 * vp[0] ** 2 + m * (vg**2).sum(0) + Ig * vb**2
    assert np.allclose(rotor.reduced_inertia(e, jnp.asarray(th)), I_fd, rtol=1e-8)


def test_derivative_matches_finite_differences():
    """I'(theta) by autodiff against finite differences of I(theta)."""
    e = two_mass_engine(lam=0.3, m_rot=1.0, J=0.01)
    th = jnp.linspace(0, 2 * np.pi, 2001)
    I = rotor.reduced_inertia(e, th)
    dI = rotor.reduced_inertia_derivative(e, th)
    fd = jnp.gradient(I, th)
    assert np.allclose(dI[1:-1], fd[1:-1], atol=2e-5 * float(jnp.max(jnp.abs(dI))))


def test_anisimov_form_keeps_the_low_harmonics():
    """Central two-mass cylinder: A, B, C agree with the lambda series to O(lambda^3), and
    what the form leaves out is the 3rd and 4th harmonic, -lam/2 and -lam^2/8 of m R^2."""
    for lam in (0.3, 0.15):
        R, m = 0.1, 2.0
        e = two_mass_engine(lam=lam, R=R, m_rec=m, m_rot=0.5, J=1e-9)
        A, B, C = (float(x[0]) for x in rotor.inertia_coefficients(e))
        mr2 = m * R**2
        assert abs(A - (-mr2)) < 2 * lam**3 * mr2
        assert abs(B - mr2 * lam / 2) < 2 * lam**3 * mr2
        assert abs(C - (0.5 * R**2 + mr2 * (1 + lam**2 / 8))) < 2 * lam**3 * mr2
        resid = rotor.reduced_inertia(e, TH) - rotor.reduced_inertia(e, TH, "coefficients")
        c = np.fft.rfft(np.asarray(resid)) / (TH.size / 2)
        assert np.all(np.abs(c[:3]) < 1e-12 * mr2)  # harmonics 0, 1, 2 kept exactly
        assert abs(c[3].real - (-lam / 2 * mr2)) < 2 * lam**3 * mr2
        assert abs(c[4].real - (-(lam**2) / 8 * mr2)) < 2 * lam**3 * mr2
        assert float(jnp.max(jnp.abs(resid))) <= (lam / 2 + lam**2 / 8 + 2 * lam**3) * mr2


def test_inline_four_inertia_has_no_first_order_term(diesel):
    """Anisimov, Yelenich and Melnyk, table 1.1: for an inline four the cos(theta) terms cancel; period 180 deg."""
    th = jnp.linspace(0, 2 * np.pi, 512, endpoint=False)
    I = np.asarray(rotor.reduced_inertia(diesel, th))
    c = np.abs(np.fft.rfft(I)) / th.size
    assert c[1] < 1e-12 * c[0] and c[3] < 1e-12 * c[0]
    assert c[2] > 1e-4 * c[0]
    assert np.allclose(I[:256], I[256:], rtol=1e-13)


def test_mean_model_is_constant(diesel):
    th = jnp.linspace(0, 2 * np.pi, 16)
    I = rotor.reduced_inertia(diesel, th, "mean")
    assert np.allclose(I, rotor.mean_reduced_inertia(diesel), rtol=0, atol=0)


def test_grad_over_engine_fields(diesel):
    """jax.grad through any numeric field, against central finite differences."""

    def mean_I(m):
        e = eqx.tree_at(lambda e: e.masses.reciprocating_kg, diesel, m)
        return rotor.mean_reduced_inertia(e)

    m0 = diesel.masses.reciprocating_kg
    g = jax.grad(mean_I)(m0)
    h = 1e-4
    fd = (mean_I(m0 + h) - mean_I(m0 - h)) / (2 * h)
    assert np.isclose(g, fd, rtol=1e-8)
    gJ = jax.grad(lambda J: rotor.mean_reduced_inertia(eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, J)))(
        diesel.crankshaft.inertia_kgm2
    )
    assert np.isclose(gJ, 1.0, rtol=1e-12)

    def torque(L):
        e = eqx.tree_at(lambda e: e.geometry.rod_length_m, diesel, L)
        return rotor.gas_torque(e, jnp.deg2rad(370.0))

    L0 = diesel.geometry.rod_length_m
    gl = jax.grad(torque)(L0)
    fdl = (torque(L0 + 1e-6) - torque(L0 - 1e-6)) / 2e-6
    assert np.isclose(gl, fdl, rtol=1e-6)


def test_jit_with_engine_argument(diesel):
    f = jax.jit(lambda e, t: rotor.reduced_inertia(e, t) + rotor.gas_torque(e, t))
    assert np.allclose(f(diesel, TH), rotor.reduced_inertia(diesel, TH) + rotor.gas_torque(diesel, TH))
