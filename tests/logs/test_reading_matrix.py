"""A matrix of simulated trigger recordings with the defects real ones carry, each read with
nothing but its signal: every catalogue pattern's own signal (either polarity, inverted,
timing jitter, the edges next to its widest gap displaced by up to 0.3 of a pitch, a glitch,
a speed that swings and ramps) is read as that pattern or refused, never as another wheel;
named, it is read as itself."""

from __future__ import annotations

import itertools

import pytest

from rotor.errors import LogError
from rotor.logs.catalogue import CATALOGUE, find_pattern
from rotor.logs.recording import PatternReading, read_wheel
from rotor.logs.synthetic import pattern_capture


def _read_as(log, wheel=None) -> str | None:
    try:
        r = read_wheel(log, wheel)
    except LogError:
        return None
    return r.pattern.name if isinstance(r, PatternReading) else r.wheel.spec


DEFECTS = list(
    itertools.product((False, True), (0.0, 0.5), (0.0, 0.3), (False, True))
)  # invert, jitter, displace, glitch
CLEAN, INVERTED = DEFECTS.index((False, 0.0, 0.0, False)), DEFECTS.index((True, 0.0, 0.0, False))
SUITE_SHARE = (
    4  # of the 16 defect cells of a pattern, the suite reads these 4 (each pattern its own, all cells covered)
)


def _cells(k: int) -> list[int]:
    """The defect cells read in the suite for the k-th pattern: clean and inverted, and two more in turn."""
    rest = [i for i in range(len(DEFECTS)) if i not in (CLEAN, INVERTED)]
    return [CLEAN, INVERTED] + [rest[(2 * k + j) % len(rest)] for j in range(SUITE_SHARE - 2)]


_READ: dict = {}


def _cell(name: str, i: int) -> str | None:
    if (name, i) not in _READ:
        inv, jit, dis, gl = DEFECTS[i]
        p = CATALOGUE[name]
        _READ[(name, i)] = _read_as(pattern_capture(p, invert=inv, jitter_deg=jit, displace=dis, glitch=gl, seed=i))
    return _READ[(name, i)]


@pytest.mark.parametrize("k,name", list(enumerate(CATALOGUE)))
def test_a_patterns_own_signal_reads_as_itself_or_is_refused(k, name):
    cells = _cells(k)
    got = {i: _cell(name, i) for i in cells}
    wrong = [(DEFECTS[i], g) for i, g in got.items() if g is not None and g != name]
    assert not wrong, f"{name} read as another wheel: {wrong}"
    if not CATALOGUE[name].evenly_spaced:
        # clean and inverted, it is read (a pattern that timing alone cannot tell is refused, by design)
        assert got[CLEAN] == name and got[INVERTED] == name


def test_most_of_the_matrix_is_read():
    cells = [(name, i) for k, name in enumerate(CATALOGUE) if not CATALOGUE[name].evenly_spaced for i in _cells(k)]
    read = sum(_cell(name, i) == name for name, i in cells)
    assert read / len(cells) >= 0.8, f"{read} of {len(cells)} read"


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_a_named_pattern_reads_its_own_signal(name):
    p = CATALOGUE[name]
    assert _read_as(pattern_capture(p), name) == name


def test_a_wheel_of_two_equal_halves_is_never_read_as_its_half():
    """36-2-2 (two equal halves) and 18-2 give the same edges at speeds a factor 2 apart:
    read as the catalogue's 36-2-2, or refused naming both, never as 18-2."""
    p = find_pattern("36-2-2")
    for k, jitter in enumerate((0.0, 0.5, 0.8)):
        try:
            got = _read_as(pattern_capture(p, jitter_deg=jitter, seed=k), None)
        except LogError as e:
            assert "18-2" in str(e) and "36-2-2" in str(e)
            continue
        assert got in ("36-2-2", None)
