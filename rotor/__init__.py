"""rotor: rotational dynamics of piston engines.

Crank kinematics, reduced inertia I(θ), gas and inertia torques, and the crankshaft's
speed fluctuation, in JAX.

Importing rotor changes one process-wide setting: JAX's float64 (``jax_enable_x64``),
which rotor's numerics need, set when JAX is imported (at once if it is already). JAX's
persistent compilation cache stays as the user left it: the ``rotor`` command switches it
on, and :func:`rotor.enable_compilation_cache` does so in Python.

Importing rotor is cheap: each public name is imported from its module on first use
(``rotor.steady_state`` imports :mod:`rotor.dynamics.steady`, and JAX with it), so that
``rotor --help`` and the commands that compute nothing with JAX start fast. ``dir(rotor)``
and ``__all__`` list every public name all the same.
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import TYPE_CHECKING, Any

from .cache import on_jax_import as _on_jax_import
from .cache import submodules_on_demand as _submodules_on_demand


def _enable_x64(jax: ModuleType) -> None:
    jax.config.update("jax_enable_x64", True)


_on_jax_import(_enable_x64)

if TYPE_CHECKING:  # what type checkers and the documentation see; at run time, _PUBLIC
    from .cache import enable_compilation_cache
    from .design.balance import Balance, balance
    from .design.bearings import BearingLoads, bearing_loads
    from .design.flywheel import (
        DiscFlywheel,
        FlywheelDesign,
        OperatingPoint,
        TextbookFlywheel,
        design_flywheel,
        inertia_for_delta,
        lightest_disc,
        textbook_flywheel,
    )
    from .design.report import Report, report
    from .diagnostics.bulk import analyze_many, diagnose_many, expand_logs
    from .diagnostics.calibration import Calibration, Diagnosis, calibrate, diagnose, measured_imep, preset_calibration
    from .diagnostics.identification import Identification, identify
    from .diagnostics.inverse import (
        HarmonicTorque,
        IndicatedTorque,
        TorqueOrders,
        harmonic_response,
        harmonic_torque,
        indicated_torque,
    )
    from .diagnostics.misfire import contribution_index
    from .diagnostics.pegging import MotoredGain, pressure_gain_from_motored
    from .diagnostics.phase import SpeedTdc, TdcCheck, TdcNotDetermined, tdc_from_speed
    from .diagnostics.synthetic import simulated_recording, simulated_tooth_errors, simulated_tooth_times
    from .dynamics.combustion import combustion_pattern
    from .dynamics.crank_train import CrankTrain, crank_train
    from .dynamics.loads import (
        ConstantLoad,
        Governor,
        Load,
        LoadStep,
        PolynomialLoad,
        PropellerLoad,
        TableLoad,
        parse_load,
    )
    from .dynamics.prepared import PreparedEngine, prepare
    from .dynamics.result import Orders, SpeedResult
    from .dynamics.steady import steady_state
    from .dynamics.sweep import SteadySweep, steady_sweep
    from .dynamics.transient import simulate
    from .engine.file import engine_from_dict, load_engine, preset_names
    from .engine.forces import (
        crank_forces,
        cylinder_gas_torques,
        cylinder_pressure,
        gas_torque,
        imep_pa,
        indicated_power_w,
        mean_gas_torque,
        reciprocating_inertia_torque,
        total_torque,
    )
    from .engine.friction import Friction
    from .engine.inertia import (
        cylinder_inertia,
        inertia_coefficients,
        mean_reduced_inertia,
        reduced_inertia,
        reduced_inertia_derivative,
    )
    from .engine.kinematics import PistonMotion, RodMotion, mean_piston_speed, piston_motion, rod_motion
    from .engine.mechanism import engine_piston_motion
    from .engine.model import (
        Articulated,
        Counterweights,
        Crankshaft,
        Engine,
        Geometry,
        Layout,
        Masses,
        Operating,
        Torsion,
    )
    from .engine.pressure import MotoredCycle, NoPressure, PressureSource, PressureTable, WiebeCycle, periodic_pchip
    from .engine.summary import EngineCurves, EngineSummary, engine_curves, engine_summary
    from .engine.table import CrankTable, crank_table
    from .errors import EngineError, InternalError, LogError, NoSteadyStateError, RotorError, SolverError
    from .logs.analysis import LogAnalysis, analyze_log, tdc_from_pressure
    from .logs.edges import Edges, find_edges
    from .logs.pattern import locate_teeth
    from .logs.reader import Log, read_log
    from .logs.wheel import ToothErrors, ToothTrack, Wheel, estimate_tooth_errors, firing_orders, parse_wheel
    from .results import Result
    from .torsion.campbell import Campbell, campbell
    from .torsion.model import TorsionalChain, crank_throw_stiffness, shaft_stiffness, torsional_chain
    from .torsion.modes import TorsionalModes, holzer_frequencies, torsional_modes
    from .torsion.response import TorsionalResponse, TorsionalSweep, torsional_response, torsional_sweep
    from .torsion.transient import TorsionalRun, torsional_simulate

__version__ = "0.1.0"

# Each public name and the module (relative to rotor) it comes from: to add a public name,
# add it here, to the TYPE_CHECKING imports above and to __all__ (tests/test_cli_latency.py
# checks that the three agree).
_PUBLIC: dict[str, tuple[str, ...]] = {
    "cache": ("enable_compilation_cache",),
    "design.balance": (
        "Balance",
        "balance",
    ),
    "design.bearings": (
        "BearingLoads",
        "bearing_loads",
    ),
    "design.flywheel": (
        "DiscFlywheel",
        "FlywheelDesign",
        "OperatingPoint",
        "TextbookFlywheel",
        "design_flywheel",
        "inertia_for_delta",
        "lightest_disc",
        "textbook_flywheel",
    ),
    "design.report": (
        "Report",
        "report",
    ),
    "diagnostics.bulk": ("analyze_many", "diagnose_many", "expand_logs"),
    "diagnostics.calibration": (
        "Calibration",
        "Diagnosis",
        "calibrate",
        "diagnose",
        "measured_imep",
        "preset_calibration",
    ),
    "diagnostics.identification": (
        "Identification",
        "identify",
    ),
    "diagnostics.inverse": (
        "HarmonicTorque",
        "IndicatedTorque",
        "TorqueOrders",
        "harmonic_response",
        "harmonic_torque",
        "indicated_torque",
    ),
    "diagnostics.misfire": ("contribution_index",),
    "diagnostics.pegging": (
        "MotoredGain",
        "pressure_gain_from_motored",
    ),
    "diagnostics.phase": (
        "SpeedTdc",
        "TdcCheck",
        "TdcNotDetermined",
        "tdc_from_speed",
    ),
    "diagnostics.synthetic": (
        "simulated_recording",
        "simulated_tooth_errors",
        "simulated_tooth_times",
    ),
    "dynamics.combustion": ("combustion_pattern",),
    "dynamics.crank_train": (
        "CrankTrain",
        "crank_train",
    ),
    "dynamics.loads": (
        "ConstantLoad",
        "Governor",
        "Load",
        "LoadStep",
        "PolynomialLoad",
        "PropellerLoad",
        "TableLoad",
        "parse_load",
    ),
    "dynamics.result": (
        "Orders",
        "SpeedResult",
        "SteadySweep",
    ),
    "dynamics.prepared": ("PreparedEngine", "prepare"),
    "dynamics.steady": ("steady_state",),
    "dynamics.sweep": ("SteadySweep", "steady_sweep"),
    "dynamics.transient": ("simulate",),
    "engine.file": (
        "engine_from_dict",
        "load_engine",
        "preset_names",
    ),
    "engine.forces": (
        "crank_forces",
        "cylinder_gas_torques",
        "cylinder_pressure",
        "gas_torque",
        "imep_pa",
        "indicated_power_w",
        "mean_gas_torque",
        "reciprocating_inertia_torque",
        "total_torque",
    ),
    "engine.friction": ("Friction",),
    "engine.inertia": (
        "cylinder_inertia",
        "inertia_coefficients",
        "mean_reduced_inertia",
        "reduced_inertia",
        "reduced_inertia_derivative",
    ),
    "engine.kinematics": (
        "PistonMotion",
        "RodMotion",
        "mean_piston_speed",
        "piston_motion",
        "rod_motion",
    ),
    "engine.mechanism": ("engine_piston_motion",),
    "engine.model": (
        "Articulated",
        "Counterweights",
        "Crankshaft",
        "Engine",
        "Geometry",
        "Layout",
        "Masses",
        "Operating",
        "Torsion",
    ),
    "engine.pressure": (
        "MotoredCycle",
        "NoPressure",
        "PressureSource",
        "PressureTable",
        "WiebeCycle",
        "periodic_pchip",
    ),
    "engine.summary": (
        "EngineCurves",
        "EngineSummary",
        "engine_curves",
        "engine_summary",
    ),
    "engine.table": (
        "CrankTable",
        "crank_table",
    ),
    "errors": (
        "EngineError",
        "InternalError",
        "LogError",
        "NoSteadyStateError",
        "RotorError",
        "SolverError",
    ),
    "logs.analysis": (
        "LogAnalysis",
        "analyze_log",
        "tdc_from_pressure",
    ),
    "logs.edges": (
        "Edges",
        "find_edges",
    ),
    "logs.pattern": ("locate_teeth",),
    "logs.reader": (
        "Log",
        "read_log",
    ),
    "logs.wheel": (
        "ToothErrors",
        "ToothTrack",
        "Wheel",
        "estimate_tooth_errors",
        "firing_orders",
        "parse_wheel",
    ),
    "results": ("Result",),
    "torsion.campbell": (
        "Campbell",
        "campbell",
    ),
    "torsion.model": (
        "TorsionalChain",
        "crank_throw_stiffness",
        "shaft_stiffness",
        "torsional_chain",
    ),
    "torsion.modes": (
        "TorsionalModes",
        "holzer_frequencies",
        "torsional_modes",
    ),
    "torsion.response": (
        "TorsionalResponse",
        "TorsionalSweep",
        "torsional_response",
        "torsional_sweep",
    ),
    "torsion.transient": (
        "TorsionalRun",
        "torsional_simulate",
    ),
}
_MODULE_OF = {name: module for module, names in _PUBLIC.items() for name in names}

__all__ = [
    "Articulated",
    "Balance",
    "BearingLoads",
    "Calibration",
    "Campbell",
    "ConstantLoad",
    "Counterweights",
    "CrankTable",
    "CrankTrain",
    "Crankshaft",
    "Diagnosis",
    "DiscFlywheel",
    "Edges",
    "Engine",
    "EngineCurves",
    "EngineError",
    "EngineSummary",
    "FlywheelDesign",
    "Friction",
    "Geometry",
    "Governor",
    "HarmonicTorque",
    "Identification",
    "IndicatedTorque",
    "InternalError",
    "Layout",
    "Load",
    "LoadStep",
    "Log",
    "LogAnalysis",
    "LogError",
    "Masses",
    "MotoredCycle",
    "MotoredGain",
    "NoPressure",
    "NoSteadyStateError",
    "Operating",
    "OperatingPoint",
    "Orders",
    "PistonMotion",
    "PolynomialLoad",
    "PreparedEngine",
    "PressureSource",
    "PressureTable",
    "PropellerLoad",
    "Report",
    "Result",
    "RodMotion",
    "RotorError",
    "SolverError",
    "SpeedResult",
    "SpeedTdc",
    "SteadySweep",
    "TableLoad",
    "TdcCheck",
    "TdcNotDetermined",
    "TextbookFlywheel",
    "ToothErrors",
    "ToothTrack",
    "TorqueOrders",
    "Torsion",
    "TorsionalChain",
    "TorsionalModes",
    "TorsionalResponse",
    "TorsionalRun",
    "TorsionalSweep",
    "Wheel",
    "WiebeCycle",
    "analyze_log",
    "analyze_many",
    "balance",
    "bearing_loads",
    "calibrate",
    "campbell",
    "combustion_pattern",
    "contribution_index",
    "crank_forces",
    "crank_table",
    "crank_throw_stiffness",
    "crank_train",
    "cylinder_gas_torques",
    "cylinder_inertia",
    "cylinder_pressure",
    "design_flywheel",
    "diagnose",
    "diagnose_many",
    "enable_compilation_cache",
    "engine_curves",
    "engine_from_dict",
    "engine_piston_motion",
    "engine_summary",
    "estimate_tooth_errors",
    "expand_logs",
    "find_edges",
    "firing_orders",
    "gas_torque",
    "harmonic_response",
    "harmonic_torque",
    "holzer_frequencies",
    "identify",
    "imep_pa",
    "indicated_power_w",
    "indicated_torque",
    "inertia_coefficients",
    "inertia_for_delta",
    "lightest_disc",
    "load_engine",
    "locate_teeth",
    "mean_gas_torque",
    "mean_piston_speed",
    "mean_reduced_inertia",
    "measured_imep",
    "parse_load",
    "parse_wheel",
    "periodic_pchip",
    "piston_motion",
    "prepare",
    "preset_calibration",
    "preset_names",
    "pressure_gain_from_motored",
    "read_log",
    "reciprocating_inertia_torque",
    "reduced_inertia",
    "reduced_inertia_derivative",
    "report",
    "rod_motion",
    "shaft_stiffness",
    "simulate",
    "simulated_recording",
    "simulated_tooth_errors",
    "simulated_tooth_times",
    "steady_state",
    "steady_sweep",
    "tdc_from_pressure",
    "tdc_from_speed",
    "textbook_flywheel",
    "torsional_chain",
    "torsional_modes",
    "torsional_response",
    "torsional_simulate",
    "torsional_sweep",
    "total_torque",
]


_submodule = _submodules_on_demand(__name__)


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (and then kept here), or a
    submodule (``rotor.engine``)."""
    module = _MODULE_OF.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
        globals()[name] = value
        return value
    return _submodule(name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
