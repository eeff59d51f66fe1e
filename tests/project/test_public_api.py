"""The public names: listed once (``rotor/__init__.pyi``), each from the module that
defines it; every public function says what it takes and gives: type hints on every
argument and the return, and a docstring (units are in the docstrings)."""

import ast
import importlib
import inspect
import os
import types

import pytest
from conftest import ROOT

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


def _stub() -> list[tuple[str, str]]:
    """(public name, module relative to rotor) as ``rotor/__init__.pyi`` lists them, in order."""
    tree = ast.parse((ROOT / "rotor" / "__init__.pyi").read_text(encoding="utf-8"))
    return [(a.name, node.module) for node in tree.body if isinstance(node, ast.ImportFrom) for a in node.names]


def _defined_at_top(module) -> set[str]:
    """The names a module's own source binds at its top level (def, class, assignment)."""
    tree = ast.parse(inspect.getsource(module))
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def test_the_public_names_are_listed_once():
    """``rotor/__init__.pyi`` names each public name once, and ``__all__`` and ``dir`` are built from it."""
    names = [name for name, _ in _stub()]
    assert len(names) == len(set(names))
    assert sorted(names) == list(rotor.__all__)
    assert set(rotor.__all__) <= set(dir(rotor))


def test_every_public_name_comes_from_the_module_that_defines_it():
    """Each name is imported from the module whose own source defines it, not from one that
    imports it from elsewhere."""
    for name, module in _stub():
        mod = importlib.import_module(f"rotor.{module}")
        value = getattr(rotor, name)
        assert value is getattr(mod, name), name
        assert name in _defined_at_top(mod), f"rotor.{module} does not define {name}"
        if inspect.isclass(value) or callable(value):
            assert value.__module__ == mod.__name__, f"{name} is defined in {value.__module__}, not rotor.{module}"


def test_subpackages_and_modules_are_attributes_and_other_names_are_not():
    assert isinstance(rotor.engine, types.ModuleType)
    assert rotor.cycles.__name__ == "rotor.cycles"
    with pytest.raises(AttributeError):
        rotor.no_such_name  # noqa: B018


@pytest.mark.parametrize("order", ["import rotor, jax.numpy as jnp", "import jax.numpy as jnp, rotor"])
def test_importing_rotor_switches_jax_to_float64(order):
    """An array made with JAX right after ``import rotor`` is float64, whether JAX was
    imported before rotor or after, and ``import rotor`` itself still imports no JAX."""
    import subprocess
    import sys

    code = f"{order}; print(jnp.zeros(1).dtype)"
    env = {k: v for k, v in os.environ.items() if k != "JAX_ENABLE_X64"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "float64"
    bare = subprocess.run(
        [sys.executable, "-c", "import sys, rotor; print('jax' in sys.modules)"],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    assert bare.stdout.strip() == "False"
