"""The trigger-pattern catalogue: every entry consistent, its reference page current, and
`rotor wheels` listing it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rotor.cli import main
from rotor.logs.catalogue import CATALOGUE, catalogue_markdown, edge_strip

PAGE = Path(__file__).resolve().parents[2] / "docs" / "reference" / "trigger-patterns.md"


def test_reference_page_is_the_catalogue():
    assert PAGE.read_text(encoding="utf-8") == catalogue_markdown(), (
        "docs/reference/trigger-patterns.md is stale: write rotor.logs.catalogue.catalogue_markdown() to it"
    )


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_every_pattern_is_whole(name):
    p = CATALOGUE[name]
    a = p.angles_deg()
    assert a.size >= 1 and np.all((a >= 0) & (a < p.period_deg))
    assert np.isclose(p.intervals_deg().sum(), p.period_deg)
    assert p.source, "every pattern names where its geometry comes from"
    # where both polarities are stated, they alternate round the turn
    if p.rising_deg and p.falling_deg and len(p.rising_deg) == len(p.falling_deg):
        both = sorted([(x, 1) for x in p.rising_deg] + [(x, 0) for x in p.falling_deg])
        kinds = [k for _, k in both]
        assert all(kinds[i] != kinds[i + 1] for i in range(len(kinds) - 1))
    assert len(edge_strip(p)) == 72


def test_rotor_wheels_lists_and_shows(capsys):
    assert main(["wheels"]) in (0, None)
    out = capsys.readouterr().out
    assert all(name in out for name in CATALOGUE)
    assert main(["wheels", "TT_36_2_1", "--json"]) in (0, None)
    data = json.loads(capsys.readouterr().out)
    assert data["name"] == "36-2-1" and len(data["rising_deg"]) == 33


def test_rotor_wheels_refuses_an_unknown_name(capsys):
    assert main(["wheels", "mazda-nb-crnk"]) == 2
    err = capsys.readouterr().err
    assert "closest: mazda-nb-crank" in err and len(err.strip().splitlines()) == 1
