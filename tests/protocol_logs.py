"""Factories of the logs subpackage's results for the protocol test (tests/project/test_result_protocol.py):
a simulated bench recording of a few cycles, analysed."""

import functools
import tempfile
from pathlib import Path

import rotor


@functools.cache
def recording() -> Path:
    """A 4-cycle simulated tue-single bench recording (time, pressure, encoder), written once."""
    folder = Path(tempfile.mkdtemp(prefix="rotor-protocol-logs-"))
    return rotor.simulated_recording(folder / "protocol.txt", cycles=4)


@functools.cache
def analysis() -> rotor.LogAnalysis:
    """The recording analysed with its pressure channel (TDC by the polytropic fit)."""
    engine = rotor.load_engine("tue-single")
    rod_ratio = float(engine.geometry.stroke_m) / 2 / float(engine.geometry.rod_length_m)
    return rotor.analyze_log(
        recording(),
        "60-2",
        columns="time,pressure_v,encoder_v",
        compression_ratio=8.5,
        rod_ratio=rod_ratio,
    )


FACTORIES = {
    "LogAnalysis": analysis,
    "ToothErrors": lambda: analysis().tooth_errors,
}
