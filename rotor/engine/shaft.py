"""The crankshaft as a beam: where its throws, webs and main journals lie along its axis.

Axial positions x [m] are measured from main journal 1 at the front (x = 0) towards the
flywheel. The J main journals (``[crankshaft] main_journals``, default throws + 1) are
``journal_spacing_m`` apart; the throws are shared evenly between the J − 1 spans (q =
throws / (J − 1) in each) and sit at the middles of q equal parts of their span, throw 1
at the front. The two webs of a throw (2k − 1 in front, 2k behind) sit a quarter of that
part's length in front of and behind it. This is the split ("разрезная") beam of the
textbook calculation of main journal loads: each span is simply supported on its two
journals (Kolchin & Demidov, "Design of automotive engines", the main journal loads;
Shishkov (2014) §3.2.8).

Default spacing: 1.25 bores per throw in a span (Kolchin & Demidov give a cylinder
spacing of 1.15…1.35 bores for inline engines).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from jaxtyping import Array

from ..cycles import array_module

if TYPE_CHECKING:
    from .model import Engine

__all__ = [
    "DEFAULT_SPACING_BORES",
    "journal_count",
    "journal_spacing_m",
    "throws_per_span",
    "throw_positions_m",
    "journal_positions_m",
    "web_positions_m",
    "span_of_throw",
]

DEFAULT_SPACING_BORES = 1.25
"""Main journal spacing per throw in a span, in bores, when the file gives none."""


def journal_count(engine: Engine) -> int:
    """The number of main journals: ``[crankshaft] main_journals``, or throws + 1."""
    j = engine.crankshaft.main_journals
    return int(j) if j is not None else engine.throw_count + 1


def throws_per_span(engine: Engine) -> int:
    """q, the throws between two neighbouring main journals."""
    return engine.throw_count // (journal_count(engine) - 1)


def journal_spacing_m(engine: Engine) -> Array:
    """Distance between neighbouring main journals [m] (the file's, or 1.25 bores per throw)."""
    s = engine.crankshaft.journal_spacing_m
    if s is not None:
        return s
    bore = engine.geometry.bore_m
    return DEFAULT_SPACING_BORES * array_module(bore).asarray(bore) * throws_per_span(engine)


def span_of_throw(engine: Engine) -> np.ndarray:
    """The span (0-based: between journals i and i + 1) of each throw, shape (throws,)."""
    return np.arange(engine.throw_count) // throws_per_span(engine)


def throw_positions_m(engine: Engine) -> Array:
    """Axial position of each throw's crank pin centre [m], shape (throws,)."""
    q = throws_per_span(engine)
    spacing = journal_spacing_m(engine)
    xp = array_module(spacing)  # NumPy for a concrete engine: no program compiled
    k = xp.arange(engine.throw_count, dtype=xp.float64)
    return (k + 0.5) * (xp.asarray(spacing) / q)


def journal_positions_m(engine: Engine) -> Array:
    """Axial position of each main journal [m], shape (journals,); journal 1 at 0."""
    spacing = journal_spacing_m(engine)
    xp = array_module(spacing)
    return xp.arange(journal_count(engine), dtype=xp.float64) * xp.asarray(spacing)


def web_positions_m(engine: Engine) -> Array:
    """Axial position of each crank web [m], shape (2·throws,): webs 2k − 1 and 2k (1-based)
    a quarter of the throw's part of its span in front of and behind throw k."""
    q = throws_per_span(engine)
    x = throw_positions_m(engine)
    xp = array_module(x)
    quarter = xp.asarray(journal_spacing_m(engine)) / q / 4
    return xp.stack([x - quarter, x + quarter], axis=-1).reshape(-1)
