"""Every public function says what it takes and gives: type hints on every argument and
the return, and a docstring (units are in the docstrings)."""

import inspect

import pytest

import rotor


def _public_functions():
    for name in rotor.__all__:
        obj = getattr(rotor, name)
        if inspect.isfunction(obj):
            yield name, obj
        elif inspect.isclass(obj):
            for attr, member in vars(obj).items():
                if not attr.startswith("_") and inspect.isfunction(member):
                    yield f"{name}.{attr}", member


FUNCTIONS = sorted(_public_functions())


@pytest.mark.parametrize("name,fn", FUNCTIONS, ids=[n for n, _ in FUNCTIONS])
def test_public_function_is_typed_and_documented(name, fn):
    sig = inspect.signature(fn)
    missing = [
        p.name
        for p in sig.parameters.values()
        if p.name not in ("self", "cls") and p.annotation is inspect.Parameter.empty
    ]
    assert not missing, f"{name}: arguments without a type hint: {missing}"
    assert sig.return_annotation is not inspect.Signature.empty, f"{name}: no return type hint"
    assert inspect.getdoc(fn), f"{name}: no docstring"
