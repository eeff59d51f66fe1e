"""Prepare once (``rotor.prepare``), the table cache, and steady states in bulk (``rotor.steady_sweep``).

The tables of an engine are built once and reused; a change to anything they depend on
must never reuse them ("a geometry change after preparing never reuses stale
tables"), while the crankshaft inertia, the speed, the fuelling and the load change
nothing prepared.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rotor
from rotor.dynamics import crank_train as ct
from rotor.dynamics.crank_train import shift_inertia, table_inputs, table_key, train_from_engine

GRID = 1.0  # coarse tables keep the compile and run times of these tests small


@pytest.fixture(scope="module")
def diesel():
    return rotor.load_engine("4chn15")


@pytest.fixture(scope="module")
def prepared(diesel):
    return rotor.prepare(diesel, grid_deg=GRID)


def _perturbed(engine, path, leaf):
    """``engine`` with one leaf of its table inputs changed by a relative 1e-9 (or +1 where it is 0)."""
    a = np.asarray(leaf, dtype=np.float64)
    new = np.where(a == 0, a + 1.0, a * (1 + 1e-9))
    return eqx.tree_at(lambda e: _get(table_inputs(e), path), engine, jnp.asarray(new, dtype=jnp.asarray(leaf).dtype))


def _get(tree, path):
    for key in path:
        tree = _step(tree, key)
    return tree


def _step(tree, key):
    if isinstance(key, jax.tree_util.SequenceKey):
        return tree[key.idx]
    if isinstance(key, jax.tree_util.GetAttrKey):
        return getattr(tree, key.name)
    if isinstance(key, jax.tree_util.DictKey):
        return tree[key.key]
    raise TypeError(key)


@pytest.mark.parametrize("name", ["4chn15", "mwm6", "v8"])
def test_every_table_input_changes_the_key_and_the_inertia_does_not(name):
    """Each number the tables depend on, changed by 1e-9, gives another cache key (so new
    tables); the crankshaft inertia, friction and operating point give the same key."""
    engine = rotor.load_engine(name)
    key = table_key(engine, "variable", 720)
    leaves = jax.tree_util.tree_leaves_with_path(table_inputs(engine))
    assert len(leaves) > 10
    for path, leaf in leaves:
        if isinstance(leaf, (int, np.integer)) and not isinstance(leaf, np.ndarray):
            continue  # strokes, cylinders: static, part of the structure
        changed = _perturbed(engine, path, leaf)
        assert table_key(changed, "variable", 720) != key, jax.tree_util.keystr(path)
    for field, value in (("crankshaft.inertia_kgm2", 3.0), ("operating.rpm", 900.0)):
        other = eqx.tree_at(lambda e, f=field: _attr(e, f), engine, jnp.asarray(value))
        assert table_key(other, "variable", 720) == key, field
    assert table_key(engine, "constant", 720) != key
    assert table_key(engine, "variable", 1440) != key


def _attr(obj, dotted):
    for name in dotted.split("."):
        obj = getattr(obj, name)
    return obj


def test_a_geometry_change_never_reuses_stale_tables(diesel):
    """Through the cache (an Engine) and through a prepared engine: a changed rod, bore,
    mass or pressure after the first solve gives the result of a fresh solve."""
    ct.clear_table_cache()
    base = rotor.steady_state(diesel, grid_deg=GRID)
    changes = {
        "rod": lambda e: e.geometry.rod_length_m,
        "bore": lambda e: e.geometry.bore_m,
        "mass": lambda e: e.masses.reciprocating_kg,
    }
    for name, where in changes.items():
        changed = eqx.tree_at(where, diesel, where(diesel) * 1.05)
        cached = rotor.steady_state(changed, grid_deg=GRID)  # the cache holds the old engine's tables
        ct.clear_table_cache()
        fresh = rotor.steady_state(changed, grid_deg=GRID)
        np.testing.assert_array_equal(np.asarray(cached.omega), np.asarray(fresh.omega), err_msg=name)
        assert float(cached.delta) != pytest.approx(float(base.delta), rel=1e-6), name
    # a prepared engine whose geometry is changed afterwards is refused, never solved with old tables
    prepared = rotor.prepare(diesel, grid_deg=GRID)
    stale = eqx.tree_at(lambda p: p.engine.geometry.rod_length_m, prepared, diesel.geometry.rod_length_m * 1.05)
    with pytest.raises(rotor.EngineError, match="changed after rotor.prepare"):
        rotor.steady_state(stale)
    with pytest.raises(rotor.EngineError, match="changed after rotor.prepare"):
        rotor.simulate(stale, cycles=2)
    # ... and inside jit, where no Python check can see the values, by a runtime check
    solve = eqx.filter_jit(lambda p: rotor.steady_state(p).delta)
    assert np.isfinite(float(solve(prepared)))
    with pytest.raises(Exception, match="changed after rotor.prepare"):
        jax.block_until_ready(solve(stale))


def test_an_engine_object_is_checked_and_its_tables_found_once(diesel, monkeypatch):
    """The same engine object (immutable) is checked and looked up once; a new object with
    the same values is checked again, and one with a bad value put in by tree_at is refused
    although its tables' inputs are those of the engine before."""
    ct.clear_table_cache()
    checks = []
    real = rotor.Engine.check
    monkeypatch.setattr(rotor.Engine, "check", lambda self: checks.append(self) or real(self))
    first = rotor.steady_state(diesel, rpm=1250.0, grid_deg=GRID)
    assert len(checks) == 1
    again = [rotor.steady_state(diesel, rpm=rpm, grid_deg=GRID) for rpm in (1250.0, 1500.0)]
    assert len(checks) == 1, "the same object is not checked again"
    np.testing.assert_array_equal(np.asarray(again[0].omega), np.asarray(first.omega))
    twin = eqx.tree_at(lambda e: e.operating.rpm, diesel, diesel.operating.rpm)  # a new object
    rotor.steady_state(twin, rpm=1250.0, grid_deg=GRID)
    assert len(checks) == 2 and checks[-1] is twin
    flywheel = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, diesel.crankshaft.inertia_kgm2 * 2)
    heavy = [rotor.steady_state(flywheel, rpm=1250.0, grid_deg=GRID) for _ in range(2)]
    assert len(checks) == 3
    np.testing.assert_array_equal(np.asarray(heavy[0].omega), np.asarray(heavy[1].omega))
    assert float(heavy[0].delta) < float(first.delta)
    broken = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, jnp.asarray(0.0))
    with pytest.raises(rotor.EngineError, match="inertia_kgm2"):
        rotor.steady_state(broken, rpm=1250.0, grid_deg=GRID)


def test_the_checked_engine_objects_are_few_and_not_kept_alive(diesel, monkeypatch):
    """The table cache remembers at most ``KNOWN_OBJECTS`` engine objects as checked, the
    most recently used (an older one is checked again), and remembering one never keeps it
    alive."""
    import gc
    import weakref

    ct.clear_table_cache()
    checks = []
    real = rotor.Engine.check
    monkeypatch.setattr(rotor.Engine, "check", lambda self: checks.append(self) or real(self))
    points = ct.grid_points(4, GRID)
    variants = [
        eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, diesel.crankshaft.inertia_kgm2 * (1 + 0.01 * i))
        for i in range(ct.KNOWN_OBJECTS + 5)
    ]
    trains = [ct.checked_train(v, "variable", points) for v in variants]
    assert len(checks) == len(variants)
    assert ct.checked_train(variants[-1], "variable", points) is trains[-1]
    assert len(checks) == len(variants), "a recent object is not checked again"
    ct.checked_train(variants[0], "variable", points)
    assert len(checks) == len(variants) + 1, "the oldest object was forgotten, so it is checked again"
    gone = weakref.ref(variants[-1])
    del variants, trains, checks[:]
    gc.collect()
    assert gone() is None, "the table cache keeps no engine alive"


def test_prepared_steady_state_is_the_engines(diesel, prepared):
    """The prepared engine gives the same steady state as the engine, bit for bit, and
    another crankshaft inertia the same as an engine built with it (1e-12)."""
    a = rotor.steady_state(diesel, grid_deg=GRID)
    b = rotor.steady_state(prepared)
    np.testing.assert_array_equal(np.asarray(a.omega), np.asarray(b.omega))
    assert float(a.load_torque_Nm) == float(b.load_torque_Nm)
    J = 2.5 * float(diesel.crankshaft.inertia_kgm2)
    c = rotor.steady_state(prepared.with_inertia(J), rpm=900.0)
    d = rotor.steady_state(
        eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, jnp.asarray(J)), 900.0, grid_deg=GRID
    )
    np.testing.assert_allclose(np.asarray(c.omega), np.asarray(d.omega), rtol=1e-12)
    assert float(c.delta) == pytest.approx(float(d.delta), rel=1e-10)
    with pytest.raises(rotor.EngineError, match="fidelity"):
        rotor.steady_sweep(prepared, fidelity="constant")


@pytest.mark.parametrize("fidelity", ["variable", "series", "coefficients", "constant"])
def test_the_crankshaft_inertia_is_a_constant_in_every_table(diesel, fidelity):
    """shift_inertia(tables at J1, J2 − J1) are the tables built at J2, at every fidelity."""
    J1 = diesel.crankshaft.inertia_kgm2
    other = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, J1 * 3.0)
    ct.clear_table_cache()
    t1 = train_from_engine(diesel, fidelity, 720)
    ct.clear_table_cache()
    t2 = train_from_engine(other, fidelity, 720)
    shifted = shift_inertia(t1, J1 * 2.0)
    np.testing.assert_allclose(np.asarray(shifted.values), np.asarray(t2.values), rtol=1e-13, atol=1e-9)
    np.testing.assert_allclose(np.asarray(shifted.slopes), np.asarray(t2.slopes), rtol=1e-13, atol=1e-9)
    assert float(shifted.mean_inertia) == pytest.approx(float(t2.mean_inertia), rel=1e-14)
    # and the cache hands out exactly that shift for the other inertia
    ct.clear_table_cache()
    train_from_engine(diesel, fidelity, 720)
    np.testing.assert_allclose(
        np.asarray(train_from_engine(other, fidelity, 720).values), np.asarray(t2.values), rtol=1e-13
    )


@pytest.mark.parametrize("fidelity", ["variable", "constant"])
def test_an_engines_tables_do_not_depend_on_what_came_before(diesel, fidelity, tmp_path, monkeypatch):
    """The tables of an engine are the same numbers, bit for bit, whether another crankshaft
    inertia of the same engine was computed before or not, and whether they were built in
    this process or read back from the table folder."""
    J1 = diesel.crankshaft.inertia_kgm2
    other = eqx.tree_at(lambda e: e.crankshaft.inertia_kgm2, diesel, J1 * 3.0 + 0.1)

    def tables(*engines, folder="off"):
        monkeypatch.setenv("ROTOR_TABLE_CACHE", folder)
        ct.clear_table_cache()
        out = [train_from_engine(e, fidelity, 720) for e in engines]
        return np.asarray(out[-1].values), float(out[-1].mean_inertia)

    alone = tables(other)
    for got in (
        tables(diesel, other),
        tables(other, folder=str(tmp_path)),
        tables(diesel, other, folder=str(tmp_path)),
    ):
        assert np.array_equal(got[0], alone[0]) and got[1] == alone[1]


def test_a_jitted_function_may_close_over_an_engine_not_seen_before(diesel, monkeypatch):
    """jax.jit(lambda rpm: steady_state(engine, rpm)) with the engine's tables not yet built
    anywhere: they are built as values (not inside the trace), kept, and the jitted steady
    state is the plain one."""
    monkeypatch.setenv("ROTOR_TABLE_CACHE", "off")
    ct.clear_table_cache()
    engine = eqx.tree_at(lambda e: e.geometry.bore_m, diesel, diesel.geometry.bore_m * 1.0137)
    jitted = float(jax.jit(lambda rpm: rotor.steady_state(engine, rpm).delta)(1250.0))
    assert jitted == pytest.approx(float(rotor.steady_state(engine, 1250.0).delta), rel=1e-12)


@pytest.mark.parametrize("batched", [False, True])
def test_an_engine_object_used_first_inside_a_trace_is_kept_as_values(diesel, monkeypatch, batched):
    """An engine object's tables found first inside ``jax.jit`` or ``jax.jit(jax.vmap(...))``
    (its crankshaft inertia added to the kept tables there), with no kept programs (whose
    compiled calls run eagerly inside a trace anyway): what is kept for the object are
    values, so that its next plain call finds them instead of a value of the finished trace."""
    monkeypatch.setenv("ROTOR_PROGRAM_CACHE", "off")
    engine = eqx.tree_at(lambda e: e.geometry.bore_m, diesel, diesel.geometry.bore_m * (1.0213 + 0.01 * batched))
    rpm = jnp.array([1000.0, 1250.0])
    delta = jax.vmap(lambda r: rotor.steady_state(engine, r).delta) if batched else None
    traced = (
        jax.jit(delta)(rpm) if batched else [jax.jit(lambda r: rotor.steady_state(engine, r).delta)(r) for r in rpm]
    )
    plain = [float(rotor.steady_state(engine, float(r)).delta) for r in rpm]
    np.testing.assert_allclose(np.asarray(traced), plain, rtol=1e-12)


def test_engines_that_differ_only_in_name_share_their_compiled_programs(diesel, monkeypatch):
    """The name is a static field of an engine; the functions compiled for an engine are
    traced once for every engine of the same structure, whatever its name."""
    monkeypatch.setenv("ROTOR_TABLE_CACHE", "off")
    traced = []

    def listen(event, seconds, fun_name="?", **_):
        if event.endswith("jaxpr_trace_duration"):
            traced.append(fun_name)

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        for name in ("a first name", "another name"):
            renamed = diesel.replace(name=name)
            traced.clear()
            ct.clear_table_cache()
            bore = eqx.tree_at(lambda e: e.geometry.bore_m, renamed, renamed.geometry.bore_m * 1.0213)
            torque = float(rotor.mean_gas_torque(bore))
            train_from_engine(bore, "variable", 720)
        assert torque == pytest.approx(float(rotor.mean_gas_torque(bore.replace(name="x"))), rel=1e-15)
        assert not {"mean_gas_torque", "_build"} & set(traced), traced
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)


def test_the_gradient_over_the_inertia_of_a_prepared_engine(diesel, prepared):
    """dδ/dJ through the prepared tables (the implicit Newton derivative) against a central difference."""
    J0 = float(diesel.crankshaft.inertia_kgm2)

    def delta(J):
        return rotor.steady_state(prepared.with_inertia(J)).delta

    g = float(jax.grad(delta)(J0))
    h = 1e-4 * J0
    fd = (float(delta(J0 + h)) - float(delta(J0 - h))) / (2 * h)
    assert g < 0
    assert g == pytest.approx(fd, rel=1e-6)


def test_a_sweep_is_the_steady_states_one_by_one(prepared):
    """Speed × inertia, per-cylinder fuelling and a carried load: each item of the sweep is
    the steady state of that item (δ to 1e-10, the balancing load and fuel scale to 1e-12)."""
    rpm = np.array([700.0, 1000.0, 1250.0, 1600.0, 2100.0])
    J = np.array([5.0, 8.0, 10.2, 14.0, 30.0])
    sw = rotor.steady_sweep(prepared, rpm=rpm, inertia_kgm2=J, chunk=2, progress=False)  # 3 chunks, the last padded
    assert sw.size == 5 and sw.chunk == 2 and np.all(sw.converged)
    for i in range(5):
        r = rotor.steady_state(prepared.with_inertia(J[i]), rpm[i])
        assert sw.delta[i] == pytest.approx(float(r.delta), rel=1e-10)
        assert sw.load_torque_Nm[i] == pytest.approx(float(r.load_torque_Nm), rel=1e-12)
        assert sw.textbook_delta[i] == pytest.approx(float(r.textbook_delta), rel=1e-10)
        assert sw.min_rpm[i] == pytest.approx(float(r.min_rpm), rel=1e-9)
        assert sw.max_rpm[i] == pytest.approx(float(r.max_rpm), rel=1e-9)
    scales = np.array([[1.0, 1.0, 1.0, 1.0], [1.0, 0.0, 1.0, 1.0], [1.1, 0.9, 1.0, 1.05]])
    loads = np.array([900.0, 700.0, 1000.0])
    sw = rotor.steady_sweep(prepared, imep_scale=scales, load_torque_Nm=loads, progress=False)
    assert sw.load_torque_Nm is None and sw.fuel_scale is not None
    for i in range(3):
        r = rotor.steady_state(prepared, load=rotor.ConstantLoad(loads[i]), imep_scale=scales[i])
        assert sw.delta[i] == pytest.approx(float(r.delta), rel=1e-10)
        assert sw.fuel_scale[i] == pytest.approx(float(r.fuel_scale), rel=1e-12)
    df = sw.to_pandas()
    assert list(df.columns[:5]) == ["rpm", "inertia_kgm2", "imep_scale_1", "imep_scale_2", "imep_scale_3"]


def test_a_sweep_with_speed_dependent_friction_solves_each_item_whole(diesel):
    """Friction with a speed-linear term leaves the flat closed form: each item is a whole
    steady state (shooting), and still equals the one-by-one solve."""
    fr = rotor.Friction(fmep_pa=40e3, fmep_per_speed_pa_s_per_m=2000.0)
    prepared = rotor.prepare(diesel, grid_deg=2.0)
    rpm = np.array([900.0, 1400.0])
    sw = rotor.steady_sweep(prepared, rpm=rpm, friction=fr, progress=False)
    for i in range(2):
        r = rotor.steady_state(prepared, rpm[i], friction=fr)
        assert sw.delta[i] == pytest.approx(float(r.delta), rel=1e-9)


def test_a_sweep_reports_items_without_a_steady_state_and_refuses_bad_input(prepared):
    sw = rotor.steady_sweep(prepared, rpm=[1250.0, 50.0], inertia_kgm2=[10.2, 0.01], progress=False)
    assert list(sw.converged) == [True, False]  # 50 rpm on 0.01 kg·m²: it stops once a cycle
    with pytest.raises(rotor.NoSteadyStateError):
        rotor.steady_state(prepared.with_inertia(0.01), 50.0)
    assert "1 items have no steady state" in sw.summary()
    for kwargs, match in (
        ({"rpm": [1000.0, 1100.0], "inertia_kgm2": [1.0, 2.0, 3.0]}, "one length"),
        ({"rpm": [1000.0, -5.0]}, r"rpm\[1\]"),
        ({"rpm": [1000.0, np.nan]}, r"rpm\[1\]"),
        ({"inertia_kgm2": [0.0]}, "positive"),
        ({"imep_scale": np.ones((2, 3))}, "imep_scale"),
        ({"chunk": 0}, "chunk"),
    ):
        with pytest.raises(rotor.EngineError, match=match):
            rotor.steady_sweep(prepared, progress=False, **kwargs)


def test_a_sweep_of_a_million_items_plans_bounded_chunks():
    """Chunks of at most MAX_CHUNK items, in equal calls, a multiple of the threads of
    them; every item is in one call."""
    from rotor.dynamics.sweep import MAX_CHUNK, default_chunk

    for n, workers in ((10**6, 2), (10**5, 2), (10**5, 16), (7, 2), (1, 4), (4097, 1)):
        size = default_chunk(n, workers)
        calls = -(-n // size)
        assert 1 <= size <= MAX_CHUNK and size * calls >= n
        assert size * calls - n < calls, (n, workers, size)  # equal calls: less than an item padded each
    assert default_chunk(10**5, 2) == 3847  # 25 calls of 4000 would leave a thread idle at the end: 26
    assert default_chunk(10**5, 1) == 4000


def test_the_first_estimate_of_the_mean_energy_is_of_fifth_order():
    """The flat closed form starts Newton from the mean-speed condition expanded to fourth
    order in the fluctuations of I and of the energy: doubling Ī + J halves both, so the
    estimate's error must fall 2⁵ = 32 times (the single cylinder: the largest fluctuation)."""
    import jax.numpy as jnp

    from rotor.dynamics.crank_train import COL_I
    from rotor.dynamics.steady import energy_moments, flat_balance, flat_energy, mean_energy_estimate

    train = rotor.prepare(rotor.load_engine("tue-single")).train
    beta, _, _ = flat_balance(train, jnp.ones(1), 0.0, "load")
    moments, beta_mean = energy_moments(train, beta)
    mean_i = float(jnp.mean(train.values[:, COL_I]))
    omega = 1500.0 / 9.549296585513721
    errors = []
    for factor in (2, 4, 8, 16):
        J = mean_i * (factor - 1)
        E0, ok, _ = flat_energy(train, J, beta, omega)
        assert bool(ok)
        estimate = mean_energy_estimate(moments, mean_i + J, omega) - beta_mean
        errors.append(abs(float(estimate / E0) - 1.0))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 28) & (ratios < 40)), ratios
