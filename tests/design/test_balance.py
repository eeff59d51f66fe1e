"""Balancing (rotor.balance): free forces and moments by order against closed forms
(Shishkov, "Dinamika dvigatelei", SUSU 2014, §3.2.10; Kolchin & Demidov, "Design of
automotive engines"), to 1e-9 of the engine's scale or tighter."""

import math
from math import comb

import numpy as np
import pytest

import rotor

R, L = 0.04, 0.14  # crank radius, rod [m]: lambda = 0.2857
LAM = R / L
M_REC, M_ROT = 0.5, 0.3  # per cylinder [kg]
RPM = 3000.0
W2 = (RPM * math.pi / 30) ** 2
TOL = 1e-9


def engine(throws, banks=None, firing=None, shaft=None, counterweights=None, **extra):
    n = len(throws)
    data = {
        "name": "test",
        "strokes": 4,
        "cylinders": n,
        "geometry": {"bore_m": 0.08, "stroke_m": 2 * R, "rod_length_m": L},
        "masses": {"reciprocating_kg": M_REC, "rotating_kg": M_ROT},
        "crankshaft": {"inertia_kgm2": 0.1, **(shaft or {})},
        "layout": {
            "throw_angles_deg": throws,
            "bank_angles_deg": banks or [0] * n,
            "firing_order": firing or list(range(1, n + 1)),
        },
        "operating": {"rpm": RPM},
        **extra,
    }
    if counterweights:
        data["counterweights"] = counterweights
    return rotor.engine_from_dict(data)


def zero(b, quantity, source, orders):
    """The ellipses of ``orders`` vanish to 1e-9 of the engine's scale."""
    scale = b.force_scale_N if quantity == "force" else b.moment_scale_Nm
    values = b.ellipse(quantity, source)["largest"][np.asarray(orders) - 1]
    return bool(np.all(values <= TOL * scale))


def exact_harmonic(j):
    """The coefficient of cos(2j·α) in d²s/dα² of the exact central slider crank [m/rad²],
    from the binomial series of √(1 − λ²sin²α) and the Fourier series of sin^{2n}α:
    s = R(1 − cos α) + L·Σ a_n λ^{2n} sin^{2n}α, a_n = (2n)!/((2n − 1)(n!)²4ⁿ), and
    sin^{2n}α has 2(−1)^j·C(2n, n − j)/4ⁿ of cos 2jα; differentiating twice multiplies by −(2j)²."""
    total = 0.0
    for n in range(j, 60):
        a_n = math.factorial(2 * n) / ((2 * n - 1) * math.factorial(n) ** 2 * 4**n)
        total += a_n * LAM ** (2 * n) * 2 * (-1) ** j * comb(2 * n, n - j) / 4**n
    return -((2 * j) ** 2) * L * total


FOUR = dict(throws=[0, 180, 180, 0], firing=[1, 3, 4, 2])


def test_inline_four_series_second_order_is_4_m_R_w2_lambda():
    b = rotor.balance(engine(**FOUR), model="series")
    assert b.free_force_N()[1] == pytest.approx(4 * M_REC * R * W2 * LAM, rel=1e-12)
    e = b.ellipse("force")
    assert e["direction_deg"][1] == pytest.approx(0.0, abs=1e-9)  # along the cylinders
    assert e["horizontal"][1] <= TOL * b.force_scale_N
    assert zero(b, "force", "total", [1, 3, 4, 5, 6])
    assert zero(b, "moment", "total", range(1, 7))
    holds = {c["symbol"]: c["holds"] for c in b.conditions}
    assert holds == {
        "sum P_j1 = 0": True,
        "sum P_j2 = 0": False,
        "sum P_c = 0": True,
        "M_1 = 0": True,
        "M_2 = 0": True,
        "M_c = 0": True,
    }
    # a Lanchester pair at 2ω: each shaft half the force, U = F/2/(2ω)²
    shafts = {(s["order"], s["turning"]): s for s in b.balance_shafts}
    for turning in ("forward", "backward"):
        assert shafts[(2, turning)]["force_unbalance_kgm"] == pytest.approx(M_REC * R * LAM / 2, rel=1e-12)
        assert shafts[(2, turning)]["force_angle_deg"] == pytest.approx(180.0)


def test_inline_four_exact_harmonics_follow_the_series_of_the_exact_slider_crank():
    b = rotor.balance(engine(**FOUR), orders=6)
    f = b.free_force_N()
    # R·λ(1 + λ²/4 + 15λ⁴/128 + 35λ⁶/512 + …) for order 2, summed independently to 60 terms
    assert f[1] == pytest.approx(4 * M_REC * W2 * abs(exact_harmonic(1)), rel=1e-12)
    series = R * LAM * (1 + LAM**2 / 4 + 15 * LAM**4 / 128 + 35 * LAM**6 / 512)
    assert exact_harmonic(1) == pytest.approx(series, rel=1e-5)  # the next term is 2e-6
    assert f[1] > 4 * M_REC * R * W2 * LAM * (1 + LAM**2 / 4)  # more than the textbook's λ
    assert f[3] == pytest.approx(4 * M_REC * W2 * abs(exact_harmonic(2)), rel=1e-10)
    assert f[5] == pytest.approx(4 * M_REC * W2 * abs(exact_harmonic(3)), rel=1e-8)
    assert zero(b, "force", "total", [1, 3, 5])
    assert zero(b, "moment", "total", range(1, 7))


def test_inline_six_has_no_free_force_or_moment_at_orders_1_and_2():
    b = rotor.balance(engine([0, 120, 240, 240, 120, 0], firing=[1, 5, 3, 6, 2, 4]))
    for q in ("force", "moment"):
        assert zero(b, q, "total", [1, 2])
    assert all(c["holds"] for c in b.conditions)
    # but its sixth order is free: 6·m·ω²·|s''₆| (the test can fail)
    assert b.free_force_N()[5] == pytest.approx(6 * M_REC * W2 * abs(exact_harmonic(3)), rel=1e-8)


def test_single_cylinder_first_order():
    b = rotor.balance(engine([0]))
    rec = b.ellipse("force", "reciprocating")
    assert rec["largest"][0] == pytest.approx(M_REC * R * W2, rel=1e-12)
    assert rec["smallest"][0] <= TOL * b.force_scale_N  # a line along the cylinder
    assert b.free_force_N("rotating")[0] == pytest.approx(M_ROT * R * W2, rel=1e-12)
    total = b.ellipse("force")
    assert total["largest"][0] == pytest.approx((M_REC + M_ROT) * R * W2, rel=1e-12)
    assert total["forward"][0] == pytest.approx((M_REC / 2 + M_ROT) * R * W2, rel=1e-12)
    assert total["backward"][0] == pytest.approx(M_REC / 2 * R * W2, rel=1e-12)
    # the usual compromise: the rotating mass and half the reciprocating one balanced,
    # split over both webs (m·r = (m_rot + m_rec/2)·R) -> a backward vector of m_rec/2·R·ω²
    half = (M_ROT + M_REC / 2) * R / 2
    cws = [{"web": w, "mass_kg": half / 0.03, "radius_m": 0.03} for w in (1, 2)]
    b = rotor.balance(engine([0], counterweights=cws))
    e = b.ellipse("force")
    assert e["forward"][0] <= TOL * b.force_scale_N
    assert e["backward"][0] == pytest.approx(M_REC / 2 * R * W2, rel=1e-12)
    assert zero(b, "moment", "total", [1])
    back = [s for s in b.balance_shafts if s["order"] == 1 and s["turning"] == "backward"][0]
    assert back["force_unbalance_kgm"] == pytest.approx(M_REC * R / 2, rel=1e-12)


def test_v_twin_90_first_order_turns_with_the_crank_and_a_counterweight_balances_it():
    twin = dict(throws=[0, 0], banks=[-45, 45], shaft={"throws": [1, 1]})
    b = rotor.balance(engine(**twin))
    rec = b.ellipse("force", "reciprocating")
    assert rec["forward"][0] == pytest.approx(M_REC * R * W2, rel=1e-12)  # constant m·R·ω² turning
    assert rec["backward"][0] <= TOL * b.force_scale_N
    assert rec["smallest"][0] == pytest.approx(rec["largest"][0], rel=1e-12)
    # the stated size: m_cw·r = (m_rec + 2·m_rot)·R at 180°, half on each web of the throw
    size = (M_REC + 2 * M_ROT) * R
    cws = [{"web": w, "mass_kg": size / 2 / 0.035, "radius_m": 0.035, "angle_deg": 180} for w in (1, 2)]
    b = rotor.balance(engine(**twin, counterweights=cws))
    assert zero(b, "force", "total", [1]) and zero(b, "moment", "total", [1])
    assert not zero(b, "force", "without_counterweights", [1])
    assert [c["holds"] for c in b.conditions if c["symbol"] in ("sum P_1 = 0", "M_1,all = 0")] == [True, True]
    # the whole of it on one web: the force is balanced, a couple remains (web ± a quarter part)
    one = [{"web": 1, "mass_kg": size / 0.035, "radius_m": 0.035}]
    b = rotor.balance(engine(**twin, counterweights=one))
    assert zero(b, "force", "total", [1])
    arm = 1.25 * 0.08 / 4  # default journal spacing 1.25 bores, the web a quarter of it from the pin
    assert b.free_moment_Nm()[0] == pytest.approx(size * W2 * arm, rel=1e-12)


V8 = dict(
    throws=[0, 270, 90, 180, 0, 270, 90, 180],
    banks=[-45] * 4 + [45] * 4,
    firing=[1, 5, 4, 8, 6, 3, 7, 2],
    shaft={"throws": [1, 2, 3, 4, 1, 2, 3, 4], "main_journals": 5, "journal_spacing_m": 0.1},
)


def test_cross_plane_v8_primary_couple_balanced_by_end_counterweights():
    a, u = 0.1, (M_REC + 2 * M_ROT) * R  # journal spacing [m]; per throw m·r turning with it
    b = rotor.balance(engine(**V8))
    assert zero(b, "force", "total", [1, 2])
    assert zero(b, "moment", "total", [2])
    couple = b.ellipse("moment")
    # the classic rotating couple √10·u·a·ω², forward, 18.43° past throw 1's plane
    assert couple["forward"][0] == pytest.approx(math.sqrt(10) * u * a * W2, rel=1e-12)
    assert couple["backward"][0] <= TOL * b.moment_scale_Nm
    assert couple["forward_angle_deg"][0] == pytest.approx(180 + math.degrees(math.atan(1 / 3)), abs=1e-9)
    # counterweights on the end webs (1.75·a from the middle): √10/3.5·u each, 180° + atan(1/3) from their throws
    angle = 180 + math.degrees(math.atan(1 / 3))
    size = math.sqrt(10) / 3.5 * u
    cws = [{"web": w, "mass_kg": size / 0.05, "radius_m": 0.05, "angle_deg": angle} for w in (1, 8)]
    b = rotor.balance(engine(**V8, counterweights=cws))
    for q in ("force", "moment"):
        assert zero(b, q, "total", [1, 2])
    assert b.free_force_N()[3] > 1e-3 * b.force_scale_N  # its fourth order stays free


def test_radial_first_order_is_half_the_cylinders_turning_with_the_crank():
    """Five cylinders on one pin, slaves with r1 = 0 (ordinary mechanisms): the first
    order is (n/2)·m_rec·R·ω² turning forward, the second order cancels."""
    art = {
        "slaves": [2, 3, 4, 5],
        "masters": [1, 1, 1, 1],
        "knuckle_radius_m": 0.0,
        "knuckle_angle_deg": 0.0,
        "rod_length_m": L,
    }
    b = rotor.balance(engine([0] * 5, banks=[0, 72, 144, 216, 288], firing=[1, 3, 5, 2, 4], articulated=art))
    rec = b.ellipse("force", "reciprocating")
    assert rec["forward"][0] == pytest.approx(2.5 * M_REC * R * W2, rel=1e-12)
    assert rec["backward"][0] <= TOL * b.force_scale_N
    assert zero(b, "force", "reciprocating", [2])
    assert b.free_force_N("rotating")[0] == pytest.approx(M_ROT * R * W2, rel=1e-12)  # the master's only


def test_knuckle_mass_force_against_finite_differences_of_its_path():
    r1, gamma, mk, bank = 0.05, 60.0, 0.2, 60.0
    art = {
        "slaves": [2],
        "masters": [1],
        "knuckle_radius_m": r1,
        "knuckle_angle_deg": gamma,
        "rod_length_m": 0.11,
    }
    e0 = engine([0, 0], banks=[0, bank], articulated=art)
    e1 = engine([0, 0], banks=[0, bank], articulated={**art, "rod_knuckle_kg": mk})
    f = rotor.balance(e1, orders=3).force["rotating"] - rotor.balance(e0, orders=3).force["rotating"]
    # the knuckle pin's path, written again here; −m·a by central differences (h = 1e-3 rad)
    n, h = 256, 1e-3
    th = 2 * np.pi * np.arange(n) / n

    def path(a):
        beta = np.arcsin(R * np.sin(a) / L)
        return R * np.exp(1j * a) + r1 * np.exp(1j * (np.deg2rad(gamma) - beta))

    acc = (path(th + h) - 2 * path(th) + path(th - h)) / h**2 * W2
    spec = np.fft.fft(-mk * acc) / n
    for k in (1, 2, 3):
        assert f[k - 1, 0] == pytest.approx(spec[k], rel=1e-6, abs=1e-3)
        assert f[k - 1, 1] == pytest.approx(spec[n - k], rel=1e-6, abs=1e-3)


def test_presets_balance_and_counterweights():
    for name in ("mwm6", "v8"):
        b = rotor.balance(rotor.load_engine(name), orders=2)
        d = b.to_json_dict()
        assert [o["order"] for o in d["orders"]] == [1, 2]
        assert b.has_counterweights
        assert zero(b, "force", "total", [1])
    # the V8's counterweights (rounded to the gram) take its primary couple to below 1e-4
    first = d["orders"][0]
    assert first["free_moment_Nm"] < 1e-4 * first["free_moment_without_counterweights_Nm"]


def test_counterweight_on_a_web_that_does_not_exist():
    with pytest.raises(rotor.EngineError) as err:
        engine([0], counterweights=[{"web": 3, "mass_kg": 0.1, "radius_m": 0.03}])
    msg = str(err.value)
    assert "web 3 does not exist" in msg and "\n" not in msg


@pytest.mark.parametrize(
    "kwargs,error,match",
    [
        (dict(orders=0), rotor.EngineError, "orders"),
        (dict(orders=65), rotor.EngineError, "orders"),
        (dict(orders=2.0), TypeError, "orders"),
        (dict(model="lambda"), rotor.EngineError, "model"),
        (dict(rpm=-5.0), rotor.EngineError, "rpm"),
    ],
)
def test_bad_arguments(kwargs, error, match):
    with pytest.raises(error, match=match):
        rotor.balance(engine([0]), **kwargs)
