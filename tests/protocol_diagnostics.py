"""Factories of the diagnostics subpackage's results for the protocol test
(tests/project/test_result_protocol.py): the simulated recording of ``protocol_logs``, identified,
calibrated and diagnosed; inverse dynamics of a short simulated run."""

import functools
import tempfile
from pathlib import Path

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


@functools.cache
def speed_tdc() -> rotor.SpeedTdc:
    return rotor.tdc_from_speed(_engine(), analysis())


def tdc_check() -> rotor.TdcCheck:
    check = diagnosis().tdc_check
    assert check is not None, "diagnose checks the calibration's TDC against the recording"
    return check


def motored_gain() -> rotor.MotoredGain:
    """The gain of a simulated recording whose cycles 1 and 2 do not fire."""
    folder = Path(tempfile.mkdtemp(prefix="rotor-protocol-motored-"))
    log = rotor.simulated_recording(folder / "cut.txt", cycles=4, seed=5, motored_cycles=(1, 2))
    engine = _engine()
    rod_ratio = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
    a = rotor.analyze_log(
        log,
        "60-2",
        columns="time,pressure_v,encoder_v",
        compression_ratio=float(engine.pressure.compression_ratio),
        rod_ratio=rod_ratio,
    )
    return rotor.pressure_gain_from_motored(engine, a)


def _speed() -> np.ndarray:
    """Two cycles of a made-up crank speed on a 3° grid [rad/s]: 314 rad/s with a firing ripple."""
    theta = np.arange(2 * 240) * 3.0 * np.pi / 180
    return (314.0 + 4.0 * np.cos(theta + 0.3) + 1.5 * np.cos(0.5 * theta)).reshape(2, 240)


def indicated():
    return rotor.indicated_torque(_engine(), _speed(), load=50.0, regularisation="orders", max_order=12)


def harmonic():
    return rotor.harmonic_torque(_engine(), _speed(), load=50.0)


@functools.cache
def monitor_result():
    """The streaming monitor's result on 30 cycles of a four-cylinder engine's 60-2 tooth times at 1500 rpm with
    a firing ripple at order 2 (no engine file)."""
    from rotor.diagnostics.monitor import MisfireMonitor

    pitch = 2 * np.pi / 60
    ang = np.concatenate([r * 2 * np.pi + pitch * np.arange(58) for r in range(60)])
    omega = 157.0 * (1 + 0.01 * np.sin(2 * ang))
    t = np.concatenate([[0.0], np.cumsum(np.diff(ang) / omega[1:])])
    m = MisfireMonitor("60-2", tdc_deg=0.0, cylinders=4, firing_order=[1, 3, 4, 2])
    m.feed(t)
    m.close()
    return m.result()


FACTORIES = {
    "MonitorResult": monitor_result,
    "Identification": identification,
    "Calibration": calibration,
    "Diagnosis": diagnosis,
    "IndicatedTorque": indicated,
    "HarmonicTorque": harmonic,
    "SpeedTdc": speed_tdc,
    "TdcCheck": tdc_check,
    "MotoredGain": motored_gain,
}
