"""Result types of the dynamics subpackage for the protocol test (``tests/project/test_result_protocol.py``)."""

import functools

import rotor


@functools.cache
def _steady():
    return rotor.steady_state(rotor.load_engine("tue-single"), grid_deg=1.0)


@functools.cache
def _sweep():
    engine = rotor.prepare(rotor.load_engine("tue-single"), grid_deg=1.0)
    return rotor.steady_sweep(engine, rpm=[1500.0, 2500.0, 3500.0], progress=False)


FACTORIES = {
    "Orders": lambda: _steady().orders(),
    "SpeedResult": _steady,
    "SteadySweep": _sweep,
}
