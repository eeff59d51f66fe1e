"""Every result type speaks the one protocol (``rotor.results.Result``): summary, tidy
pandas, JSON without NaN, plot(ax=), a short repr and HTML. Factories live beside each
subpackage's tests in ``tests/protocol_<subpackage>.py``."""

import importlib

import pytest
from result_protocol import check_result_protocol

import rotor
from rotor.results import Result

SUBPACKAGES = [
    "engine",
    "bearings",
    "balance",
    "dynamics",
    "logs",
    "diagnostics",
    "design",
    "torsion",
    "torsion_response",
]


def _factories():
    out = {}
    for subpackage in SUBPACKAGES:
        try:
            mod = importlib.import_module(f"protocol_{subpackage}")
        except ModuleNotFoundError:
            continue
        out.update(mod.FACTORIES)
    return out


FACTORIES = _factories()


def _all_result_types():
    seen, todo = set(), list(Result.__subclasses__())
    while todo:
        c = todo.pop()
        if c not in seen:
            seen.add(c)
            todo.extend(c.__subclasses__())
    return sorted(c.__name__ for c in seen if c.__module__.startswith("rotor."))


def test_every_result_type_has_a_factory():
    assert rotor  # every subpackage imported
    missing = [n for n in _all_result_types() if n not in FACTORIES]
    assert not missing, f"result types without a protocol check: {missing}"


@pytest.mark.parametrize("name", sorted(FACTORIES))
def test_result_speaks_the_protocol(name):
    result = FACTORIES[name]()
    assert type(result).__name__ == name
    check_result_protocol(result)
