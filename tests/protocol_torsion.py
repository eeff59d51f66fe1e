"""Result types of the torsion subpackage for the protocol test (``tests/project/test_result_protocol.py``)."""

import functools

import rotor


@functools.cache
def _engine():
    return rotor.load_engine("mwm6")


FACTORIES = {
    "TorsionalModes": lambda: rotor.torsional_modes(_engine()),
    "Campbell": lambda: rotor.campbell(_engine(), rpm=(600.0, 2600.0)),
}
