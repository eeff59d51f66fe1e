"""mkdocs hooks: the notebooks live in notebooks/ (beside the package, where `make
notebooks` and the tests run them); they become pages under notebooks/ here, before
mkdocs-jupyter turns them into HTML; CHANGELOG.md becomes changelog.md; and
``<!-- rotor COMMAND --help -->`` in a page becomes what that command prints, so that
the command-line page never falls behind the parser."""

from __future__ import annotations

import contextlib
import io
import os
import re
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
    return files


HELP = re.compile(r"^<!-- (rotor(?: [a-z-]+)? --help) -->$", re.MULTILINE)


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


def on_page_markdown(markdown: str, page, config, files) -> str:
    """``<!-- rotor COMMAND --help -->`` on a line of its own becomes that help text."""
    return HELP.sub(lambda m: f"```text\n$ {m.group(1)}\n{rotor_help(m.group(1))}\n```", markdown)
