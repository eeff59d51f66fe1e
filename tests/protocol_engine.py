"""Result types of the engine subpackage for the protocol test (``tests/project/test_result_protocol.py``)."""

import functools

import rotor
from rotor.engine.summary import engine_curves


@functools.cache
def _engine():
    return rotor.load_engine("tue-single")


FACTORIES = {
    "CrankTable": lambda: rotor.crank_table(_engine(), step_deg=10.0),
    "EngineCurves": lambda: engine_curves(_engine(), points_per_deg=1),
    "EngineSummary": lambda: rotor.engine_summary(_engine()),
}
