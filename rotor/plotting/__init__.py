"""Plotting: draws what a result hands it; computes nothing a result could.

matplotlib is imported only here, and only when a plot is asked for. Every function takes
``ax=`` (one Axes or an array of them) and returns what it drew on. One module per
subpackage whose results it draws: :mod:`.engine`, :mod:`.speed`, :mod:`.logs`, :mod:`.diagnostics`,
:mod:`.design`, :mod:`.torsion`; shared helpers in :mod:`.common`.

May import: the base layer only (:mod:`rotor.units`, :mod:`rotor.fileio`, …). The
results call these functions, not the other way round, so plotting stays a leaf.
"""

from .balance import plot_balance_ellipses, plot_balance_orders
from .bearings import plot_bearing_loads, plot_developed_load, plot_polar_load, plot_running_torques, plot_wear
from .common import angle_axis, new_axes, save_figure
from .design import plot_disc_flywheel, plot_flywheel_design, plot_textbook_flywheel
from .diagnostics import plot_calibration, plot_identification, plot_indicated_torque, plot_torque_orders
from .engine import plot_inertia, plot_table, plot_torque
from .logs import plot_log_analysis, plot_tooth_errors
from .speed import plot_cycle_torque, plot_orders, plot_speed, plot_speed_time
from .torsion import plot_campbell, plot_mode_shapes
from .torsion_response import plot_torsional_response, plot_torsional_run, plot_torsional_sweep

__all__ = [
    "angle_axis",
    "new_axes",
    "plot_balance_ellipses",
    "plot_balance_orders",
    "plot_bearing_loads",
    "plot_calibration",
    "plot_campbell",
    "plot_cycle_torque",
    "plot_developed_load",
    "plot_disc_flywheel",
    "plot_flywheel_design",
    "plot_identification",
    "plot_indicated_torque",
    "plot_inertia",
    "plot_log_analysis",
    "plot_mode_shapes",
    "plot_orders",
    "plot_polar_load",
    "plot_running_torques",
    "plot_speed",
    "plot_speed_time",
    "plot_table",
    "plot_textbook_flywheel",
    "plot_tooth_errors",
    "plot_torque",
    "plot_torque_orders",
    "plot_torsional_response",
    "plot_torsional_run",
    "plot_torsional_sweep",
    "plot_wear",
    "save_figure",
]
