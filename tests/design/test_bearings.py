"""Bearing loads, wear diagrams and running torques (Shishkov (2014) §3.2.4–3.2.9): the
textbook hand check on 4ChN15/20.5, invariants that hold for any engine (virtual work,
the balance of forces and moments on the crankshaft), a V8 with two rods on a pin and
counterweights, articulated rods, the wear diagram's closed forms, and bad input."""

import json

import equinox as eqx
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np
import pytest

import rotor
from rotor.design.bearings import load_direction_rad, wear_indices
from rotor.engine.articulated import knuckle_velocity_sq
from rotor.engine.mechanism import slave_geometry
from rotor.engine.shaft import journal_positions_m, throw_positions_m, web_positions_m
from rotor.units import RAD_S_PER_RPM


@pytest.fixture(scope="module")
def e4():
    return rotor.load_engine("4chn15")


@pytest.fixture(scope="module")
def loads4(e4):
    return rotor.bearing_loads(e4)  # 1° step, 1250 rpm


total_torque = eqx.filter_jit(rotor.total_torque)  # compiled once per engine, not op by op


@pytest.fixture(scope="module")
def v8(e4):
    """The V8 with a throw mass of its own (m_rot − m₂ = 0.1 kg per rod) and three
    counterweights, so that every kind of force on the crankshaft is there; the pressure
    table of 4ChN15 (a table compiles in a fraction of the time of the Wiebe cycle)."""
    e = rotor.load_engine("v8")
    return e.replace(
        pressure=e4.pressure,
        masses=rotor.Masses(reciprocating_kg=0.85, rotating_kg=0.5, rod_big_end_kg=0.4),
        counterweights=rotor.Counterweights(
            webs=[1, 4, 8], mass_kg=[1.1, 0.4, 1.2], radius_m=[0.05, 0.045, 0.05], angle_deg=[198.4, 150.0, 18.4]
        ),
    )


@pytest.fixture(scope="module")
def loads8(v8):
    return rotor.bearing_loads(v8, step_deg=5.0)


R_A, L_A, L1_A = 0.05, 0.18, 0.14


def v2(r1=0.04, rod=L1_A, knuckle_kg=0.2, rotating=0.3, offset=0.003):
    """An articulated V2 (master 1, slave 2 at 60°), inertia forces only."""
    return rotor.Engine(
        name="articulated V2",
        strokes=4,
        cylinders=2,
        geometry=rotor.Geometry(bore_m=0.1, stroke_m=2 * R_A, rod_length_m=L_A, pin_offset_m=offset),
        masses=rotor.Masses(reciprocating_kg=0.6, rotating_kg=rotating),
        crankshaft=rotor.Crankshaft(inertia_kgm2=0.05),
        layout=rotor.Layout(throw_angles_deg=[0, 0], bank_angles_deg=[0, 60], firing_order=[1, 2]),
        articulated=rotor.Articulated(
            slaves=[2],
            masters=[1],
            knuckle_radius_m=r1,
            knuckle_angle_deg=55.0,
            rod_length_m=rod,
            rod_knuckle_kg=knuckle_kg,
        ),
    )


def omega(rpm):
    return rpm * RAD_S_PER_RPM


def block_vectors(t, z, psi):
    """Block-frame (x, y) of a force with textbook components t, z in a frame at angle psi."""
    return -t * np.sin(psi) - z * np.cos(psi), t * np.cos(psi) - z * np.sin(psi)


# ---------------------------------------------------------------- the textbook engine
crank_forces = eqx.filter_jit(rotor.crank_forces)  # one compile per cylinder, not op by op


@pytest.fixture(scope="module")
def forces1(e4):
    """Cylinder 1's textbook forces (the forces table's columns) at 0, 1, …, 719° and 1250 rpm,
    and S₂ = −m₂·R·ω²."""
    w = omega(1250.0)
    f = crank_forces(e4, jnp.deg2rad(jnp.arange(720.0)), w, 1)
    s2 = -float(e4.masses.big_end_kg(e4.geometry.rod_length_m)) * float(e4.geometry.crank_radius_m) * w**2
    return {k: np.asarray(v) for k, v in f.items()}, s2


def test_crank_pin_at_firing_tdc_is_the_hand_check(loads4, forces1):
    """At cylinder 1's firing TDC (360°) T = 0 and Z₁ = Z + S₂ from the forces table."""
    f, s2 = forces1
    z1 = float(f["z_N"][360]) + s2
    assert f["k_N"][360] == pytest.approx(f["psum_N"][360], rel=1e-12)  # the rod is along the cylinder
    i = int(np.flatnonzero(loads4.angle_deg == 360.0)[0])
    assert loads4.pin_z1_N[i, 0] == pytest.approx(z1, rel=1e-9)
    assert abs(loads4.pin_t_N[i, 0]) < 1e-9 * abs(z1)
    assert loads4.pin_q_N[i, 0] == pytest.approx(abs(z1), rel=1e-9)
    # at TDC the rod is along the crank: the big end sees the same load
    assert loads4.big_end_z_N[i, 0] == pytest.approx(z1, rel=1e-9)


def test_peak_crank_pin_load_is_stated(loads4, forces1):
    """The peak crank-pin load and its angle, from the forces table independently, are in the summary."""
    f, s2 = forces1
    q = np.hypot(f["t_N"], f["z_N"] + s2)
    i = int(np.argmax(q))
    assert np.allclose(loads4.pin_q_N[:, 0], q, rtol=1e-9, atol=1e-6)
    assert loads4.angle_deg[int(np.argmax(loads4.pin_q_N[:, 0]))] == i
    assert 360 < i < 400  # just after firing TDC, where the gas force peaks
    assert f"Q max {q[i] / 1e3:9.2f} kN at {float(i):5.1f}°" in loads4.summary()
    assert np.mean(loads4.pin_q_N[:, 0]) == pytest.approx(np.mean(q), rel=1e-9)


def test_torque_of_the_pins_is_the_total_torque(e4, loads4):
    """Virtual work: Σ over throws of T·R is rotor.total_torque at every angle; the last
    main journal passes it on, the first none."""
    theta = np.deg2rad(loads4.angle_deg)
    total = np.asarray(total_torque(e4, theta, omega(1250.0)))
    scale = np.max(np.abs(total))
    assert np.max(np.abs(loads4.pin_t_N.sum(axis=1) * loads4.crank_radius_m - total)) < 1e-9 * scale
    assert np.max(np.abs(loads4.running_torque_Nm[:, -1] - total)) < 1e-9 * scale
    assert np.all(loads4.running_torque_Nm[:, 0] == 0)
    # journal j passes on the throws 1…j−1 in front of it
    m = loads4.pin_t_N * loads4.crank_radius_m
    assert np.allclose(loads4.running_torque_Nm[:, 2], m[:, 0] + m[:, 1], rtol=0, atol=1e-9 * scale)


def check_journal_balance(engine, result):
    """Σ of the main journal loads equals Σ of the forces applied to the crankshaft, and
    so do their moments about journal 1, at every angle (block frame)."""
    R = result.crank_radius_m
    w = omega(result.rpm)
    theta = np.deg2rad(result.angle_deg)[:, None]
    throw_deg = np.array([float(engine.layout.throw_angles_deg[c[0] - 1]) for c in result.throw_cylinders])
    psi = theta - np.deg2rad(throw_deg)[None, :]
    fx, fy = block_vectors(result.pin_t_N, result.pin_z1_N, psi)
    m_rec, m_rot = engine.masses.two_mass_split(engine.geometry.rod_length_m)
    m2 = float(engine.masses.big_end_kg(engine.geometry.rod_length_m))
    slaves = engine.slave_index()
    own = np.array([sum(1 for c in cyl if c - 1 not in slaves) for cyl in result.throw_cylinders])
    unb = (float(m_rot) - m2) * own * R * w**2
    fx, fy = fx + unb * np.cos(psi), fy + unb * np.sin(psi)
    x = np.asarray(throw_positions_m(engine))
    forces = [(fx, fy, x)]
    cw = engine.counterweights
    if cw is not None:
        webs = np.asarray(cw.webs) - 1
        c = np.asarray(cw.mass_kg) * np.asarray(cw.radius_m) * w**2
        ang = psi[:, webs // 2] + np.deg2rad(np.asarray(cw.angle_deg))
        forces.append((c * np.cos(ang), c * np.sin(ang), np.asarray(web_positions_m(engine))[webs]))
    ax = sum(f[0].sum(axis=1) for f in forces)
    ay = sum(f[1].sum(axis=1) for f in forces)
    mx = sum((f[0] * f[2]).sum(axis=1) for f in forces)
    my = sum((f[1] * f[2]).sum(axis=1) for f in forces)
    jx, jy = -result.bearing_z_N, result.bearing_t_N
    xj = np.asarray(journal_positions_m(engine))
    scale = max(np.max(np.hypot(ax, ay)), np.max(result.journal_q_N))
    assert np.max(np.abs(jx.sum(axis=1) - ax)) < 1e-9 * scale
    assert np.max(np.abs(jy.sum(axis=1) - ay)) < 1e-9 * scale
    assert np.max(np.abs(jx @ xj - mx)) < 1e-9 * scale * xj[-1]
    assert np.max(np.abs(jy @ xj - my)) < 1e-9 * scale * xj[-1]
    # the shaft frame is the block frame turned to the journal's throw
    ref = psi[:, np.asarray(result.journal_frame_throw) - 1]
    bx, by = block_vectors(result.journal_t_N, result.journal_z_N, ref)
    assert np.allclose(bx, jx, rtol=0, atol=1e-9 * scale) and np.allclose(by, jy, rtol=0, atol=1e-9 * scale)


def test_main_journals_carry_the_forces_on_the_crankshaft(e4, loads4):
    check_journal_balance(e4, loads4)
    # the inline four is symmetric: journal 1 mirrors journal 5, 2 mirrors 4
    q = loads4.journal_q_N
    assert np.max(q[:, 0]) == pytest.approx(np.max(q[:, 4]), rel=1e-9)
    assert np.max(q[:, 1]) == pytest.approx(np.max(q[:, 3]), rel=1e-9)
    assert loads4.journal_frame_throw == (1, 1, 2, 3, 4)


# ---------------------------------------------------------------- V8
def test_v8_pins_carry_two_rods_and_balance(v8, loads8):
    w = omega(3000.0)
    theta = np.deg2rad(loads8.angle_deg)
    R = loads8.crank_radius_m
    s2 = -0.4 * R * w**2
    for k, (a, b) in enumerate(loads8.throw_cylinders[:2]):
        fa, fb = (rotor.crank_forces(v8, theta, w, c) for c in (a, b))
        assert np.allclose(loads8.pin_t_N[:, k], np.asarray(fa["t_N"]) + np.asarray(fb["t_N"]), rtol=1e-9, atol=1e-6)
        z1 = np.asarray(fa["z_N"]) + np.asarray(fb["z_N"]) + 2 * s2
        assert np.allclose(loads8.pin_z1_N[:, k], z1, rtol=1e-9, atol=1e-6)
    total = np.asarray(total_torque(v8, theta, w))
    assert np.max(np.abs(loads8.pin_t_N.sum(axis=1) * R - total)) < 1e-9 * np.max(np.abs(total))
    assert np.max(np.abs(loads8.running_torque_Nm[:, -1] - total)) < 1e-9 * np.max(np.abs(total))
    check_journal_balance(v8, loads8)


def test_v8_big_ends_turned_back_add_up_to_the_pin(v8, loads8):
    """Each rod's big-end load, turned back by −(φ + β) into the throw frame, adds up to its pin's."""
    alpha = np.asarray(v8.mechanical_angles(jnp.asarray(np.deg2rad(loads8.angle_deg))))
    g = v8.geometry
    delta = alpha + np.arcsin(float(g.crank_radius_m) * np.sin(alpha) / float(g.rod_length_m))
    t = loads8.big_end_t_N * np.cos(delta) + loads8.big_end_z_N * np.sin(delta)
    z = loads8.big_end_z_N * np.cos(delta) - loads8.big_end_t_N * np.sin(delta)
    assert loads8.big_end_cylinders == tuple(range(1, 9))
    for k, (a, b) in enumerate(loads8.throw_cylinders):
        assert np.allclose(t[:, a - 1] + t[:, b - 1], loads8.pin_t_N[:, k], rtol=1e-9, atol=1e-6)
        assert np.allclose(z[:, a - 1] + z[:, b - 1], loads8.pin_z1_N[:, k], rtol=1e-9, atol=1e-6)
    assert np.allclose(np.hypot(t, z), loads8.big_end_q_N, rtol=1e-12)


# ---------------------------------------------------------------- articulated rods
def test_articulated_pin_torque_is_the_total_torque_by_virtual_work():
    e = v2(knuckle_kg=0.0)
    r = rotor.bearing_loads(e, 3000.0, step_deg=5.0)
    theta = np.deg2rad(r.angle_deg)
    total = np.asarray(total_torque(e, theta, omega(3000.0)))
    assert r.throw_cylinders == ((1, 2),) and r.big_end_cylinders == (1,)
    assert np.max(np.abs(r.pin_t_N[:, 0] * R_A - total)) < 1e-9 * np.max(np.abs(total))
    check_journal_balance(e, r)
    with pytest.raises(rotor.EngineError, match="slave"):
        r.plot_big_end(cylinder=2)
    plt.close("all")


def test_articulated_knuckle_mass_adds_its_inertia_torque():
    """With a knuckle mass m_k the pins also carry its inertia torque −½·m_k·ω²·d|dK/dα|²/dα."""
    e = v2(knuckle_kg=0.2)
    w = omega(3000.0)
    r = rotor.bearing_loads(e, 3000.0, step_deg=5.0)
    theta = np.deg2rad(r.angle_deg)
    sg = slave_geometry(e, 1, 0)
    a_master = np.asarray(e.mechanical_angles(jnp.asarray(theta)))[:, 0]
    h = 1e-5
    dv2 = (np.asarray(knuckle_velocity_sq(a_master + h, sg)) - np.asarray(knuckle_velocity_sq(a_master - h, sg))) / (
        2 * h
    )
    expected = np.asarray(total_torque(e, theta, w)) - 0.5 * 0.2 * w**2 * dv2
    assert np.max(np.abs(r.pin_t_N[:, 0] * R_A - expected)) < 1e-6 * np.max(np.abs(expected))


def test_slave_on_the_crank_pin_is_a_second_rod_on_it():
    """r₁ = 0, l₁ = L (central pins): the slave rod pulls on the crank pin itself, as a
    second rod would."""
    art = rotor.bearing_loads(v2(r1=0.0, rod=L_A, knuckle_kg=0.0, rotating=0.0, offset=0.0), 3000.0, step_deg=5.0)
    plain_engine = rotor.Engine(
        name="V2 on one pin",
        strokes=4,
        cylinders=2,
        geometry=rotor.Geometry(bore_m=0.1, stroke_m=2 * R_A, rod_length_m=L_A),
        masses=rotor.Masses(reciprocating_kg=0.6, rotating_kg=0.0),
        crankshaft=rotor.Crankshaft(inertia_kgm2=0.05, throws=[1, 1]),
        layout=rotor.Layout(throw_angles_deg=[0, 0], bank_angles_deg=[0, 60], firing_order=[1, 2]),
    )
    plain = rotor.bearing_loads(plain_engine, 3000.0, step_deg=5.0)
    scale = np.max(plain.pin_q_N)
    assert np.allclose(art.pin_t_N, plain.pin_t_N, rtol=0, atol=1e-9 * scale)
    assert np.allclose(art.pin_z1_N, plain.pin_z1_N, rtol=0, atol=1e-9 * scale)


# ---------------------------------------------------------------- wear diagram
def test_wear_of_a_constant_load_in_one_direction():
    """A constant load along ray 3 acts on rays 1…5 (±60°) in full and on no other."""
    d = np.full(10, np.deg2rad(90.0))
    w = wear_indices(d, np.full(10, 5.0), 12, 60.0)
    assert np.array_equal(np.flatnonzero(w), [1, 2, 3, 4, 5])
    assert np.allclose(w[[1, 2, 3, 4, 5]], 5.0)
    # a narrower sector: only the nearest ray
    w = wear_indices(np.full(3, np.deg2rad(95.0)), np.full(3, 2.0), 12, 20.0)
    assert np.array_equal(np.flatnonzero(w), [3]) and w[3] == 2.0


def test_wear_of_a_load_turning_uniformly():
    """A constant load turning once at 1° steps gives every ray (2·60 + 1)/360 of it."""
    d = np.deg2rad(np.arange(360.0))
    w = wear_indices(d, np.full(360, 7.0), 12, 60.0)
    assert np.allclose(w, 7.0 * 121 / 360, rtol=1e-12)


def test_wear_of_the_crank_pin_follows_its_load(loads4):
    q, d = loads4.pin_q_N[:, 0], load_direction_rad(loads4.pin_t_N[:, 0], loads4.pin_z1_N[:, 0])
    brute = []
    for ray in np.deg2rad(loads4.ray_angles_deg):
        diff = np.abs((np.rad2deg(d - ray) + 180) % 360 - 180)
        brute.append(np.sum(q[diff <= 60 + 1e-9]) / len(q))
    assert np.allclose(loads4.pin_wear_N[0], brute, rtol=1e-12)
    assert loads4.pin_oil_hole_deg(1) == loads4.ray_angles_deg[int(np.argmin(brute))]
    # textbook direction: a load pushing the pin towards the crank axis points along ray 6 (180°)
    assert np.rad2deg(load_direction_rad(0.0, 1.0)) == pytest.approx(180.0)
    assert np.rad2deg(load_direction_rad(1.0, 0.0)) == pytest.approx(90.0)


# ---------------------------------------------------------------- result, plots, errors
def test_json_is_modest_and_plots_return_axes(loads4):
    d = loads4.to_json_dict()
    text = json.dumps(d, allow_nan=False)
    assert len(text) < 200_000
    assert d["worst_journal"] == loads4.worst_journal and len(d["journals"]) == 5
    assert d["throws"][0]["max_N"] == pytest.approx(float(np.max(loads4.pin_q_N[:, 0])))
    df = loads4.to_pandas()
    assert {"angle_deg", "element", "number", "t_N", "z_N", "q_N", "running_torque_Nm"} <= set(df.columns)
    assert len(df) == 720 * (4 + 4 + 5 + 5)
    assert loads4.wear_to_pandas()["oil_hole"].sum() == 4 + 5
    try:
        ax = loads4.plot_crank_pin(throw=2)
        assert ax.yaxis_inverted() and hasattr(ax, "figure")
        for axis in (
            loads4.plot_big_end(cylinder=3),
            loads4.plot_developed(throw=4),
            loads4.plot_wear(throw=1),
            loads4.plot_wear(journal=3),
            loads4.plot_main_journal(),
            loads4.plot_main_bearing(journal=2),
            loads4.plot_running_torques(),
        ):
            assert hasattr(axis, "figure")
        with pytest.raises(rotor.EngineError, match="throw 5 does not exist"):
            loads4.plot_crank_pin(throw=5)
        with pytest.raises(rotor.EngineError, match="journal 6 does not exist"):
            loads4.plot_main_journal(journal=6)
    finally:
        plt.close("all")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"step_deg": 7.0}, r"bearing_loads\(step_deg\) = 7: must divide the 720° cycle"),
        ({"step_deg": 0.0}, r"bearing_loads\(step_deg\)"),
        ({"step_deg": float("nan")}, r"bearing_loads\(step_deg\)"),
        ({"rays": 2}, r"bearing_loads\(rays\) = 2: must be 3 or more"),
        ({"sector_deg": 0.0}, r"bearing_loads\(sector_deg\)"),
        ({"sector_deg": 181.0}, r"bearing_loads\(sector_deg\)"),
        ({"rpm": -100.0}, r"bearing_loads\(rpm\)"),
        ({"rpm": 1e9}, r"bearing_loads\(rpm\)"),
        ({"model": "textbook"}, r"bearing_loads\(model\)"),
    ],
)
def test_bad_input_is_one_line(e4, kwargs, match):
    with pytest.raises(rotor.EngineError, match=match) as info:
        rotor.bearing_loads(e4, **kwargs)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "call",
    [
        lambda e: rotor.bearing_loads("4chn15"),
        lambda e: rotor.bearing_loads(e, rpm="fast"),
        lambda e: rotor.bearing_loads(e, step_deg="1"),
        lambda e: rotor.bearing_loads(e, rays=12.0),
        lambda e: rotor.bearing_loads(e, model=1),
    ],
)
def test_wrong_type_names_the_call(e4, call):
    with pytest.raises(TypeError, match="bearing_loads"):
        call(e4)
