"""Result types of the dynamics room for the protocol test (``tests/test_result_protocol.py``)."""

import functools

import rotor


@functools.cache
def _steady():
    return rotor.steady_state(rotor.load_engine("tue-single"), grid_deg=1.0)


FACTORIES = {
    "Orders": lambda: _steady().orders(),
    "SpeedResult": _steady,
}
