"""What a command-line user reads: every option explained, warnings as one line of rotor's
own words, no Python or numpy text on the terminal."""

import argparse
import warnings
from pathlib import Path

import numpy as np
import pytest

import rotor
from rotor import cli
from rotor.cli.app import build_parser, warning_line


def _subparsers(parser):
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices


def test_every_option_has_help_text():
    missing = [
        f"rotor {name} {' '.join(a.option_strings) or a.dest}"
        for name, sub in _subparsers(build_parser()).items()
        for a in sub._actions
        if not a.help or a.help == argparse.SUPPRESS or not str(a.help).strip()
    ]
    assert missing == []


def test_a_warning_is_one_line_of_rotors_words(capsys):
    code = cli.main(["simulate", "4chn15", "--cycles", "2", "--load", "none", "--quiet"])
    err = capsys.readouterr().err
    assert code == 0
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rotor: warning: ") and "will accelerate" in lines[0]
    assert ".py" not in err and "UserWarning" not in err and "warnings.warn" not in err
    assert "rotor.ConstantLoad" not in err and "leave out --load" in err  # the command line's words


def test_numpy_and_library_warnings_do_not_reach_the_terminal(capsys, monkeypatch):
    def noisy(args):
        np.log(np.zeros(3))  # numpy: "divide by zero encountered in log"
        np.float64(1.0) / np.float64(0.0)
        warnings.warn("old", DeprecationWarning, stacklevel=1)
        warnings.warn("a remark from outside rotor", UserWarning, stacklevel=1)

    parser = build_parser()
    sub = _subparsers(parser)["presets"]
    monkeypatch.setattr(sub, "_defaults", {**sub._defaults, "func": noisy})
    monkeypatch.setattr(cli.app, "build_parser", lambda: parser)
    assert cli.main(["presets"]) == 0
    err = capsys.readouterr().err
    assert err == ""  # numpy's, a deprecation and a warning from outside rotor: none shown


ROTOR = Path(rotor.__file__).parent


@pytest.mark.parametrize(
    ("category", "where", "shown"),
    [
        (UserWarning, ROTOR / "dynamics" / "transient.py", True),
        (RuntimeWarning, ROTOR / "dynamics" / "transient.py", False),
        (UserWarning, Path(np.__file__), False),
    ],
)
def test_warning_line_shows_rotors_user_warnings_only(capsys, category, where, shown):
    warning_line("it\nhappened", category, str(where), 12)
    err = capsys.readouterr().err
    assert (err == "rotor: warning: it happened\n") if shown else err == ""


def test_modes_without_a_torsion_table_speaks_the_command_lines_words(capsys):
    code = cli.main(["modes", "4chn15"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "[torsion] table" in err
    assert "torsional_chain(" not in err and "docs/" not in err


def test_analyze_plot_names_no_tdc_it_does_not_know():
    import matplotlib

    matplotlib.use("Agg")
    omega = 1200.0 / 60 * 2 * np.pi  # rad/s
    pitch = 2 * np.pi / 60
    angles = np.concatenate([r * 2 * np.pi + pitch * np.arange(58) for r in range(20)])
    log = rotor.Log.from_arrays(tooth_time_s=angles / omega)
    a = rotor.analyze_log(log, "60-2", cylinders=4)
    assert str(a.tdc_method).startswith("unknown")
    axes = np.asarray(a.plot()).ravel()
    assert "TDC unknown" in axes[0].get_xlabel() and "firing TDC" not in axes[0].get_xlabel()
    assert axes[1].get_lines()[0].get_xdata()[0] == 1  # cycles count from 1
    one = a.plot(kind="cycles")  # one Axes, one panel
    assert one.get_xlabel() == "cycle (from 1)" and one.get_lines()[0].get_xdata()[0] == 1
    assert "TDC unknown" in a.plot(kind="speed").get_xlabel()
    with pytest.raises(ValueError, match="kind"):
        a.plot(kind="all of them")


def test_a_near_tie_for_the_oil_hole_is_reported_with_both_rays():
    loads = rotor.bearing_loads(rotor.load_engine("4chn15"))
    assert loads.journal_oil_hole_candidates_deg(2) == [270.0, 90.0]  # wear 3161.0 against 3189.7 N
    assert loads.journal_oil_hole_candidates_deg(3) == [240.0]
    assert "oil hole at 270° (near tie: 90° (+0.9%)" in loads.summary()
    journal = loads.to_json_dict()["journals"][1]
    assert journal["oil_hole_deg"] == 270.0 and journal["oil_hole_candidates_deg"] == [270.0, 90.0]
    # polar diagram: angles whose points nearly coincide share one label instead of overprinting
    import matplotlib

    matplotlib.use("Agg")
    texts = [t.get_text() for t in loads.plot_crank_pin().texts]
    assert "180, 540" in texts and "180" not in texts and "540" not in texts


def test_campbell_says_why_its_margin_is_zero(capsys):
    assert cli.main(["campbell", "mwm6"]) == 0
    out = capsys.readouterr().out
    assert "0 at each of the 15 critical speeds in the range" in out and "smallest separation margin 0.00" not in out
    assert cli.main(["campbell", "mwm6", "--rpm-range", "600:700"]) == 0
    assert "smallest separation margin 35.36 %" in capsys.readouterr().out  # no critical speed: a real margin


def test_calibration_plot_takes_one_axes_with_kind():
    import matplotlib

    matplotlib.use("Agg")
    from rotor.plotting.diagnostics import plot_calibration

    figures = dict(imep_measured_pa=[9e5, 9.2e5, 9.1e5], loss_torque_Nm=[40.0, 41.0, 39.5], imep_file_pa=9e5)
    both = plot_calibration(**figures, title="bench")
    assert len(both) == 2
    one = plot_calibration(**figures, title="bench", kind="loss")
    assert one.get_xlabel() == "cycle (from 1)" and list(one.get_lines()[0].get_xdata()) == [1, 2, 3]
    assert plot_calibration(**figures, title="bench", kind="imep").get_ylabel() == "IMEP [bar]"
