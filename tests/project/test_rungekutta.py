"""The Dopri8 with its stages written out is diffrax's Dopri8: with fixed steps the same
values to rounding (saved, read from the dense output, batched, differentiated), with
adaptive steps the same number of steps and values within the tolerance (also across jumps
of the step-size controller), and it is of eighth order on a closed form."""

from __future__ import annotations

import diffrax as dfx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rotor.rungekutta import UnrolledDopri8


def field(t, y, args):
    """A damped, forced pair of oscillators with a scalar leaf beside them."""
    x, v, s = y
    k, c = args
    return v, -k * x - c * v + jnp.sin(3.0 * t) * jnp.array([1.0, 0.5]), jnp.sum(x**2)


def switched_field(t, y, args):
    """:func:`field` with a forcing that jumps at t = 2 and t = 3.5 (the solve is told)."""
    x, v, s = field(t, y, args)
    return x, v + jnp.where(t >= 2.0, 1.0, 0.0) - jnp.where(t >= 3.5, 3.0, 0.0), s


Y0 = (jnp.array([1.0, -0.5]), jnp.array([0.0, 2.0]), jnp.asarray(0.0))


def solve(solver, args=None, controller=None, dense=False, vector_field=field):
    """The oscillators from t = 0 to 12, saved at 40 times (or their dense output read
    there); fixed steps of 0.05 unless a ``controller`` is given."""
    ts = jnp.linspace(0.1, 12.0, 40)
    args = (jnp.array([4.0, 9.0]), 0.3) if args is None else args
    sol = dfx.diffeqsolve(
        dfx.ODETerm(vector_field),
        solver,
        0.0,
        12.0,
        0.05,
        Y0,
        args=args,
        saveat=dfx.SaveAt(dense=True) if dense else dfx.SaveAt(ts=ts, t1=True),
        stepsize_controller=dfx.ConstantStepSize() if controller is None else controller,
        max_steps=10_000,
    )
    if dense:
        return jax.vmap(sol.evaluate)(ts), sol.stats["num_steps"]
    return sol.ys, sol.stats["num_steps"]


def assert_close(a, b, rtol=1e-12, atol=1e-13):
    for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
        np.testing.assert_allclose(np.asarray(x), np.asarray(y), rtol=rtol, atol=atol)


@pytest.mark.parametrize("dense", [False, True], ids=["saved", "dense output"])
def test_fixed_steps_give_diffrax_dopri8_values_to_rounding(dense):
    ys, steps = jax.jit(lambda: solve(UnrolledDopri8(), dense=dense))()
    ref, ref_steps = jax.jit(lambda: solve(dfx.Dopri8(), dense=dense))()
    assert int(steps) == int(ref_steps) == 240
    assert_close(ys, ref)


@pytest.mark.parametrize("jumps", [False, True], ids=["smooth", "a forcing that jumps"])
def test_adaptive_steps_are_diffrax_dopri8_steps(jumps):
    """The error estimate is a sum of large terms that cancel, so its rounding (and with it
    each next step size) differs in the ninth digit: the same number of steps give or take
    two, values within the tolerance (rtol = atol = 1e-9). Where the forcing jumps, the
    step after each jump evaluates its first stage afresh (the last stage of the step
    before belongs to the forcing before the jump)."""
    controller = dfx.PIDController(rtol=1e-9, atol=1e-9, jump_ts=jnp.array([2.0, 3.5]) if jumps else None)
    vector_field = switched_field if jumps else field
    ys, steps = jax.jit(lambda: solve(UnrolledDopri8(), controller=controller, vector_field=vector_field))()
    ref, ref_steps = jax.jit(lambda: solve(dfx.Dopri8(), controller=controller, vector_field=vector_field))()
    assert int(ref_steps) > 60 and abs(int(steps) - int(ref_steps)) <= 2
    assert_close(ys, ref, rtol=0.0, atol=1e-9)


def test_batched_and_differentiated_as_diffrax_dopri8():
    stiffness = jnp.array([[4.0, 9.0], [1.0, 16.0], [2.5, 2.5]])

    def batch(solver):
        return jax.vmap(lambda k: solve(solver, args=(k, 0.3))[0])(stiffness)

    assert_close(jax.jit(lambda: batch(UnrolledDopri8()))(), jax.jit(lambda: batch(dfx.Dopri8()))())

    def end(solver, c):
        ys, _ = solve(solver, args=(jnp.array([4.0, 9.0]), c))
        return ys[0][-1, 0]

    grad = jax.jit(jax.grad(lambda c: end(UnrolledDopri8(), c)))(0.3)
    ref = jax.jit(jax.grad(lambda c: end(dfx.Dopri8(), c)))(0.3)
    assert abs(float(ref)) > 1e-3
    np.testing.assert_allclose(float(grad), float(ref), rtol=1e-10)


def test_eighth_order_on_a_closed_form():
    """y' = y², y(0) = 1 has y = 1/(1 − t): with fixed steps to t = 0.5, halving the step
    divides the error at the end by about 2⁸."""

    def error(n):
        sol = dfx.diffeqsolve(
            dfx.ODETerm(lambda t, y, args: y**2),
            UnrolledDopri8(),
            0.0,
            0.5,
            0.5 / n,
            jnp.asarray(1.0),
            stepsize_controller=dfx.ConstantStepSize(),
        )
        return abs(float(sol.ys[-1]) - 2.0)

    assert 7.5 < np.log2(error(4) / error(8)) < 8.5
