"""Factories of the torsional forced response's and transient's results for the
result-protocol test (coarse grids, few speeds, a short free-vibration run)."""

import rotor


def _response():
    return rotor.torsional_response(rotor.load_engine("mwm6"), 1500, grid_deg=2.0)


def _sweep():
    return rotor.torsional_sweep(rotor.load_engine("mwm6"), [1200, 1800, 2400], grid_deg=2.0)


def _run():
    chain = rotor.TorsionalChain([211.4, 8.3], [9.775e6], names=["engine", "propeller"])
    return rotor.torsional_simulate(chain, duration_s=0.05, initial=([0.0, 1e-3], [0.0, 0.0]), samples=200)


FACTORIES = {
    "TorsionalResponse": _response,
    "TorsionalSweep": _sweep,
    "TorsionalRun": _run,
}
