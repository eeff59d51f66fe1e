"""One operating-point language: a load is a torque the engine carries, the fuelling is given
or solved, and every output says which; torques that say what they are."""

import json
import warnings

import numpy as np
import pytest
from conftest import run_cli

import rotor
from rotor import cli
from rotor.dynamics.operating import FuelScaleWarning, check_fuel_scale


# ----------------------------------------------------------------------------- the load and the fuel scale
def test_steady_json_carries_the_load_and_the_solved_fuel_scale(capsys):
    code, out, err = run_cli(capsys, "steady", "4chn15", "--load", "500", "--json")
    s = json.loads(out)
    assert code == 0 and err == ""
    assert s["load_torque_Nm"] == pytest.approx(500.0)
    assert s["fuel_scale"] == pytest.approx(0.4485, abs=1e-4) and s["solved_for"] == "fuel_scale"


def test_steady_solves_the_load_at_a_given_fuel_scale(capsys):
    code, out, _ = run_cli(capsys, "steady", "4chn15", "--fuel-scale", "0.5", "--json")
    s = json.loads(out)
    assert code == 0 and s["solved_for"] == "load" and s["fuel_scale"] == 0.5
    # IMEP is affine in the fuel scale, so is the load carried (no friction in this engine file)
    full = rotor.steady_state(rotor.load_engine("4chn15"))
    assert 0.3 * float(full.load_torque_Nm) < s["load_torque_Nm"] < 0.6 * float(full.load_torque_Nm)
    code, _, err = run_cli(capsys, "steady", "4chn15", "--fuel-scale", "0.5", "--load", "300")
    assert code == 2 and err.startswith("rotor: error:") and "give one" in err and err.count("\n") == 1


def test_a_heavy_load_warns_once_naming_the_imep(capsys):
    code, out, err = run_cli(capsys, "steady", "4chn15", "--load", "3000")
    assert code == 0
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rotor: warning:")
    assert "×2.63" in lines[0] and "IMEP 26.1 bar" in lines[0]
    assert ".py" not in err and "Warning" not in err  # no source path, no Python category
    assert "3000.00 N·m (given)" in out and "2.6302" in out


def test_an_absurd_load_or_fuel_scale_is_refused(capsys):
    code, _, err = run_cli(capsys, "steady", "4chn15", "--load", "50000")
    assert code == 2 and "×43.6" in err and "units" in err and err.count("\n") == 1
    for bad in ("11", "-0.5"):
        code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--fuel-scale", bad)
        assert code == 2 and "fuel scale lies in 0 … 10" in err


def test_simulate_keeps_the_fuel_unless_told(capsys):
    code, out, _ = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--load", "500", "--json")
    s = json.loads(out)
    assert code == 0 and s["fuel_scale"] == 1.0 and s["load_torque_Nm"] == 500.0 and s["solved_for"] is None
    code, out, _ = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--load", "500", "--balance", "--json")
    s = json.loads(out)
    assert s["fuel_scale"] == pytest.approx(0.4485, abs=1e-4) and s["solved_for"] == "fuel_scale"
    assert s["mean_rpm"] == pytest.approx(1250.0, abs=5.0)  # it holds its speed
    code, out, _ = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--load", "500", "--balance")
    assert "500.00 N·m (given)" in out and "0.4485" in out and "(solved: the fuelling" in out
    code, _, err = run_cli(capsys, "simulate", "4chn15", "--cycles", "2", "--balance")
    assert code == 2 and "give a --load" in err
    code, _, err = run_cli(
        capsys, "simulate", "4chn15", "--cycles", "2", "--load", "500", "--balance", "--fuel-scale", "1"
    )
    assert code == 2 and "not both" in err


def test_simulate_help_says_what_no_load_means(capsys):
    with pytest.raises(SystemExit):
        cli.main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default none)" not in text and "balancing the mean engine torque at the start speed" in text
    assert "--fuel-scale" in text and "--balance" in text


def test_python_steady_state_names_what_was_solved(diesel):
    ss = rotor.steady_state(diesel, load=rotor.PropellerLoad(500.0, 1250.0))
    assert ss.solved_for == "fuel_scale" and float(ss.load_torque_Nm) == pytest.approx(500.0, rel=2e-3)
    with pytest.warns(FuelScaleWarning, match="IMEP"):
        rotor.steady_state(diesel, imep_scale=1.5)
    with pytest.raises(rotor.EngineError, match="not an operating point"):
        rotor.steady_state(diesel, load=rotor.ConstantLoad(50000.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_fuel_scale(1.2, [1e5], [9e5], solved=False)  # at the limit: no warning


# ----------------------------------------------------------------------------- torques that say what they are
def test_steady_orders_give_the_total_torque_beside_the_gas_torque(capsys):
    code, out, _ = run_cli(capsys, "steady", "4chn15", "--json")
    order2 = next(o for o in json.loads(out)["orders"] if o["order"] == 2.0)
    assert order2["gas_torque_amplitude_Nm"] == pytest.approx(2594.6, abs=0.5)
    assert order2["total_torque_amplitude_Nm"] == pytest.approx(912.0, rel=0.03)
    assert order2["reciprocating_torque_amplitude_Nm"] == pytest.approx(3506.0, rel=0.01)
    assert order2["inertia_term_amplitude_Nm"] == pytest.approx(order2["reciprocating_torque_amplitude_Nm"], rel=0.01)
    code, out, _ = run_cli(capsys, "steady", "4chn15")
    assert "gas [N·m]" in out and "total [N·m]" in out and "the torque that drives the speed" in out


def test_a_load_given_as_a_one_element_array_is_the_number(diesel):
    """A load's torque or coefficient given as a NumPy array of one element (as a load's
    own checks accept): the steady state of the plain number, the same figures."""
    for one, plain in (
        (rotor.ConstantLoad(np.array([900.0])), rotor.ConstantLoad(900.0)),
        (rotor.PropellerLoad(np.array([900.0]), 1250.0), rotor.PropellerLoad(900.0, 1250.0)),
    ):
        a, b = rotor.steady_state(diesel, rpm=1400.0, load=one), rotor.steady_state(diesel, rpm=1400.0, load=plain)
        assert float(a.delta) == pytest.approx(float(b.delta), rel=1e-12)
        assert float(a.fuel_scale) == pytest.approx(float(b.fuel_scale), rel=1e-12)


def test_total_torque_drives_the_speed(diesel):
    ss = rotor.steady_state(diesel)
    total = np.asarray(ss.total_torque)
    np.testing.assert_allclose(total, np.asarray(ss.gas_torque) + np.asarray(ss.inertia_term_torque), rtol=1e-12)
    # the speed rises where the total torque exceeds the load: I·dω/dt = total − load
    rising = np.asarray(ss.accel) > 0
    assert np.all((total - np.asarray(ss.load_torque))[rising] > 0)
    df = ss.to_pandas()
    assert {"gas_torque_Nm", "reciprocating_torque_Nm", "inertia_term_torque_Nm", "total_torque_Nm"} <= set(df)
    assert df["cycle"].min() == 1


def test_steady_torque_plot_shows_the_total_against_the_load(diesel):
    import matplotlib

    matplotlib.use("Agg")
    ax = rotor.steady_state(diesel).plot(kind="torque")
    labels = [line.get_label() for line in ax.get_lines()]
    assert any(label.startswith("total torque") for label in labels) and "load + friction" in labels


def test_orders_of_a_run_count_cycles_from_one(diesel):
    load = rotor.ConstantLoad(float(rotor.steady_state(diesel).load_torque_Nm))
    run = rotor.simulate(diesel, cycles=3, load=load, progress=False)
    first = np.asarray(run.orders(1).speed_amplitude_rad_s)
    np.testing.assert_allclose(first, np.asarray(run.orders(-3).speed_amplitude_rad_s))
    np.testing.assert_allclose(
        np.asarray(run.orders(3).torque_amplitude_Nm), np.asarray(run.orders().torque_amplitude_Nm)
    )
    for bad in (0, 4, -4):
        with pytest.raises(ValueError, match="count from 1"):
            run.orders(bad)
    assert run.to_pandas()["cycle"].tolist()[:1] == [1]


def test_python_simulate_states_what_it_was_given(diesel):
    run = rotor.simulate(diesel, cycles=2, load=rotor.ConstantLoad(1000.0), progress=False)
    assert float(run.load_torque_Nm) == 1000.0 and run.fuel_scale == 1.0 and run.solved_for is None
    assert "1000.00 N·m (given)" in run.summary()
    pattern = rotor.combustion_pattern(2, 4, imep_scale=0.8)
    run = rotor.simulate(diesel, cycles=2, load=rotor.PropellerLoad(900.0, 1250.0), combustion=pattern, progress=False)
    assert run.load_torque_Nm is None and run.fuel_scale == 0.8  # a speed-dependent load is no one number
