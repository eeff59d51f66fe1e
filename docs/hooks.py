"""mkdocs hooks: the notebooks live in notebooks/ (beside the package, where `make
notebooks` and the tests run them); they become pages under notebooks/ here, before
mkdocs-jupyter turns them into HTML; CHANGELOG.md becomes changelog.md (without the
project's work-item numbers); the figures of benchmarks/figures/ become files of the site;
``<!-- rotor COMMAND --help -->`` in a page is followed by what that command prints, so
that the command-line page never falls behind the parser; and ``<!-- rotor commands -->``,
``<!-- engine-file keys -->`` and ``<!-- standard wheels -->`` by the reference tables
generated from the parser, the engine-file loader and the wheel reader. The generated text
is written into the pages of the repository too (``make reference``, which runs this file;
tests/project/test_docs.py fails while a page lags the code), so that they read there as
on the site."""

from __future__ import annotations

import contextlib
import io
import os
import re
import sys
from pathlib import Path

from mkdocs.plugins import event_priority
from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]


@event_priority(100)  # before mkdocs-jupyter's on_files
def on_files(files: Files, config) -> Files:
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        # a File under the repository root (not a generated one): mkdocs-jupyter reads
        # the notebook from src_dir/src_uri
        files.append(
            File(
                f"notebooks/{nb.name}",
                src_dir=str(ROOT),
                dest_dir=config["site_dir"],
                use_directory_urls=config["use_directory_urls"],
            )
        )
    files.append(File.generated(config, "changelog.md", abs_src_path=str(ROOT / "CHANGELOG.md")))
    # the figures the benchmark scripts draw, shown on the explanation pages as they are
    for png in sorted((ROOT / "benchmarks" / "figures").glob("*.png")):
        files.append(
            File(
                f"benchmarks/figures/{png.name}",
                src_dir=str(ROOT),
                dest_dir=config["site_dir"],
                use_directory_urls=config["use_directory_urls"],
            )
        )
    return files


HELP = re.compile(r"^<!-- (rotor(?: [a-z-]+)? --help) -->$", re.MULTILINE)
"""A marker line whose generated text is what that command prints for ``--help``."""


def rotor_help(command: str) -> str:
    """What ``rotor … --help`` prints, from the parser itself (80 columns)."""
    from rotor.cli.app import build_parser

    argv = command.split()[1:]
    out = io.StringIO()
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "80"
    try:
        with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
            build_parser().parse_args(argv)
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    return out.getvalue().rstrip()


# --- reference pages generated from the code they describe ---------------------------

COMMANDS = re.compile(r"^<!-- rotor commands -->$", re.MULTILINE)
ENGINE_KEYS = re.compile(r"^<!-- engine-file keys -->$", re.MULTILINE)
WHEELS = re.compile(r"^<!-- standard wheels -->$", re.MULTILINE)


def _parser_commands() -> list[tuple[str, str, set[str]]]:
    """(name, help, option strings) of every ``rotor`` command, in the parser's order."""
    from rotor.cli.app import build_parser

    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    helps = {a.dest: a.help or "" for a in sub._choices_actions}
    out = []
    for name, p in sub.choices.items():
        options = {s for a in p._actions for s in a.option_strings}
        out.append((name, helps.get(name, ""), options))
    return out


def command_table() -> str:
    """The table of commands: each command's one-line help and which of the common flags it takes."""
    rows = [
        "| command | what it does | `--json` | `--plot DIR` | `--quiet` |",
        "|---|---|---|---|---|",
    ]
    for name, text, options in _parser_commands():
        text = text.replace("|", "\\|")
        flags = ["✓" if f in options else "" for f in ("--json", "--plot", "--quiet")]
        rows.append(f"| `rotor {name}` | {text} | " + " | ".join(flags) + " |")
    return "\n".join(rows)


_SUFFIX_UNITS = (
    ("_Nms_per_rad", "N·m·s/rad"),
    ("_Nm_per_rad", "N·m/rad"),
    ("_pa_s2_per_m2", "Pa·s²/m²"),
    ("_pa_s_per_m", "Pa·s/m"),
    ("_kgm2", "kg·m²"),
    ("_kg", "kg"),
    ("_deg", "deg"),
    ("_pa", "Pa"),
    ("_m", "m"),
    ("rpm", "rev/min"),
)


def _unit(key: str) -> str:
    for suffix, unit in _SUFFIX_UNITS:
        if key.endswith(suffix):
            return unit
    return "–"


def _number(x: float) -> str:
    """A range's end as people write it: ``1e9``, ``0.001``, ``−3600``."""
    text = f"{x:g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")
    return text.replace("-", "−")


def _kind(annotation) -> str:
    text = str(annotation)
    if "tuple" in text:
        return "list of whole numbers"
    if text.startswith("int"):
        return "whole number"
    if text == "str":
        return "string"
    return "number(s)"


def _default(field) -> str | None:
    """The default of a dataclass field as text, or None where the key is required."""
    import dataclasses

    if field.default is not dataclasses.MISSING:
        value = field.default
        if value is None:
            return "absent"
        if value == ():
            return "none"
        return f"`{float(value):g}`" if isinstance(value, (int, float)) else f"`{value}`"
    if field.default_factory is not dataclasses.MISSING:  # type: ignore[misc]
        return "(built)"
    return None


def _doc(cls) -> str:
    import inspect

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from griffe_rotor import markdown

    return markdown(inspect.cleandoc(cls.__doc__ or ""))


def _key_rows(table: str, cls, rename: dict[str, str] | None = None) -> list[str]:
    import dataclasses

    from rotor.engine.plausible import PLAUSIBLE

    rows = ["| key | required / default | unit | plausible range | value |", "|---|---|---|---|---|"]
    for f in dataclasses.fields(cls):
        if f.name in ("kind",) or not f.init:
            continue
        key = (rename or {}).get(f.name, f.name)
        default = _default(f)
        needed = "**required**" if default is None else default
        if (table, key) in PLAUSIBLE:
            lo, hi, unit, _hint = PLAUSIBLE[(table, key)]
            span = f"{_number(lo)} … {_number(hi)}"
            unit = unit or "–"
        else:
            span, unit = "", _unit(key)
        rows.append(f"| `{key}` | {needed} | {unit} | {span} | {_kind(f.type)} |")
    return rows


def _required_tables() -> dict[str, bool]:
    """Which tables an engine file must have: each table of the 4chn15 preset left out in
    turn and the file read by the loader itself."""
    import tomllib

    import rotor
    from rotor.engine.file import preset_path

    data = tomllib.loads(Path(preset_path("4chn15")).read_text(encoding="utf-8"))
    out = {}
    for name in ("geometry", "masses", "crankshaft", "layout", "operating", "pressure"):
        trimmed = {k: v for k, v in data.items() if k != name}
        try:
            rotor.engine_from_dict(trimmed)
            out[name] = False
        except rotor.EngineError as e:
            out[name] = "is missing" in str(e)
    return out


def engine_file_reference() -> str:
    """Every key of an engine file, table by table, from the classes the loader builds,
    the plausible ranges it checks (``rotor.engine.plausible.PLAUSIBLE``) and which tables it
    requires."""
    import dataclasses

    from rotor.engine.friction import Friction
    from rotor.engine.model import (
        Articulated,
        Counterweights,
        Crankshaft,
        Engine,
        Geometry,
        Layout,
        Masses,
        Operating,
        Torsion,
    )
    from rotor.engine.pressure import PRESSURE_KINDS

    required = _required_tables()
    out = ["### Top-level keys", "", "| key | required / default | value |", "|---|---|---|"]
    for f in dataclasses.fields(Engine):
        if str(f.type) in ("str", "int"):
            out.append(f"| `{f.name}` | **required** | {_kind(f.type)} |")
    out.append("")
    tables = [
        ("geometry", Geometry),
        ("masses", Masses),
        ("crankshaft", Crankshaft),
        ("layout", Layout),
        ("operating", Operating),
    ]
    for name, cls in tables:
        need = "required" if required.get(name, False) else "optional"
        out += [f"### `[{name}]` ({need})", "", *_key_rows(name, cls), "", _doc(cls), ""]
    need = "required" if required.get("pressure", False) else "optional: without it, no gas pressure"
    out += [
        f"### `[pressure]` ({need})",
        "",
        "`kind` (**required**) picks the pressure source: "
        + ", ".join(f"`{k}`" for k in PRESSURE_KINDS)
        + ". The other keys depend on it.",
        "",
    ]
    for kind, cls in PRESSURE_KINDS.items():
        out += [f'#### `kind = "{kind}"`', "", *_key_rows("pressure", cls), "", _doc(cls), ""]
    for name, cls in (("friction", Friction), ("articulated", Articulated), ("torsion", Torsion)):
        out += [f"### `[{name}]` (optional)", "", *_key_rows(name, cls), "", _doc(cls), ""]
    out += [
        "### `[[counterweights]]` (optional, one table per counterweight)",
        "",
        *_key_rows("counterweights", Counterweights, {"webs": "web"}),
        "",
        "In the file each counterweight is a table of its own with one `web` (1 … 2 × throws; "
        "webs 2k−1 and 2k flank throw k) and its own `mass_kg`, `radius_m` and `angle_deg` "
        "(default 180: opposite its throw).",
        "",
        _doc(Counterweights),
    ]
    return "\n".join(out)


def wheel_reference() -> str:
    """The standard wheel patterns that ``--wheel auto`` tries, and the keys of a wheel file."""
    from rotor.logs.identify import STANDARD_WHEELS
    from rotor.logs.wheel import MAX_POSITIONS, WHEEL_FILE_KEYS

    return (
        "The standard patterns `--wheel auto` tries: "
        + ", ".join(f"`{w}`" for w in STANDARD_WHEELS)
        + f". A wheel has 3 to {MAX_POSITIONS:,} tooth positions. The keys of a wheel file: "
        + ", ".join(f"`{k}`" for k in WHEEL_FILE_KEYS)
        + "; any other key is refused by name."
    )


def changelog_for_users(markdown: str) -> str:
    """CHANGELOG.md as the site shows it: Sphinx roles as code, a blank line before every
    list (``griffe_rotor.markdown``)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from griffe_rotor import markdown as docstring_markdown

    return docstring_markdown(markdown)


MARKER = re.compile(
    r"^(<!-- (?:rotor(?: [a-z-]+)? --help|rotor commands|engine-file keys|standard wheels) -->)\n"
    r"(?:.*?^<!-- end of generated text -->\n)?",
    re.MULTILINE | re.DOTALL,
)
END = "<!-- end of generated text -->"
GENERATED_PAGES = ("cli.md", "reference/engine-file.md", "reference/wheels.md")
"""The pages of docs/ whose generated text is written into the page itself."""


def _generated(marker: str) -> str:
    """What a marker line stands for: a command's help, or one of the reference tables."""
    if m := HELP.match(marker):
        return f"```text\n$ {m.group(1)}\n{rotor_help(m.group(1))}\n```"
    if COMMANDS.match(marker):
        return command_table()
    if ENGINE_KEYS.match(marker):
        return engine_file_reference()
    return wheel_reference()


def fill(markdown: str) -> str:
    """``markdown`` with the text after each marker line (``<!-- rotor COMMAND --help -->``,
    ``<!-- rotor commands -->``, ``<!-- engine-file keys -->``, ``<!-- standard wheels -->``)
    generated afresh from the code, up to the line ``<!-- end of generated text -->``
    (written where it is missing). A page whose text is current is returned unchanged."""
    return MARKER.sub(lambda m: f"{m.group(1)}\n{_generated(m.group(1))}\n{END}\n", markdown)


def write_generated_pages() -> list[str]:
    """Rewrite the generated text of :data:`GENERATED_PAGES` in docs/ (``make reference``);
    the pages that changed."""
    changed = []
    for name in GENERATED_PAGES:
        path = ROOT / "docs" / name
        text = path.read_text(encoding="utf-8")
        if fill(text) != text:
            path.write_text(fill(text), encoding="utf-8")
            changed.append(name)
    return changed


def on_page_markdown(markdown: str, page, config, files) -> str:
    """The generated text of every marker (:func:`fill`), so that the site shows the code as it
    is even where a page in the repository lags it; CHANGELOG.md for users."""
    if page is not None and page.file.src_uri == "changelog.md":
        markdown = changelog_for_users(markdown)
    return fill(markdown)


if __name__ == "__main__":
    print("\n".join(f"docs/{name} rewritten" for name in write_generated_pages()) or "docs/: generated text current")
