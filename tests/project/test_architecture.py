"""The structure that import-linter cannot see: no private name crosses a module boundary
(in the package, its tests, benchmarks and notebooks), every subpackage says in its
``__init__`` docstring what lives there and what it may import, and every module that
imports JAX imports :mod:`rotor.jaxconfig` (float64 on) with it.

The layer contracts themselves are in ``pyproject.toml`` (``[tool.importlinter]``) and run
by ``make test`` as ``lint-imports``; ``test_layer_contracts_hold`` runs them here too."""

import ast
import json
import re
import shutil
import subprocess

import pytest
from conftest import ROOT

SUBPACKAGES = ["engine", "dynamics", "logs", "diagnostics", "design", "torsion", "plotting", "cli"]


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _module_name(path):
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _absolute(node: ast.ImportFrom, here: str, is_package: bool) -> str:
    if not node.level:
        return node.module or ""
    base = here.split(".") if is_package else here.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _violations(source: str, here: str, is_package: bool = False):
    """Private names of rotor modules used from outside the module that defines them."""
    tree = ast.parse(source)
    aliases = {}  # local name -> rotor module it is bound to
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name == "rotor" or a.name.startswith("rotor."):
                    aliases[a.asname or a.name.split(".")[0]] = a.asname and a.name or "rotor"
                    if any(_private(p) for p in a.name.split(".")):
                        found.append(f"line {node.lineno}: import {a.name}")
        elif isinstance(node, ast.ImportFrom):
            mod = _absolute(node, here, is_package)
            if not (mod == "rotor" or mod.startswith("rotor.")):
                continue
            if any(_private(p) for p in mod.split(".")):
                found.append(f"line {node.lineno}: from {mod} import ...")
            for a in node.names:
                if _private(a.name):
                    found.append(f"line {node.lineno}: from {mod} import {a.name}")
                else:
                    aliases.setdefault(a.asname or a.name, f"{mod}.{a.name}")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            chain, v = [node.attr], node.value
            while isinstance(v, ast.Attribute):
                chain.append(v.attr)
                v = v.value
            if isinstance(v, ast.Name) and v.id in aliases and v.id != "self":
                found.append(f"line {node.lineno}: {v.id}.{'.'.join(reversed(chain))}")
    return found


def _python_files():
    for folder in ("rotor", "tests", "benchmarks"):
        yield from sorted((ROOT / folder).rglob("*.py"))


@pytest.mark.parametrize("path", list(_python_files()), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_name_crosses_a_module(path):
    here = _module_name(path) if path.parts[len(ROOT.parts)] == "rotor" else "__outside__"
    bad = _violations(path.read_text(encoding="utf-8"), here, path.name == "__init__.py")
    assert not bad, f"{path.relative_to(ROOT)} uses private names of other modules: {bad}"


@pytest.mark.parametrize("path", sorted((ROOT / "notebooks").glob("*.ipynb")), ids=lambda p: p.name)
def test_notebooks_use_no_private_names(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    code = "\n".join(line for line in code.splitlines() if not line.lstrip().startswith(("%", "!")))
    assert not _violations(code, "__outside__")


def test_the_checker_sees_a_private_import():
    """The rule above can fail: the forms it must catch are caught."""
    assert _violations("from rotor.dynamics.equation import _wrap", "__outside__")
    assert _violations("import rotor\nrotor.design.flywheel._state(1)", "__outside__")
    assert _violations("from ..dynamics import crank_train\ncrank_train._I", "rotor.diagnostics.inverse")
    assert _violations("from ._checks import x", "rotor.engine.model")
    assert not _violations("from .crank_train import COL_I\nself._x = 1", "rotor.dynamics.equation")


@pytest.mark.parametrize("subpackage", SUBPACKAGES)
def test_every_subpackage_says_what_lives_there_and_what_it_may_import(subpackage):
    doc = ast.get_docstring(ast.parse((ROOT / "rotor" / subpackage / "__init__.py").read_text(encoding="utf-8")))
    assert doc and len(doc.splitlines()) >= 3, f"rotor/{subpackage}/__init__.py needs a docstring"
    assert "import" in doc, f"rotor/{subpackage}/__init__.py must say what it may import"


BASE = ("units", "errors", "checks", "fileio", "cache", "results", "cycles", "jaxconfig", "progress")


def test_the_base_layer_imports_only_its_own_modules():
    for name in BASE:
        here = f"rotor.{name}"
        tree = ast.parse((ROOT / "rotor" / f"{name}.py").read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                mod = _absolute(node, here, False)
                assert not mod.startswith("rotor") or mod in {f"rotor.{g}" for g in BASE}, f"{name}: imports {mod}"


def test_every_module_that_imports_jax_imports_jaxconfig():
    """float64 is on before rotor computes: each module that imports JAX also imports
    :mod:`rotor.jaxconfig`, directly or through the modules it imports."""
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("rotor", include_external_packages=True)
    users = graph.find_modules_that_directly_import("jax")
    assert "rotor.dynamics.steady" in users
    missing = sorted(
        m for m in users if m != "rotor.jaxconfig" and not graph.chain_exists(importer=m, imported="rotor.jaxconfig")
    )
    assert not missing, f"these modules import jax but not rotor.jaxconfig: {missing}"


@pytest.mark.skipif(
    shutil.which("lint-imports") is None and not (ROOT / ".venv/bin/lint-imports").exists(),
    reason="import-linter not installed",
)
def test_layer_contracts_hold():
    exe = shutil.which("lint-imports") or str(ROOT / ".venv/bin/lint-imports")
    r = subprocess.run([exe, "--no-cache"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]


def test_top_level_all_is_one_sorted_list():
    import rotor

    assert list(rotor.__all__) == sorted(rotor.__all__)
    assert len(set(rotor.__all__)) == len(rotor.__all__)
    for name in rotor.__all__:
        assert hasattr(rotor, name), name


def test_every_module_is_reachable_as_an_attribute_of_its_subpackage():
    """``import rotor`` is lazy, yet ``rotor.diagnostics.calibration_record.preset_calibration``
    works in a fresh process, as it did when every module was imported eagerly."""
    import sys

    code = (
        "import pkgutil, rotor\n"
        f"for name in {SUBPACKAGES!r}:\n"
        "    package = getattr(rotor, name)\n"
        "    for m in pkgutil.iter_modules(package.__path__):\n"
        "        if not m.name.startswith('_'):\n"
        "            getattr(package, m.name)\n"
        "try:\n"
        "    rotor.dynamics.no_such_module\n"
        "except AttributeError:\n"
        "    print('ok')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]


# rotor's flags are words joined by hyphens (``--tdc-deg``); XLA's options have underscores
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]+(?!\w)")
SPEAKS_PYTHON = [ROOT / "rotor" / f"{name}.py" for name in BASE] + [
    path
    for name in ("engine", "dynamics", "design", "torsion", "plotting", "logs", "diagnostics")
    for path in (ROOT / "rotor" / name).rglob("*.py")
]


def _flags_in_messages(source: str) -> list[str]:
    """The command-line flags (``--load``) in the string constants of ``source`` that are no docstring."""
    tree = ast.parse(source)
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        f"line {node.lineno}: {node.value[:80]!r}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and id(node) not in docstrings
        and FLAG.search(node.value)
    ]


@pytest.mark.parametrize("path", SPEAKS_PYTHON, ids=lambda p: str(p.relative_to(ROOT)))
def test_the_library_names_python_arguments_not_flags(path):
    """A message of the library names the function's argument (``load='abc': …``, with
    ``RotorError(argument=...)``); the command line turns it into the flag."""
    assert not _flags_in_messages(path.read_text(encoding="utf-8"))


def test_the_flag_check_sees_a_flag():
    assert _flags_in_messages('raise EngineError(f"--load {spec!r}: not understood")')
    assert not _flags_in_messages('def f():\n    """``--load`` on the command line."""\n')


def test_the_command_line_prints_the_library_notes_in_flags():
    """A library note names its arguments; the command line shows the same note with its flags."""
    from rotor.cli.args import cli_json_words, cli_words

    assert cli_words("read as wheel='60-2', edge='rising'") == "read as --wheel 60-2 --edge rising"
    assert cli_words("a calibration (tooth_errors=FILE) gives") == "a calibration (--tooth-errors FILE) gives"
    assert cli_words("give cylinders=N, or") == "give --cylinders N, or"
    assert cli_words("e.g. columns='time,encoder_d,-', if") == "e.g. --columns time,encoder_d,-, if"
    assert cli_words("fit (compression_ratio=…, rod_ratio=…)") == "fit (--compression-ratio … --rod-ratio …)"
    assert cli_words("a ratio=3 and wheels=2 stay") == "a ratio=3 and wheels=2 stay"
    assert cli_json_words({"pins": "wheel='36-1'", "n": 3, "notes": ["calibration=None"]}) == {
        "pins": "--wheel 36-1",
        "n": 3,
        "notes": ["--no-calibration"],
    }


MAX_FUNCTION_LINES = 150


def test_no_function_of_the_package_is_over_150_lines():
    """Every function in ``rotor/``, from its ``def`` to its last line (docstring included),
    fits in 150 lines: a longer one holds more than one job."""
    long = []
    for path in sorted((ROOT / "rotor").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} ({lines} lines)")
    assert not long, "functions over 150 lines:\n" + "\n".join(long)
