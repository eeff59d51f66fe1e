"""A pressure option of the command line (rotor.cli.args.pressure_pa) takes pascals within
the plausible range of its quantity and refuses a value in bar or kPa as a usage error that
names the unit it reads as."""

from __future__ import annotations

import pytest

from rotor.cli.args import Parser, pressure_pa


def parser() -> Parser:
    p = Parser(prog="rotor x")
    p.add_argument("--intake-pa", type=pressure_pa("intake_pa"))
    return p


def test_a_pressure_in_pascals_is_taken():
    assert parser().parse_args(["--intake-pa", "95000"]).intake_pa == 95000.0


@pytest.mark.parametrize("text, unit", [("0.95", "bar"), ("95", "kPa")])
def test_a_pressure_in_another_unit_is_a_usage_error_naming_it(text, unit, capsys):
    with pytest.raises(SystemExit) as e:
        parser().parse_args(["--intake-pa", text])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"argument --intake-pa: '{text}' lies outside the plausible 10000 … 500000 Pa" in err
    assert f"reads as {unit}" in err
