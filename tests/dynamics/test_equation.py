"""The equation of motion's small helpers agree with their plain definitions."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rotor.dynamics.equation import sum_columns


@pytest.mark.parametrize("shape", [(3,), (5, 4), (2, 3, 6), (4, 1), (4, 0)])
def test_sum_columns_is_the_sum_over_the_last_axis(shape):
    x = np.random.default_rng(len(shape)).normal(size=shape)
    expected = np.sum(x, axis=-1)
    got = sum_columns(jnp.asarray(x))
    assert got.shape == expected.shape
    np.testing.assert_allclose(got, expected, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(jax.jit(sum_columns)(x), expected, rtol=1e-15, atol=1e-15)


def test_sum_columns_under_vmap_and_grad():
    x = np.random.default_rng(7).normal(size=(6, 5, 4))
    np.testing.assert_allclose(jax.vmap(sum_columns)(x), np.sum(x, axis=-1), rtol=1e-15, atol=1e-15)
    weights = np.arange(1.0, 5.0)
    gradient = jax.grad(lambda w: jnp.sum(sum_columns(w * x)))(weights)
    np.testing.assert_allclose(gradient, np.sum(x, axis=(0, 1)), rtol=1e-13)
