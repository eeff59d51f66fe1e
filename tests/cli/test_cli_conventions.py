"""The command line's conventions: one module per command group, thin, one rule for flags.

--json on every command with a result, --plot DIR on every command that draws (--out DIR
only for `rotor report`, whose product is a whole folder),
--quiet where a progress bar may show, --format only for tables; the command modules
import the library's subpackages lazily, never the top-level package, and build no JSON."""

import argparse
import ast
import subprocess
import sys
from pathlib import Path

import pytest

from rotor.cli import app

CLI = Path(app.__file__).parent
PARSER = app.build_parser()
COMMANDS = {
    name: p
    for action in PARSER._actions
    if isinstance(action, argparse._SubParsersAction)
    for name, p in action.choices.items()
}
DRAWS = {"plot", "demo", "steady", "simulate", "analyze", "diagnose", "calibrate", "flywheel", "loads", "balance"}
DRAWS |= {"modes", "campbell", "torsion"}
OUT = {"report"}  # its product is a folder (a page, figures and tables), named by --out DIR
NO_RESULT = {"plot", "demo"}  # they only write plots / print a tour of several results
PROGRESS = {"simulate", "demo"}  # they run transients long enough for a progress bar
PROGRESS |= {"analyze", "diagnose"}  # over many LOGs: a bar counting the files


def _options(p):
    return {s for a in p._actions for s in a.option_strings}


def test_every_command_is_there():
    assert set(COMMANDS) == {
        "table",
        "info",
        "plot",
        "presets",
        "wheels",
        "steady",
        "simulate",
        "analyze",
        "diagnose",
        "calibrate",
        "monitor",
        "flywheel",
        "loads",
        "balance",
        "modes",
        "campbell",
        "torsion",
        "report",
        "demo",
    }


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_json_on_every_command_with_a_result(name):
    assert ("--json" in _options(COMMANDS[name])) == (name not in NO_RESULT)


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_plot_dir_on_every_command_that_draws(name):
    opts = _options(COMMANDS[name])
    assert ("--plot" in opts) == (name in DRAWS)
    assert ("--out" in opts) == (name in OUT)


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_quiet_where_a_progress_bar_may_show_and_format_only_for_tables(name):
    opts = _options(COMMANDS[name])
    assert ("--quiet" in opts) == (name in PROGRESS)
    assert ("--format" in opts) == (name == "table")


def test_the_convention_is_in_the_top_level_help():
    text = PARSER.format_help()
    for flag in ("--json", "--plot DIR", "--quiet", "--format"):
        assert flag in text


def test_plot_and_demo_default_to_out():
    assert PARSER.parse_args(["plot", "4chn15"]).plot == "out"
    assert PARSER.parse_args(["demo"]).plot == "out"
    assert PARSER.parse_args(["steady", "4chn15"]).plot is None


def _modules():
    return sorted(CLI.glob("*.py"))


@pytest.mark.parametrize("path", _modules(), ids=lambda p: p.name)
def test_no_top_level_package_and_no_json_building(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            assert all(a.name != "rotor" for a in node.names), f"{path.name}:{node.lineno}: import rotor"
        elif isinstance(node, ast.ImportFrom):
            if node.level == 2 and node.module is None:  # from .. import X
                assert [a.name for a in node.names] == ["__version__"], f"{path.name}:{node.lineno}"
            assert node.module != "rotor", f"{path.name}:{node.lineno}: from rotor import"
        elif isinstance(node, ast.Attribute) and node.attr in ("dumps", "dump") and path.name != "output.py":
            pytest.fail(f"{path.name}:{node.lineno}: JSON is written by output.py from a result's to_json_dict()")


def test_every_command_module_is_a_group():
    groups = {g.__name__.rsplit(".", 1)[-1] for g in app.COMMAND_GROUPS}
    helpers = {"__init__", "__main__", "app", "args", "kept", "output"}
    assert groups == {p.stem for p in _modules()} - helpers
    for g in app.COMMAND_GROUPS:
        assert callable(g.add_parsers)


def test_help_imports_no_plotting_library():
    code = (
        "import sys\nfrom rotor.cli.app import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in ('matplotlib', 'pandas') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"


def test_json_and_csv_are_written_by_output_only():
    """One writer (cli/output.py) for every command's JSON and CSV: none of the command
    modules calls json.dumps or a result's to_csv, so that none can write NaN or Infinity."""
    for path in CLI.glob("*.py"):
        if path.name == "output.py":
            continue
        text = path.read_text(encoding="utf-8")
        for needle in ("json.dump", ".to_csv(", "csv.writer", "allow_nan"):
            assert needle not in text, f"rotor/cli/{path.name} writes JSON or CSV itself ({needle}): use cli/output.py"


def test_debug_is_a_global_flag_and_exit_statuses_are_documented():
    assert "--debug" in PARSER.format_help()
    for code in ("70", "130"):
        assert code in PARSER.epilog and code in (app.__doc__ or "")


@pytest.mark.parametrize("name", ["analyze", "diagnose"])
def test_log_commands_take_many_logs_jobs_and_a_scheduler(name):
    """Several LOGs or a pattern in one run: --jobs, --scheduler, and the exit
    status of a run where some files fail is in the help."""
    p = COMMANDS[name]
    assert {"--jobs", "--scheduler", "--quiet"} <= _options(p)
    (log,) = [a for a in p._actions if a.dest == "log"]
    assert log.nargs == "+"
    text = " ".join(p.format_help().split())
    assert "JSON line per file" in text and "exit status" in text and "pip install 'crank-rotor[dask]'" in text
