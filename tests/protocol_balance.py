"""Result types of balancing for the protocol test (``tests/project/test_result_protocol.py``)."""

import functools

import rotor


@functools.cache
def _engine():
    return rotor.load_engine("v8")


FACTORIES = {
    "Balance": lambda: rotor.balance(_engine(), orders=4),
}
