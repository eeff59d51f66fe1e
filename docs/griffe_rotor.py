"""A griffe extension for rotor's docstrings, so that they render as Markdown.

rotor writes plain docstrings: ``**Arguments:**`` followed directly by a ``- name: …
[unit]`` list, and Sphinx roles (``:class:`Engine```) here and there. Markdown needs a
blank line before a list and knows no roles: this adds the one and turns the other into
code. It also says "base layer" and "subpackage" where a docstring uses the project's
shorthand for them, and "the fixed frame" for the mechanical ground a damper acts
against, so that the site speaks one vocabulary.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:class|func|meth|mod|attr|data|obj|exc):`~?([^`]+)`")
_WORDS = ((re.compile(r"\bthe(\s+)ground\b"), r"the\1fixed frame"),)


def markdown(text: str) -> str:
    """``text`` with Sphinx roles as code and a blank line before every list."""
    text = _ROLE.sub(r"`\1`", text)
    for pattern, word in _WORDS:
        text = pattern.sub(word, text)
    out: list[str] = []
    for line in text.split("\n"):
        stripped = line.lstrip()
        is_item = stripped.startswith(("- ", "* ")) or bool(re.match(r"\d+\. ", stripped))
        if is_item and out and out[-1].strip() and not _in_list(out):
            out.append("")
        out.append(line)
    return "\n".join(out)


def _in_list(lines: list[str]) -> bool:
    """Whether the last lines are a list item or its indented continuation."""
    for line in reversed(lines):
        if not line.strip():
            return False
        s = line.lstrip()
        if s.startswith(("- ", "* ")) or re.match(r"\d+\. ", s):
            return True
        if line == s:  # unindented text that is not an item: a paragraph
            return False
    return False


class RotorDocstrings(griffe.Extension):
    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)
