"""Crank kinematics: closed forms against autodiff, the lambda series against the exact
forms (an O(lambda^3) difference), and the textbook formulas for the offset mechanism (Lukanin, "Dvigateli vnutrennego sgoraniya", vol. 2)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rotor
from rotor.engine.kinematics import piston_motion, rod_motion
from rotor.units import RAD_S_PER_RPM

TH = jnp.linspace(0, 2 * np.pi, 721)
R = 0.05


def _max_diff(lam, k=0.0):
    L = R / lam
    ex = piston_motion(TH, R, L, k, "exact")
    se = piston_motion(TH, R, L, k, "series")
    return np.array([float(jnp.max(jnp.abs(a - b))) / R for a, b in zip(ex, se)])


def test_series_differs_from_exact_by_lambda_cubed():
    lams = np.array([0.32, 0.16, 0.08])
    diffs = np.array([_max_diff(l) for l in lams])  # rows: lambda, cols: s, ds, d2s
    ratios = diffs[:-1] / diffs[1:]
    # halving lambda divides the error by 2^3 = 8 (up to the next order)
    assert np.all((ratios > 7.0) & (ratios < 9.0)), ratios
    scaled = diffs / lams[:, None] ** 3
    assert np.all(scaled < 1.0)  # and the constant is of order one


def test_offset_series_error_is_higher_order():
    for lam in (0.3, 0.15):
        z = 0.2
        d = _max_diff(lam, k=z * R)
        assert np.all(d < 2 * (lam**3 + lam**2 * z**2)), (lam, d)


@pytest.mark.parametrize("k", [0.0, 0.01, -0.015])
def test_derivatives_match_autodiff(k):
    L = 0.16
    s = lambda t: piston_motion(t, R, L, k).s  # noqa: E731
    ds = jax.vmap(jax.grad(s))(TH)
    d2s = jax.vmap(jax.grad(jax.grad(s)))(TH)
    pm = piston_motion(TH, R, L, k)
    assert np.allclose(pm.ds, ds, atol=1e-13)
    assert np.allclose(pm.d2s, d2s, atol=1e-12)
    b = lambda t: rod_motion(t, R, L, k).beta  # noqa: E731
    rm = rod_motion(TH, R, L, k)
    assert np.allclose(rm.dbeta, jax.vmap(jax.grad(b))(TH), atol=1e-13)
    assert np.allclose(rm.d2beta, jax.vmap(jax.grad(jax.grad(b)))(TH), atol=1e-12)


def test_the_offset_mechanism_follows_lukanins_formulas():
    """The offset mechanism (Lukanin, vol. 2): sin b = lam (sin a - z); rod angular velocity and acceleration; TDC at s = 0."""
    L, k = 0.17, 0.012
    lam, z = R / L, k / R
    a = TH
    rm = rod_motion(a, R, L, k)
    assert np.allclose(jnp.sin(rm.beta), lam * (jnp.sin(a) - z), atol=1e-15)
    root = 1 - lam**2 * (jnp.sin(a) - z) ** 2
    assert np.allclose(rm.dbeta, lam * jnp.cos(a) / jnp.sqrt(root), atol=1e-14)
    eps = lam * (lam**2 * jnp.cos(a) ** 2 * (jnp.sin(a) - z) - jnp.sin(a) * root) / root**1.5
    assert np.allclose(rm.d2beta, eps, atol=1e-13)
    s = piston_motion(a, R, L, k).s
    assert float(jnp.min(s)) > -1e-12 and float(jnp.min(s)) < 1e-4 * R
    # the offset stroke is longer than 2R: sqrt((L+R)^2-k^2) - sqrt((L-R)^2-k^2)
    stroke = np.sqrt((L + R) ** 2 - k**2) - np.sqrt((L - R) ** 2 - k**2)
    fine = jnp.linspace(0, 2 * np.pi, 200001)
    s_fine = piston_motion(fine, R, L, k).s
    assert abs(float(jnp.max(s_fine) - jnp.min(s_fine)) - stroke) < 1e-9
    assert stroke > 2 * R


def test_central_tdc_bdc_values():
    L = 0.2
    pm = piston_motion(jnp.array([0.0, np.pi]), R, L)
    assert np.allclose(pm.s, [0.0, 2 * R], atol=1e-15)
    assert np.allclose(pm.ds, 0.0, atol=1e-15)
    lam = R / L
    assert np.allclose(pm.d2s, [R * (1 + lam), -R * (1 - lam)], rtol=1e-14)


def test_mean_piston_speed():
    omega = 1250 * RAD_S_PER_RPM
    assert np.isclose(rotor.mean_piston_speed(0.205, omega), 0.205 * 1250 / 30, rtol=1e-14)


def test_unknown_model_is_an_error():
    with pytest.raises(ValueError, match="series"):
        piston_motion(0.0, R, 0.2, model="taylor")
