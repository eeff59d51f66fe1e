"""rotor: rotational dynamics of piston engines.

Crank kinematics, reduced inertia I(θ), gas and inertia torques, and the crankshaft's
speed fluctuation, in JAX (float64 is switched on when rotor is imported).
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from .cache import enable_compilation_cache  # noqa: E402

enable_compilation_cache()

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
from .diagnostics.calibration import (  # noqa: E402
    Calibration,
    calibrate,
    cylinder_torques,
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
from .diagnostics.synthetic import simulated_recording, simulated_tooth_errors  # noqa: E402
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
from .engine.model import Articulated, Crankshaft, Engine, Geometry, Layout, Masses, Operating  # noqa: E402
from .engine.pressure import MotoredCycle, NoPressure, PressureTable, WiebeCycle, periodic_pchip  # noqa: E402
from .engine.summary import engine_summary  # noqa: E402
from .engine.table import CrankTable, crank_table  # noqa: E402
from .errors import (  # noqa: E402
    EngineError,
    LogError,
    NoSteadyStateError,  # noqa: E402
)
from .logs.analysis import LogAnalysis, analyze_log, tdc_from_pressure  # noqa: E402
from .logs.edges import Edges, find_edges  # noqa: E402
from .logs.reader import Log, read_log  # noqa: E402
from .logs.wheel import (  # noqa: E402
    ToothErrors,
    ToothTrack,
    Wheel,
    estimate_tooth_errors,
    firing_orders,
    locate_teeth,
    parse_wheel,
)

__version__ = "0.1.0"

__all__ = [
    "preset_calibration",
    "simulated_recording",
    "simulated_tooth_errors",
    "design_flywheel",
    "textbook_flywheel",
    "inertia_for_delta",
    "lightest_disc",
    "FlywheelDesign",
    "TextbookFlywheel",
    "DiscFlywheel",
    "OperatingPoint",
    "enable_compilation_cache",
    "EngineError",
    "Engine",
    "Geometry",
    "Masses",
    "Crankshaft",
    "Layout",
    "Operating",
    "Articulated",
    "PressureTable",
    "WiebeCycle",
    "MotoredCycle",
    "NoPressure",
    "load_engine",
    "engine_from_dict",
    "preset_names",
    "piston_motion",
    "rod_motion",
    "PistonMotion",
    "RodMotion",
    "mean_piston_speed",
    "engine_piston_motion",
    "reduced_inertia",
    "reduced_inertia_derivative",
    "cylinder_inertia",
    "inertia_coefficients",
    "mean_reduced_inertia",
    "cylinder_pressure",
    "cylinder_gas_torques",
    "gas_torque",
    "reciprocating_inertia_torque",
    "total_torque",
    "crank_forces",
    "imep_pa",
    "mean_gas_torque",
    "indicated_power_w",
    "periodic_pchip",
    "crank_table",
    "CrankTable",
    "engine_summary",
    "Friction",
    "Load",
    "ConstantLoad",
    "PolynomialLoad",
    "PropellerLoad",
    "TableLoad",
    "LoadStep",
    "Governor",
    "parse_load",
    "combustion_pattern",
    "CrankTrain",
    "crank_train",
    "SpeedResult",
    "Orders",
    "steady_state",
    "simulate",
    "NoSteadyStateError",
    "LogError",
    "Log",
    "read_log",
    "Edges",
    "find_edges",
    "Wheel",
    "parse_wheel",
    "firing_orders",
    "ToothTrack",
    "locate_teeth",
    "ToothErrors",
    "estimate_tooth_errors",
    "LogAnalysis",
    "analyze_log",
    "tdc_from_pressure",
    "indicated_torque",
    "IndicatedTorque",
    "harmonic_torque",
    "harmonic_response",
    "HarmonicTorque",
    "TorqueOrders",
    "identify",
    "Identification",
    "contribution_index",
    "Calibration",
    "calibrate",
    "diagnose",
    "measured_imep",
    "cylinder_torques",
]
