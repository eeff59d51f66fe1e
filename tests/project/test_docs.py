"""The documentation site: every public name has its API entry, on its subpackage's page;
every command its help block; every page and notebook is in the navigation, under one of
the four sections of the Diátaxis layout; the generated reference pages (the table of
commands, the engine-file keys, the wheel patterns) come from the code. `make test` builds
the site with `mkdocs build --strict` (a broken reference or a docstring that does not
render fails it); these tests say what the build alone cannot: that nothing is missing."""

from __future__ import annotations

import importlib.util
import re
import types

import pytest
from conftest import ROOT

import rotor
from rotor.cli.app import build_parser

DOCS = ROOT / "docs"
API = DOCS / "api"
MKDOCS = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
SUBPACKAGES = ("engine", "dynamics", "logs", "diagnostics", "design", "torsion")
ENTRY = re.compile(r"^::: rotor\.(\w+)\s*$", re.MULTILINE)


def api_entries() -> dict[str, list[str]]:
    """Each ``::: rotor.NAME`` of the API pages (not the subpackage and module directives) and the pages it is on."""
    found: dict[str, list[str]] = {}
    for page in sorted(API.glob("*.md")):
        for name in ENTRY.findall(page.read_text(encoding="utf-8")):
            if isinstance(getattr(rotor, name, None), types.ModuleType):
                continue  # `::: rotor.engine`, `::: rotor.errors`: a subpackage's or module's own docstring
            found.setdefault(name, []).append(page.stem)
    return found


def subpackage_of(name: str) -> str:
    """The subpackage a public name lives in (``base`` for the base layer)."""
    parts = getattr(rotor, name).__module__.split(".")
    return parts[1] if len(parts) > 2 and parts[1] in SUBPACKAGES else "base"


def test_every_public_name_has_one_api_entry_on_its_subpackages_page():
    entries = api_entries()
    missing = sorted(set(rotor.__all__) - set(entries))
    assert not missing, f"public names without an entry in docs/api/<subpackage>.md: {missing}"
    stale = sorted(set(entries) - set(rotor.__all__))
    assert not stale, f"docs/api entries for names that are not in rotor.__all__: {stale}"
    twice = {n: p for n, p in entries.items() if len(p) > 1}
    assert not twice, f"documented more than once: {twice}"
    misplaced = {n: (p[0], subpackage_of(n)) for n, p in entries.items() if p[0] != subpackage_of(n)}
    assert not misplaced, f"(page, subpackage) of names on another subpackage's page: {misplaced}"


def test_every_plotting_function_has_its_entry():
    import rotor.plotting

    page = (API / "plotting.md").read_text(encoding="utf-8")
    for name in rotor.plotting.__all__:
        module = getattr(rotor.plotting, name).__module__
        assert f"::: {module}.{name}\n" in page, f"docs/api/plotting.md has no entry for rotor.plotting.{name}"


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
    pytest.importorskip("mkdocs")
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    names = commands()
    assert "simulate" in names and "demo" in names
    assert "<!-- rotor commands -->" in cli
    table = load_docs_module("hooks").command_table()
    for name in names:
        assert f"<!-- rotor {name} --help -->" in cli, name
        assert f"| `rotor {name}` |" in table, f"rotor {name} is missing from the table of commands"


def test_the_table_of_commands_says_which_common_flags_each_takes():
    pytest.importorskip("mkdocs")
    rows = {
        line.split("|")[1].strip(): [c.strip() for c in line.split("|")[3:6]]
        for line in load_docs_module("hooks").command_table().splitlines()[2:]
    }
    assert rows["`rotor simulate`"] == ["✓", "✓", "✓"]
    assert rows["`rotor presets`"][1:] == ["", ""]


def test_the_engine_file_reference_comes_from_the_loader():
    """Every key with a plausible range is in the generated reference, under its table, and
    the tables the loader requires are marked so."""
    pytest.importorskip("mkdocs")
    from rotor.engine.plausible import PLAUSIBLE

    text = load_docs_module("hooks").engine_file_reference()
    sections = re.split(r"^#{3,4} ", text, flags=re.MULTILINE)
    for table, key in PLAUSIBLE:
        assert any(
            s.startswith(f"`[{table}]`")
            or s.startswith(f"`[[{table}]]`")
            or (table == "pressure" and s.startswith("`kind ="))
            for s in sections
            if f"| `{key}` |" in s
        ), (table, key)
    for table in ("geometry", "masses", "crankshaft", "layout", "operating"):
        assert f"### `[{table}]` (required)" in text, table
    assert "### `[pressure]` (optional" in text and "### `[torsion]` (optional)" in text
    assert "| `bore_m` | **required** | m | 0.001 … 2 |" in text
    assert "| `web` |" in text and "| `webs` |" not in text


def test_the_wheel_reference_names_the_standard_wheels():
    pytest.importorskip("mkdocs")
    from rotor.logs.identify import STANDARD_WHEELS

    text = load_docs_module("hooks").wheel_reference()
    for spec in STANDARD_WHEELS:
        assert f"`{spec}`" in text
    assert "`positions`, `missing`, `angles_deg`" in text


SECTIONS = ("Tutorials", "How-to guides", "Reference", "Explanation")


def test_the_navigation_has_the_four_kinds_of_documentation():
    nav = MKDOCS.split("\nnav:\n")[1]
    tops = re.findall(r"^  - ([^:]+):", nav, re.MULTILINE)
    assert tops == ["Home", *SECTIONS]
    section = dict(
        zip(
            SECTIONS, re.split(r"^  - (?:Tutorials|How-to guides|Reference|Explanation):$", nav, flags=re.MULTILINE)[1:]
        )
    )
    assert "notebooks/" in section["Tutorials"]
    assert all(f"how-to/{p.name}" in section["How-to guides"] for p in (DOCS / "how-to").glob("*.md"))
    assert all(f"api/{p.name}" in section["Reference"] for p in API.glob("*.md"))
    assert "cli.md" in section["Reference"] and "physics.md" in section["Explanation"]


def test_every_figure_names_the_script_that_draws_it():
    """Every image shown in the site is a file of the repository, and its page names a
    script (``*.py``) within a few lines of it."""
    for page in DOCS.rglob("*.md"):
        lines = page.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            for target in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", line):
                path = (page.parent / target).resolve()
                on_disk = path if path.is_file() else ROOT / path.relative_to(DOCS.resolve())
                assert on_disk.is_file(), f"{page.relative_to(ROOT)}:{i + 1}: {target} does not exist"
                near = " ".join(lines[max(0, i - 5) : i + 6])
                assert re.search(r"`[\w/.-]+\.py", near), (
                    f"{page.relative_to(ROOT)}:{i + 1}: no script named for {target}"
                )


def load_docs_module(name: str):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_help_blocks_come_from_the_parser():
    pytest.importorskip("mkdocs")
    hooks = load_docs_module("hooks")
    text = hooks.on_page_markdown("a\n<!-- rotor simulate --help -->\nb", page=None, config=None, files=None)
    assert text.startswith("a\n<!-- rotor simulate --help -->\n```text\n$ rotor simulate --help\nusage: rotor simulate")
    assert "--misfire" in text and text.endswith("```\n<!-- end of generated text -->\nb")
    assert hooks.fill(text) == text  # written once, the same text again
    stale = text.replace("--misfire", "--misfires")
    assert hooks.fill(stale) == text


@pytest.mark.parametrize("name", ["cli.md", "reference/engine-file.md", "reference/wheels.md"])
def test_the_generated_reference_is_written_into_the_repository(name):
    """The command-line and engine-file reference pages hold their generated text in the
    repository too, as the site shows it (the README links to them there)."""
    pytest.importorskip("mkdocs")
    hooks = load_docs_module("hooks")
    assert name in hooks.GENERATED_PAGES
    text = (DOCS / name).read_text(encoding="utf-8")
    assert hooks.END in text
    assert hooks.fill(text) == text, f"docs/{name} lags the code: run `make reference` (python docs/hooks.py)"


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


def test_the_changelog_page_speaks_to_users():
    """The changelog (and so its page on the site) names no work-item numbers and none of the
    project's shorthand for the package's parts."""
    pytest.importorskip("mkdocs")
    text = load_docs_module("hooks").changelog_for_users((ROOT / "CHANGELOG.md").read_text(encoding="utf-8"))
    found = re.findall(r"(?i).{0,30}(?:\bissue \d|\bhouse\b|\brooms?\b|ground floor).{0,30}", text)
    assert not found, found
