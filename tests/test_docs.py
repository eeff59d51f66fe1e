"""The documentation site: every public name has its API entry, on its room's page; every
command its help block; every page and notebook is in the navigation. `make test` builds
the site with `mkdocs build --strict` (a broken reference or a docstring that does not
render fails it); these tests say what the build alone cannot: that nothing is missing."""

from __future__ import annotations

import importlib.util
import re
import types
from pathlib import Path

import pytest

import rotor
from rotor.cli.app import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
API = DOCS / "api"
MKDOCS = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
ROOMS = ("engine", "dynamics", "logs", "diagnostics", "design", "torsion")
ENTRY = re.compile(r"^::: rotor\.(\w+)\s*$", re.MULTILINE)


def api_entries() -> dict[str, list[str]]:
    """Each ``::: rotor.NAME`` of the API pages (not the room and module directives) and the pages it is on."""
    found: dict[str, list[str]] = {}
    for page in sorted(API.glob("*.md")):
        for name in ENTRY.findall(page.read_text(encoding="utf-8")):
            if isinstance(getattr(rotor, name, None), types.ModuleType):
                continue  # `::: rotor.engine`, `::: rotor.errors`: a room's or module's own docstring
            found.setdefault(name, []).append(page.stem)
    return found


def room_of(name: str) -> str:
    """The room a public name lives in (``ground`` for the ground floor)."""
    parts = getattr(rotor, name).__module__.split(".")
    return parts[1] if len(parts) > 2 and parts[1] in ROOMS else "ground"


def test_every_public_name_has_one_api_entry_on_its_rooms_page():
    entries = api_entries()
    missing = sorted(set(rotor.__all__) - set(entries))
    assert not missing, f"public names without an entry in docs/api/<room>.md: {missing}"
    stale = sorted(set(entries) - set(rotor.__all__))
    assert not stale, f"docs/api entries for names that are not in rotor.__all__: {stale}"
    twice = {n: p for n, p in entries.items() if len(p) > 1}
    assert not twice, f"documented more than once: {twice}"
    misplaced = {n: (p[0], room_of(n)) for n, p in entries.items() if p[0] != room_of(n)}
    assert not misplaced, f"(page, room) of names on another room's page: {misplaced}"


def test_every_api_page_is_in_the_navigation():
    for page in API.glob("*.md"):
        assert f"api/{page.name}" in MKDOCS, page


def test_every_page_and_notebook_is_in_the_navigation():
    for page in DOCS.rglob("*.md"):
        assert page.relative_to(DOCS).as_posix() in MKDOCS, page
    notebooks = sorted((ROOT / "notebooks").glob("*.ipynb"))
    assert notebooks
    for nb in notebooks:
        assert f"notebooks/{nb.name}" in MKDOCS, nb
        assert f"({nb.name})" in (DOCS / "notebooks" / "index.md").read_text(encoding="utf-8"), nb


def commands() -> list[str]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    return list(sub.choices)


def test_every_command_has_its_help_on_the_cli_page():
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    names = commands()
    assert "simulate" in names and "demo" in names
    for name in names:
        assert f"<!-- rotor {name} --help -->" in cli, name
        assert f"| `rotor {name}` |" in cli, f"rotor {name} is missing from the table of commands"


def load_docs_module(name: str):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_help_blocks_come_from_the_parser():
    pytest.importorskip("mkdocs")
    hooks = load_docs_module("hooks")
    text = hooks.on_page_markdown("a\n<!-- rotor simulate --help -->\nb", page=None, config=None, files=None)
    assert text.startswith("a\n```text\n$ rotor simulate --help\nusage: rotor simulate")
    assert "--misfire" in text and text.endswith("```\nb")


def test_docstrings_become_markdown():
    pytest.importorskip("griffe")
    ext = load_docs_module("griffe_rotor")
    doc = "Say.\n\n**Arguments:**\n- ``a``: one [m].\n  more.\n- ``b``: see :class:`rotor.Engine`.\n\n**Returns:** x."
    assert ext.markdown(doc) == (
        "Say.\n\n**Arguments:**\n\n- ``a``: one [m].\n  more.\n- ``b``: see `rotor.Engine`.\n\n**Returns:** x."
    )
    assert ext.markdown("already\n\n- fine") == "already\n\n- fine"


def test_the_site_fetches_nothing():
    # offline builds: no social cards (they download fonts), no external fonts or inventories
    plugins = re.findall(r"^  - ([\w-]+)", MKDOCS.split("\nplugins:")[1].split("\n\n")[0], re.MULTILINE)
    assert plugins == ["search", "mkdocs-jupyter", "mkdocstrings"]
    assert "font: false" in MKDOCS
    assert not re.search(r"^\s+(import|inventories):", MKDOCS, re.MULTILINE)  # objects.inv from the web
    assert "strict: true" in MKDOCS
