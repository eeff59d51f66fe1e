"""The public functions check traced values as they check known ones.

Under ``jax.jit``, ``jax.grad`` and ``jax.vmap`` an argument is a tracer with no value to
look at while the program is built; each public function that takes numbers checks it with
``eqx.error_if`` when the program runs (or, where the function computes on the host,
refuses the tracer at once), so that a NaN, an infinity, a zero where zero is invalid or a
value out of range raises an error naming the argument, never a plausible number. The
steady state with none (the kinetic energy would reach zero) raises too, unless
``throw=False`` asks for ``result.converged`` instead.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rotor

ENGINE = rotor.load_engine("4chn15")
PREPARED = rotor.prepare(ENGINE)
NAN, INF = math.nan, math.inf


def _with(path: Callable[[Any], Any]) -> Callable[[Any], rotor.Engine]:
    """The engine with the field at ``path`` replaced by the (traced) value."""
    return lambda x: eqx.tree_at(path, ENGINE, jnp.asarray(x, dtype=jnp.float64))


with_inertia = _with(lambda e: e.crankshaft.inertia_kgm2)
with_bore = _with(lambda e: e.geometry.bore_m)
with_rod = _with(lambda e: e.geometry.rod_length_m)
with_stroke = _with(lambda e: e.geometry.stroke_m)
THETA = jnp.linspace(0.0, 4 * jnp.pi, 16)


KNOTS = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)


def _sum(x: Any) -> Any:
    return jnp.sum(jnp.asarray(x))


def _after(result: Any, x: Any) -> Any:
    """``x``, once ``result`` is made (a function that returns no number of the input)."""
    return jnp.asarray(x)


# (case, function of one traced number returning a number, a valid value, bad values, what
# the error names): every public function that takes numbers a user may trace
CASES: list[tuple[str, Callable[[Any], Any], float, list[float], str]] = [
    ("steady_state rpm", lambda r: rotor.steady_state(ENGINE, rpm=r).delta, 1250.0, [NAN, INF, 0.0, -5.0, 1e6], "rpm"),
    ("steady_state no steady state", lambda r: rotor.steady_state(ENGINE, rpm=r).delta, 1250.0, [5.0], "no steady"),
    (
        "steady_state inertia",
        lambda j: rotor.steady_state(with_inertia(j)).delta,
        1.0,
        [NAN, 0.0, -1.0],
        r"\[crankshaft\] inertia_kgm2",
    ),
    (
        "steady_state prepared inertia",
        lambda j: rotor.steady_state(PREPARED.with_inertia(j)).delta,
        1.0,
        [NAN, 0.0],
        r"\[crankshaft\] inertia_kgm2",
    ),
    (
        "steady_state bore",
        lambda b: rotor.steady_state(with_bore(b)).delta,
        0.15,
        [NAN, 0.0],
        r"\[geometry\] bore_m",
    ),
    (
        "steady_state rod length",
        lambda L: rotor.steady_state(with_rod(L)).delta,
        0.384,
        [0.05],
        r"\[geometry\] rod_length_m",
    ),
    (
        "steady_state imep_scale",
        lambda s: rotor.steady_state(ENGINE, imep_scale=s).delta,
        1.0,
        [NAN, -1.0, 50.0],
        "imep_scale",
    ),
    (
        "steady_state constant load",
        lambda m: rotor.steady_state(ENGINE, load=rotor.ConstantLoad(m)).delta,
        300.0,
        [NAN, INF],
        r"\[load\] torque_Nm",
    ),
    (
        "steady_state load past the fuelling",
        lambda m: rotor.steady_state(ENGINE, load=rotor.ConstantLoad(m)).delta,
        300.0,
        [30000.0],
        "fuel scale",
    ),
    (
        "steady_state propeller load",
        lambda r: rotor.steady_state(ENGINE, load=rotor.PropellerLoad(600.0, r)).delta,
        1250.0,
        [NAN, 0.0],
        r"\[load\] rpm",
    ),
    (
        "steady_state friction",
        lambda f: rotor.steady_state(ENGINE, friction=rotor.Friction(f)).delta,
        1e5,
        [NAN, -1.0],
        r"\[friction\] fmep_pa",
    ),
    (
        "simulate rpm",
        lambda r: rotor.simulate(ENGINE, r, 2, load=rotor.ConstantLoad(500.0)).omega[-1],
        1250.0,
        [NAN, INF, 0.0],
        "rpm",
    ),
    (
        "simulate load",
        lambda m: rotor.simulate(ENGINE, 1250.0, 2, load=rotor.ConstantLoad(m)).omega[-1],
        500.0,
        [NAN],
        r"\[load\] torque_Nm",
    ),
    (
        "simulate combustion",
        lambda s: rotor.simulate(
            ENGINE, 1250.0, 2, load=rotor.ConstantLoad(500.0), combustion=jnp.full((2, 4), s)
        ).omega[-1],
        1.0,
        [NAN, -1.0],
        "combustion",
    ),
    (
        "simulate rtol",
        lambda t: rotor.simulate(ENGINE, 1250.0, 2, load=rotor.ConstantLoad(500.0), rtol=t).omega[-1],
        1e-9,
        [NAN, 1.0],
        "rtol",
    ),
    (
        "crank_train inertia",
        lambda j: rotor.crank_train(with_inertia(j)).mean_inertia,
        1.0,
        [NAN, 0.0],
        r"\[crankshaft\] inertia_kgm2",
    ),
    (
        "reduced_inertia theta",
        lambda t: _sum(rotor.reduced_inertia(ENGINE, THETA + t)),
        0.0,
        [NAN, INF],
        r"reduced_inertia\(theta\)",
    ),
    (
        "reduced_inertia engine",
        lambda j: _sum(rotor.reduced_inertia(with_inertia(j), THETA)),
        1.0,
        [NAN, 0.0],
        r"\[crankshaft\] inertia_kgm2",
    ),
    (
        "reduced_inertia_derivative theta",
        lambda t: _sum(rotor.reduced_inertia_derivative(ENGINE, THETA + t)),
        0.0,
        [NAN],
        r"reduced_inertia_derivative\(theta\)",
    ),
    (
        "cylinder_inertia theta",
        lambda t: _sum(rotor.cylinder_inertia(ENGINE, THETA + t)),
        0.0,
        [INF],
        r"cylinder_inertia\(theta\)",
    ),
    (
        "mean_reduced_inertia stroke",
        lambda s: rotor.mean_reduced_inertia(with_stroke(s)),
        0.205,
        [NAN, 0.0],
        r"\[geometry\] stroke_m",
    ),
    (
        "inertia_coefficients bore",
        lambda s: _sum(rotor.inertia_coefficients(with_stroke(s))[0]),
        0.205,
        [NAN],
        r"\[geometry\] stroke_m",
    ),
    (
        "engine_piston_motion theta",
        lambda t: _sum(rotor.engine_piston_motion(ENGINE, THETA + t).s),
        0.0,
        [NAN],
        r"engine_piston_motion\(theta\)",
    ),
    ("gas_torque theta", lambda t: _sum(rotor.gas_torque(ENGINE, THETA + t)), 0.0, [NAN, INF], r"gas_torque\(theta\)"),
    (
        "cylinder_pressure theta",
        lambda t: _sum(rotor.cylinder_pressure(ENGINE, THETA + t)),
        0.0,
        [NAN],
        r"cylinder_pressure\(theta\)",
    ),
    (
        "total_torque omega",
        lambda w: _sum(rotor.total_torque(ENGINE, THETA, w)),
        130.0,
        [NAN, INF],
        r"total_torque\(omega\)",
    ),
    (
        "reciprocating_inertia_torque omega",
        lambda w: _sum(rotor.reciprocating_inertia_torque(ENGINE, THETA, w)),
        130.0,
        [NAN],
        r"reciprocating_inertia_torque\(omega\)",
    ),
    (
        "crank_forces omega",
        lambda w: _sum(rotor.crank_forces(ENGINE, THETA, w)["t_N"]),
        130.0,
        [NAN],
        r"crank_forces\(omega\)",
    ),
    ("imep_pa bore", lambda b: rotor.imep_pa(with_bore(b)), 0.15, [NAN, 0.0], r"\[geometry\] bore_m"),
    ("mean_gas_torque bore", lambda b: rotor.mean_gas_torque(with_bore(b)), 0.15, [INF], r"\[geometry\] bore_m"),
    (
        "indicated_power_w omega",
        lambda w: rotor.indicated_power_w(ENGINE, w),
        130.0,
        [NAN],
        r"indicated_power_w\(omega\)",
    ),
    (
        "piston_motion theta",
        lambda t: _sum(rotor.piston_motion(THETA + t, 0.1, 0.4).s),
        0.0,
        [NAN],
        r"piston_motion\(theta\)",
    ),
    (
        "piston_motion crank radius",
        lambda r: _sum(rotor.piston_motion(THETA, r, 0.4).s),
        0.1,
        [NAN, 0.0, -0.1],
        r"piston_motion\(crank_radius_m\)",
    ),
    (
        "piston_motion rod length",
        lambda L: _sum(rotor.piston_motion(THETA, 0.1, L).ds),
        0.4,
        [NAN, 0.05],
        r"piston_motion\(rod_length_m\)",
    ),
    (
        "rod_motion rod length",
        lambda L: _sum(rotor.rod_motion(THETA, 0.1, L).beta),
        0.4,
        [0.1, INF],
        r"rod_motion\(rod_length_m\)",
    ),
    (
        "mean_piston_speed stroke",
        lambda s: rotor.mean_piston_speed(s, 130.0),
        0.2,
        [NAN, 0.0],
        r"mean_piston_speed\(stroke_m\)",
    ),
    ("mean_piston_speed omega", lambda w: rotor.mean_piston_speed(0.2, w), 130.0, [INF], r"mean_piston_speed\(omega\)"),
    (
        "periodic_pchip query",
        lambda q: _sum(rotor.periodic_pchip(THETA + q, KNOTS, np.sin(KNOTS), 2 * np.pi)),
        0.0,
        [NAN],
        r"periodic_pchip\(xq\)",
    ),
    (
        "periodic_pchip knots",
        lambda k: _sum(rotor.periodic_pchip(THETA, KNOTS * k, np.sin(KNOTS), 2 * np.pi)),
        1.0,
        [NAN, -1.0],
        r"periodic_pchip\(x\)",
    ),
    # computed on the host: a traced value is refused at once, naming the argument
    (
        "engine_summary engine",
        lambda b: _after(rotor.engine_summary(with_bore(b)), b),
        0.15,
        [NAN],
        r"engine_summary\(engine\)",
    ),
    ("crank_table engine", lambda b: _after(rotor.crank_table(with_bore(b)), b), 0.15, [NAN], r"crank_table\(engine\)"),
    (
        "steady_sweep rpm",
        lambda r: jnp.asarray(rotor.steady_sweep(ENGINE, r).delta[0]),
        1250.0,
        [NAN],
        r"steady_sweep\(rpm\)",
    ),
    (
        "design_flywheel delta",
        lambda d: jnp.asarray(rotor.design_flywheel(ENGINE, d).crankshaft_inertia_kgm2),
        0.01,
        [NAN, 0.0],
        r"design_flywheel\(delta\)",
    ),
    (
        "inertia_for_delta delta",
        lambda d: jnp.asarray(rotor.inertia_for_delta(ENGINE, d)),
        0.01,
        [NAN],
        r"inertia_for_delta\(delta\)",
    ),
    (
        "textbook_flywheel delta",
        lambda d: jnp.asarray(rotor.textbook_flywheel(ENGINE, d).total_inertia_kgm2),
        0.01,
        [INF],
        r"textbook_flywheel\(delta\)",
    ),
    (
        "lightest_disc inertia",
        lambda j: jnp.asarray(rotor.lightest_disc(j, peak_rpm=1250.0, max_outer_diameter_m=0.5).mass_kg),
        1.0,
        [NAN, 0.0],
        r"lightest_disc\(inertia_kgm2\)",
    ),
    (
        "combustion_pattern imep_scale",
        lambda s: jnp.sum(jnp.asarray(rotor.combustion_pattern(2, 4, imep_scale=s))),
        1.0,
        [NAN],
        r"combustion_pattern\(imep_scale\)",
    ),
]

TRANSFORMS: dict[str, Callable[[Callable[[Any], Any], float, float], Any]] = {
    "jit": lambda f, good, bad: jax.jit(f)(bad),
    "grad": lambda f, good, bad: jax.grad(f)(bad),
    "vmap": lambda f, good, bad: jax.vmap(f)(jnp.asarray([good, bad])),
}

_JITTED: dict[str, Callable[[Any], Any]] = {}


def _params() -> list:
    out = []
    for case, f, good, bads, names in CASES:
        for bad in bads:
            for transform in TRANSFORMS:
                out.append(pytest.param(case, f, good, bad, names, transform, id=f"{case} {bad:g} {transform}"))
    return out


@pytest.mark.parametrize("case, f, good, bad, names, transform", _params())
def test_a_traced_invalid_value_raises_naming_the_argument(case, f, good, bad, names, transform):
    if transform == "jit":  # one compiled program per case, for every bad value
        f = _JITTED.setdefault(case, jax.jit(f))
        run: Callable[[], Any] = lambda: f(bad)  # noqa: E731
    else:
        run = lambda: TRANSFORMS[transform](f, good, bad)  # noqa: E731
    with pytest.raises((RuntimeError, TypeError, ValueError)) as info:
        out = run()
        jax.block_until_ready(out)
        pytest.fail(f"{case}: {bad!r} under {transform} gave {out!r}, no error")
    assert re.search(names, str(info.value)), str(info.value)[-600:]


@pytest.mark.parametrize(
    "case", ["steady_state rpm", "reduced_inertia engine", "piston_motion rod length", "total_torque omega"]
)
def test_the_same_calls_with_valid_values_run(case):
    """The cases above are the checks, not a function that fails anyway: a valid value runs
    under each transformation and gives a finite number."""
    _, f, good, _, _ = next(c for c in CASES if c[0] == case)
    for transform in ("jit", "grad"):
        out = np.asarray(TRANSFORMS[transform](f, good, good))
        assert np.all(np.isfinite(out)), (case, transform, out)
    assert np.all(np.isfinite(np.asarray(jax.vmap(f)(jnp.asarray([good, good])))))


def test_no_steady_state_under_jit_raises_as_the_plain_call_does():
    with pytest.raises(rotor.NoSteadyStateError):
        rotor.steady_state(ENGINE, rpm=5.0)
    with pytest.raises(RuntimeError, match="no steady state"):
        jax.block_until_ready(jax.jit(lambda r: rotor.steady_state(ENGINE, rpm=r).delta)(5.0))


def test_throw_false_returns_the_status_instead():
    """``throw=False``: the result says it is none (``converged`` False), under jit and vmap
    item by item, and for known values too."""
    plain = rotor.steady_state(ENGINE, rpm=5.0, throw=False)
    assert not bool(plain.converged)
    jitted = jax.jit(lambda r: rotor.steady_state(ENGINE, rpm=r, throw=False).converged)
    assert not bool(jitted(5.0)) and bool(jitted(1250.0))
    both = jax.vmap(lambda r: rotor.steady_state(ENGINE, rpm=r, throw=False).converged)(jnp.asarray([1250.0, 5.0]))
    assert np.asarray(both).tolist() == [True, False]
    # an invalid traced argument: no error either, the status and NaN numbers
    flagged = jax.jit(lambda j: (lambda r: (r.converged, r.delta))(rotor.steady_state(with_inertia(j), throw=False)))
    ok, delta = flagged(0.0)
    assert not bool(ok) and np.isnan(float(delta))
    loaded = jax.jit(lambda m: rotor.steady_state(ENGINE, load=rotor.ConstantLoad(m), throw=False).converged)
    assert not bool(loaded(math.nan)) and bool(loaded(300.0))
    ok, delta = flagged(1.0)
    assert bool(ok) and float(delta) == pytest.approx(float(rotor.steady_state(with_inertia(1.0)).delta), rel=1e-9)
    with pytest.raises(TypeError, match=r"steady_state\(throw\)"):
        rotor.steady_state(ENGINE, throw="no")


@pytest.mark.parametrize("jit", [eqx.filter_jit, jax.jit], ids=["eqx.filter_jit", "jax.jit"])
def test_a_compiled_function_may_return_the_steady_state(jit):
    """A steady state is a pytree: a compiled function returns it whole, the same numbers
    as the plain call, and it speaks the result protocol afterwards."""
    plain = rotor.steady_state(ENGINE, rpm=1250.0)
    r = jit(lambda rpm: rotor.steady_state(ENGINE, rpm=rpm))(jnp.asarray(1250.0))
    assert isinstance(r, rotor.SpeedResult) and r.kind == "steady" and bool(r.converged)
    np.testing.assert_allclose(np.asarray(r.omega), np.asarray(plain.omega), rtol=1e-12)
    assert float(r.delta) == pytest.approx(float(plain.delta), rel=1e-9)
    assert float(r.load_torque_Nm) == pytest.approx(float(plain.load_torque_Nm), rel=1e-9)
    assert r.summary().splitlines()[0] == plain.summary().splitlines()[0]
