"""Factories of the diagnostics room's results for the protocol test
(tests/test_result_protocol.py): the simulated recording of ``protocol_logs``, identified,
calibrated and diagnosed; inverse dynamics of a short simulated run."""

import functools

import numpy as np
from protocol_logs import analysis, recording

import rotor
from rotor.diagnostics.synthetic import BENCH_GAIN_PA_PER_V


@functools.cache
def _engine():
    return rotor.load_engine("tue-single")


@functools.cache
def identification() -> rotor.Identification:
    return rotor.identify(_engine(), analysis())


@functools.cache
def calibration() -> rotor.Calibration:
    return rotor.calibrate(_engine(), analysis(), pressure_gain=BENCH_GAIN_PA_PER_V, refine=False)


@functools.cache
def diagnosis():
    return rotor.diagnose(_engine(), recording(), calibration(), columns="time,-,encoder_v", wheel="60-2")


def _speed() -> np.ndarray:
    """Two cycles of a made-up crank speed on a 3° grid [rad/s]: 314 rad/s with a firing ripple."""
    theta = np.arange(2 * 240) * 3.0 * np.pi / 180
    return (314.0 + 4.0 * np.cos(theta + 0.3) + 1.5 * np.cos(0.5 * theta)).reshape(2, 240)


def indicated():
    return rotor.indicated_torque(_engine(), _speed(), load=50.0, regularisation="orders", max_order=12)


def harmonic():
    return rotor.harmonic_torque(_engine(), _speed(), load=50.0)


FACTORIES = {
    "Identification": identification,
    "Calibration": calibration,
    "Diagnosis": diagnosis,
    "IndicatedTorque": indicated,
    "HarmonicTorque": harmonic,
}
