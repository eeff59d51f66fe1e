"""The distribution: its name, version, licence and changelog, and the wheel's contents.

The wheel is built from a copy of the sources (nothing is left in the tree), without
build isolation (offline: setuptools comes with the test extra). Installing it in a clean
virtualenv and running ``rotor demo`` there downloads the dependencies and takes about a
minute: it runs with ``ROTOR_WHEEL_CHECK=1`` (``make wheel-check``).
"""

from __future__ import annotations

import email.parser
import os
import shutil
import subprocess
import sys
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest
from conftest import ROOT

import rotor

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
PROJECT = PYPROJECT["project"]
DIST = "crank-rotor"


def test_distribution_name_is_not_the_taken_one():
    # `rotor` on the package index is another project; the import name stays rotor
    assert PROJECT["name"] == DIST
    assert PROJECT["scripts"] == {"rotor": "rotor.cli:command"}


def test_version_is_one():
    assert PROJECT["version"] == rotor.__version__


def test_licence_file_is_mit():
    assert PROJECT["license"] == "MIT"
    assert PROJECT["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License")
    assert "the rotor authors" in text
    assert "WITHOUT WARRANTY OF ANY KIND" in text


def test_changelog_has_this_version_and_unreleased():
    lines = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8").splitlines()
    headings = [line[3:].strip() for line in lines if line.startswith("## ")]
    assert headings[0] == "Unreleased"
    assert rotor.__version__ in headings


def test_every_extra_dependency_is_pinned_to_a_range():
    # `make test` on a fresh machine installs these: an open range is a future breakage
    deps = list(PROJECT["dependencies"])
    for group in PROJECT["optional-dependencies"].values():
        deps += group
    for dep in deps:
        assert ">=" in dep and "<" in dep, f"{dep}: pin it to a range (>=lower,<upper)"


def build_wheel(out: Path) -> Path:
    """Build the wheel from a copy of the sources (no build/ or *.egg-info in the tree)."""
    src = out / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, src / name)
    shutil.copytree(ROOT / "rotor", src / "rotor", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(out), str(src)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    wheels = list(out.glob("*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    return build_wheel(tmp_path_factory.mktemp("wheel"))


def test_wheel_name(wheel):
    assert wheel.name == f"crank_rotor-{rotor.__version__}-py3-none-any.whl"


def test_wheel_holds_the_package_typed_with_its_presets(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "rotor/py.typed" in names
    sources = {
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "rotor").rglob("*")
        if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".pyc"
    }
    # every module and data file of the package (the presets' TOML and JSON included)
    assert {s for s in sources if s.startswith("rotor/presets/")} >= {
        "rotor/presets/4chn15.toml",
        "rotor/presets/tue-single.calibration.json",
    }
    assert sources - names == set()
    # and nothing else at the top: no tests, notebooks or benchmarks
    assert {n.split("/")[0] for n in names} == {"rotor", f"crank_rotor-{rotor.__version__}.dist-info"}


def test_wheel_metadata(wheel):
    zf = zipfile.ZipFile(wheel)
    info = f"crank_rotor-{rotor.__version__}.dist-info"
    meta = email.parser.Parser().parsestr(zf.read(f"{info}/METADATA").decode())
    assert meta["Name"] == DIST
    assert meta["Version"] == rotor.__version__
    assert meta["License-Expression"] == "MIT"
    assert meta["License-File"] == "LICENSE"
    assert meta["Requires-Python"] == ">=3.11"
    requires = meta.get_all("Requires-Dist")
    assert any(r.startswith("jax") for r in requires)
    assert "Typing :: Typed" in meta.get_all("Classifier")
    assert zf.read(f"{info}/licenses/LICENSE").decode().startswith("MIT License")
    entry_points = zf.read(f"{info}/entry_points.txt").decode()
    assert "[console_scripts]" in entry_points
    assert "rotor = rotor.cli:command" in entry_points


@pytest.mark.skipif(
    os.environ.get("ROTOR_WHEEL_CHECK") != "1", reason="installs dependencies (a minute): make wheel-check"
)
def test_wheel_installs_in_clean_venv_and_runs_the_demo(wheel, tmp_path):
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True, system_site_packages=False, clear=True)
    bin_dir = env_dir / "bin"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env["PATH"] = f"{bin_dir}{os.pathsep}{env['PATH']}"
    env["MPLBACKEND"] = "Agg"

    def run(*argv: str, timeout: float = 600) -> str:
        proc = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=timeout)
        assert proc.returncode == 0, f"{argv}:\n{proc.stdout}\n{proc.stderr}"
        return proc.stdout

    run(str(bin_dir / "python"), "-m", "pip", "install", "-q", str(wheel))
    # the installed package, not the source tree
    where = run(
        str(bin_dir / "python"),
        "-c",
        "import importlib.metadata as m, importlib.resources as r, rotor;"
        "assert r.files('rotor').joinpath('py.typed').is_file();"
        "assert r.files('rotor.presets').joinpath('4chn15.toml').is_file();"
        "print(m.version('crank-rotor'), rotor.__file__)",
    )
    version, path = where.split()
    assert version == rotor.__version__
    assert Path(path).resolve().is_relative_to(env_dir.resolve())
    assert run(str(bin_dir / "rotor"), "--version").strip() == f"rotor {rotor.__version__}"
    out = run(str(bin_dir / "rotor"), "demo", "--quiet", "--plot", str(tmp_path / "plots"))
    assert "4ChN15" in out  # its summary
    assert len(list((tmp_path / "plots").glob("*.png"))) >= 3
