"""rotor: rotational dynamics of piston engines.

Crank kinematics, reduced inertia I(θ), gas and inertia torques, and the crankshaft's
speed fluctuation, in JAX.

Importing rotor changes one process-wide setting: JAX's float64 (``jax_enable_x64``),
which rotor's numerics need. JAX's persistent compilation cache stays as the user left
it: the ``rotor`` command switches it on, and :func:`rotor.enable_compilation_cache`
does so in Python.
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from .cache import enable_compilation_cache  # noqa: E402
from .design.balance import Balance, balance  # noqa: E402
from .design.bearings import BearingLoads, bearing_loads  # noqa: E402
from .design.flywheel import (  # noqa: E402
    DiscFlywheel,
    FlywheelDesign,
    OperatingPoint,
    TextbookFlywheel,
    design_flywheel,
    inertia_for_delta,
    lightest_disc,
    textbook_flywheel,
)
from .design.report import Report, report  # noqa: E402
from .diagnostics.calibration import (  # noqa: E402
    Calibration,
    Diagnosis,
    calibrate,
    diagnose,
    measured_imep,
    preset_calibration,
)
from .diagnostics.identification import Identification, identify  # noqa: E402
from .diagnostics.inverse import (  # noqa: E402
    HarmonicTorque,
    IndicatedTorque,
    TorqueOrders,
    harmonic_response,
    harmonic_torque,
    indicated_torque,
)
from .diagnostics.misfire import contribution_index  # noqa: E402
from .diagnostics.pegging import MotoredGain, pressure_gain_from_motored  # noqa: E402
from .diagnostics.phase import SpeedTdc, TdcCheck, TdcNotDetermined, tdc_from_speed  # noqa: E402
from .diagnostics.synthetic import simulated_recording, simulated_tooth_errors, simulated_tooth_times  # noqa: E402
from .dynamics.combustion import combustion_pattern  # noqa: E402
from .dynamics.crank_train import CrankTrain, crank_train  # noqa: E402
from .dynamics.loads import (  # noqa: E402
    ConstantLoad,
    Governor,
    Load,
    LoadStep,
    PolynomialLoad,
    PropellerLoad,
    TableLoad,
    parse_load,
)
from .dynamics.result import Orders, SpeedResult  # noqa: E402
from .dynamics.steady import steady_state  # noqa: E402
from .dynamics.transient import simulate  # noqa: E402
from .engine.file import engine_from_dict, load_engine, preset_names  # noqa: E402
from .engine.forces import (  # noqa: E402
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
from .engine.friction import Friction  # noqa: E402
from .engine.inertia import (  # noqa: E402
    cylinder_inertia,
    inertia_coefficients,
    mean_reduced_inertia,
    reduced_inertia,
    reduced_inertia_derivative,
)
from .engine.kinematics import PistonMotion, RodMotion, mean_piston_speed, piston_motion, rod_motion  # noqa: E402
from .engine.mechanism import engine_piston_motion  # noqa: E402
from .engine.model import (  # noqa: E402
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
from .engine.pressure import (  # noqa: E402
    MotoredCycle,
    NoPressure,
    PressureSource,
    PressureTable,
    WiebeCycle,
    periodic_pchip,
)
from .engine.summary import EngineCurves, EngineSummary, engine_curves, engine_summary  # noqa: E402
from .engine.table import CrankTable, crank_table  # noqa: E402
from .errors import EngineError, InternalError, LogError, NoSteadyStateError, RotorError, SolverError  # noqa: E402
from .logs.analysis import LogAnalysis, analyze_log, tdc_from_pressure  # noqa: E402
from .logs.edges import Edges, find_edges  # noqa: E402
from .logs.pattern import locate_teeth  # noqa: E402
from .logs.reader import Log, read_log  # noqa: E402
from .logs.wheel import (  # noqa: E402
    ToothErrors,
    ToothTrack,
    Wheel,
    estimate_tooth_errors,
    firing_orders,
    parse_wheel,
)
from .results import Result  # noqa: E402
from .torsion.campbell import Campbell, campbell  # noqa: E402
from .torsion.model import TorsionalChain, crank_throw_stiffness, shaft_stiffness, torsional_chain  # noqa: E402
from .torsion.modes import TorsionalModes, holzer_frequencies, torsional_modes  # noqa: E402
from .torsion.response import TorsionalResponse, TorsionalSweep, torsional_response, torsional_sweep  # noqa: E402
from .torsion.transient import TorsionalRun, torsional_simulate  # noqa: E402

__version__ = "0.1.0"

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
    "enable_compilation_cache",
    "engine_curves",
    "engine_from_dict",
    "engine_piston_motion",
    "engine_summary",
    "estimate_tooth_errors",
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
