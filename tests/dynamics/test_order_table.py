"""The steady state's order table: one column per distinct torque quantity."""

import pytest

import rotor


@pytest.fixture(scope="module")
def diesel():
    return rotor.load_engine("4chn15")


def test_equal_reciprocating_and_inertia_term_columns_are_one(diesel):
    r = rotor.steady_state(diesel)
    o = r.orders(max_order=6.0)
    # the two parts are the same amplitudes where I(θ) carries the reciprocating inertia
    assert o.reciprocating_torque_amplitude_Nm == pytest.approx(o.inertia_term_amplitude_Nm, rel=1e-9, abs=1e-9)
    for text in (r.summary(), o.summary()):
        assert "recip.=I′ω²/2" in text
        assert "−I′ω²/2 [N·m]" not in text
        header = next(line for line in text.splitlines() if "order  speed amplitude" in line)
        assert header.count("[N·m]") == 2 and "recip.=I′ω²/2" in header  # gas, one for both, total


def test_distinct_columns_stay_apart(diesel):
    r = rotor.steady_state(diesel, fidelity="constant")  # the inertia term is zero here, the torque holds it
    header = next(line for line in r.summary().splitlines() if "order  speed amplitude" in line)
    assert "recip. [N·m]" in header and "−I′ω²/2 [N·m]" in header


def test_print_engine_shows_its_numbers(diesel):
    text = repr(diesel)
    assert "f64[" not in text
    assert "bore_m=0.1497" in text and "inertia_kgm2=10.2" in text
    assert "(72 values)" in text  # a long table: its first values and its length
