"""The one result protocol, as a check any test can call on any result object.

Each subpackage keeps the factories of its result types in ``tests/protocol_<subpackage>.py`` as
``FACTORIES = {"ClassName": callable returning an instance, ...}``;
``tests/project/test_result_protocol.py`` runs :func:`check_result_protocol` on every one and
checks that every subclass of :class:`rotor.results.Result` has a factory."""

import json
import math

import matplotlib
import numpy as np
import pandas as pd

from rotor.results import Result

matplotlib.use("Agg")


def _no_nan(x, path="$"):
    if isinstance(x, dict):
        for k, v in x.items():
            assert isinstance(k, str), f"{path}: key {k!r} is not a string"
            _no_nan(v, f"{path}.{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _no_nan(v, f"{path}[{i}]")
    elif isinstance(x, float):
        assert math.isfinite(x), f"{path}: {x} (use None)"
    else:
        assert x is None or isinstance(x, (str, int, bool)), f"{path}: {type(x).__name__} is not plain JSON"


def check_result_protocol(result):
    """summary() -> str of one screen; to_pandas() -> DataFrame with units in its column
    names; to_json_dict() -> plain JSON with no NaN; plot(ax=None) returns what it drew;
    a short repr; _repr_html_."""
    import matplotlib.pyplot as plt

    assert isinstance(result, Result), f"{type(result).__name__} does not inherit rotor.results.Result"
    s = result.summary()
    assert isinstance(s, str) and s.strip(), "summary() must return text"
    assert len(s.splitlines()) <= 60, f"summary() is {len(s.splitlines())} lines: one screen is at most 60"
    df = result.to_pandas()
    assert isinstance(df, pd.DataFrame) and len(df) > 0, "to_pandas() must return a non-empty DataFrame"
    d = result.to_json_dict()
    assert isinstance(d, dict) and d, "to_json_dict() must return a non-empty dict"
    _no_nan(d)
    assert json.loads(json.dumps(d, allow_nan=False)) == d
    r = repr(result)
    assert len(r) <= 300, f"repr is {len(r)} characters: keep it short"
    assert type(result).__name__ in r
    html = result._repr_html_()
    assert isinstance(html, str) and html
    drawn = result.plot()
    assert drawn is not None, "plot() must return what it drew"
    axes = np.ravel(np.asarray(drawn, dtype=object))
    assert all(hasattr(a, "figure") for a in axes), "plot() returns Axes"
    fig, ax = plt.subplots()
    try:
        again = result.plot(ax=ax) if len(axes) == 1 else result.plot(ax=axes)
        assert again is not None
    finally:
        plt.close("all")
