"""The result object: δ, orders, tables, plots, progress; chunked runs equal one-shot runs."""

import equinox as eqx
import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np
import pytest

import rotor
from rotor.progress import Progress


@pytest.fixture(scope="module")
def steady(diesel):
    return rotor.steady_state(diesel)


def test_orders_reconstruct_the_speed(steady):
    """mean + Σ A·cos(order·θ + φ) over all orders gives ω(θ) back."""
    o = steady.orders(max_order=1e9)
    theta = np.asarray(steady.theta)
    w = float(jnp.mean(steady.omega)) + sum(
        a * np.cos(k * theta + p)
        for k, a, p in zip(o.order, np.asarray(o.speed_amplitude_rad_s), np.asarray(o.speed_phase_rad))
    )
    assert np.max(np.abs(w - np.asarray(steady.omega))) < 1e-9 * float(steady.omega[0])
    assert o.order[0] == 0.5 and np.allclose(np.diff(o.order), 0.5)


def test_delta_matches_sample_extremes(steady):
    w = np.asarray(steady.omega)
    raw = (w.max() - w.min()) / float(steady.mean_omega)
    # parabolic refinement moves δ by less than the sampling error of 0.25° steps
    assert float(steady.delta) == pytest.approx(raw, rel=1e-5)
    assert float(steady.delta) >= raw


def test_the_extremes_of_concrete_cycles_are_the_compiled_ones_to_the_bit(steady, diesel):
    """A finished result's δ takes its cycles' refined extremes in NumPy, a traced one in the
    compiled program: the same numbers to the bit for the same cycles, and δ per cycle the
    same to rounding (the cycles' means are summed in a different order)."""
    import dataclasses

    from rotor.cycles import cycle_slopes
    from rotor.dynamics.result import cycle_extremes

    run = rotor.simulate(diesel, cycles=3, load=rotor.ConstantLoad(1131.95), progress=False)
    x = np.asarray(run.omega)[: 3 * run.points_per_cycle].reshape(3, -1)
    slopes = cycle_slopes(np.asarray(run.cycle_mean_omega), run.cycle_rad)
    concrete = cycle_extremes(x, slopes, run.cycle_rad)
    traced = jax.jit(cycle_extremes, static_argnums=2)(x, slopes, run.cycle_rad)
    assert all(isinstance(c, np.ndarray) for c in concrete)
    for c, t in zip(concrete, traced, strict=True):
        np.testing.assert_array_equal(c, np.asarray(t))
    for r in (steady, run):
        traced_delta = jax.jit(lambda w, r=r: dataclasses.replace(r, omega=w).delta_per_cycle)(jnp.asarray(r.omega))
        np.testing.assert_allclose(np.asarray(r.delta_per_cycle), np.asarray(traced_delta), rtol=1e-14, atol=0)


def test_a_steady_states_delta_is_the_one_of_its_arrays(diesel):
    """The closed form hands δ back with its arrays (its compiled program computes it with the
    code the result uses): the δ the result computes from its own ω and period, at several
    speeds and balances; a result whose ω is replaced computes its own."""
    import dataclasses

    for rpm, load in ((700.0, None), (1250.0, None), (2100.0, rotor.ConstantLoad(600.0))):
        r = rotor.steady_state(diesel, rpm=rpm, load=load)
        again = dataclasses.replace(r, omega=np.array(r.omega))  # the same speeds in another array
        np.testing.assert_allclose(float(r.delta), float(again.delta), rtol=1e-14, atol=0)
        np.testing.assert_allclose(np.asarray(r.delta_per_cycle), np.asarray(again.delta_per_cycle), rtol=1e-14)
    ramp = np.linspace(1.0, 1.01, r.omega.shape[0])
    changed = dataclasses.replace(r, omega=np.asarray(r.omega) * ramp)
    assert float(changed.delta) > float(r.delta) + 5e-3
    longer = dataclasses.replace(r, cycle_rad=2 * r.cycle_rad)  # twice the mean speed: half the δ
    assert float(longer.delta) == pytest.approx(0.5 * float(r.delta), rel=1e-12)
    with pytest.raises(ValueError, match="no complete cycle"):
        _ = dataclasses.replace(r, uniform_cycles=0).delta


def test_extreme_index_is_argmax_and_argmin_in_numpy_and_jax():
    """The first largest or smallest value's index, the first NaN's where there is one: as
    NumPy's and JAX's argmax and argmin, ties and NaNs included, compiled or not."""
    from rotor.cycles import extreme_index

    rng = np.random.default_rng(7)
    x = rng.integers(0, 5, size=(6, 40)).astype(float)  # many ties
    x[2, 17] = np.nan
    x[4, 3] = x[4, 30] = np.nan
    x[5] = -np.inf
    compiled = jax.jit(extreme_index, static_argnums=(0, 2))
    for largest, ref in ((True, np.argmax), (False, np.argmin)):
        for rows in (x, x[0], x[4]):
            want = ref(rows, axis=-1)
            np.testing.assert_array_equal(extreme_index(np, rows, largest), want)
            np.testing.assert_array_equal(np.asarray(compiled(jnp, jnp.asarray(rows), largest)), want)


def test_the_speed_range_of_a_finished_result_is_the_traced_one(steady, diesel):
    """The range of the speed over a run, (ω_max − ω_min)/ω_mean: in NumPy for a finished
    result, compiled where the speed is traced; the same to rounding, for the periodic
    cycle of a steady state and for a transient's cycles."""
    import dataclasses

    run = rotor.simulate(diesel, cycles=3, load=rotor.ConstantLoad(1131.95), progress=False)
    for r in (steady, run):
        concrete = r.speed_range_ratio
        traced = jax.jit(lambda w, r=r: dataclasses.replace(r, omega=w).speed_range_ratio)(jnp.asarray(r.omega))
        assert isinstance(concrete, np.generic | np.ndarray)
        np.testing.assert_allclose(float(concrete), float(traced), rtol=1e-14, atol=0)
    assert float(steady.speed_range_ratio) == pytest.approx(float(steady.delta), rel=1e-12)


def test_to_pandas_and_plots(steady, tmp_path):
    df = steady.to_pandas()
    assert list(df.columns)[:4] == ["t_s", "theta_rad", "angle_deg", "cycle"]
    assert len(df) == steady.points_per_cycle and df["rpm"].mean() == pytest.approx(1250, rel=1e-3)
    fig, ax = plt.subplots()
    assert steady.plot(ax=ax, kind="cycle") is ax and len(ax.lines) >= 1
    for kind in ("torque", "orders"):
        steady.plot(kind=kind)
    with pytest.raises(ValueError, match="kind"):
        steady.plot(kind="spectrum")
    plt.close("all")


def test_progress_bar_changes_no_number(diesel):
    load = rotor.PropellerLoad(1100.0, 1250.0)
    for method in ("closed", "grid"):
        one = rotor.simulate(diesel, rpm=1200.0, cycles=40, load=load, method=method, progress=False)
        shown = rotor.simulate(diesel, rpm=1200.0, cycles=40, load=load, method=method, progress=True)
        np.testing.assert_allclose(np.asarray(shown.omega), np.asarray(one.omega), rtol=1e-12)
        np.testing.assert_allclose(np.asarray(shown.t), np.asarray(one.t), rtol=1e-12)


def test_progress_bar_draws_after_two_seconds(capsys):
    bar = Progress(10, True)
    bar.update(1)
    assert capsys.readouterr().err == ""  # a short run shows nothing
    bar.start -= 3.0
    bar.update(5)
    bar.close()
    err = capsys.readouterr().err
    assert "simulating [" in err and "5/10 cycles" in err and err.endswith("\n")


def test_vmap_over_a_transient(diesel):
    load = rotor.PropellerLoad(1100.0, 1250.0)

    def delta(J):
        return rotor.simulate(
            eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, J), rpm=1200.0, cycles=3, load=load
        ).delta

    Js = jnp.array([8.0, 12.0])
    batch = jax.vmap(delta)(Js)
    for J, d in zip(Js, batch):
        assert float(d) == pytest.approx(float(delta(float(J))), rel=1e-10)
