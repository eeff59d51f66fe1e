"""Result types of the bearing loads for the protocol test (``tests/project/test_result_protocol.py``)."""

import functools

import rotor


@functools.cache
def _engine():
    return rotor.load_engine("4chn15")


FACTORIES = {
    "BearingLoads": lambda: rotor.bearing_loads(_engine(), step_deg=10.0),
}
