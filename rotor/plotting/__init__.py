"""Plotting: draws what a result hands it; computes nothing a result could.

matplotlib is imported only here, and only when a plot is asked for. Every function takes
``ax=`` (one Axes or an array of them) and returns what it drew on. One module per room
whose results it draws: :mod:`.engine`, :mod:`.speed`, :mod:`.logs`, :mod:`.diagnostics`,
:mod:`.design`; shared helpers in :mod:`.common`.

May import: the ground floor only (:mod:`rotor.units`, :mod:`rotor.fileio`, …). The
results call these functions, not the other way round, so plotting stays a leaf.
"""

from .common import angle_axis, new_axes, save_figure
from .design import plot_disc_flywheel, plot_flywheel_design, plot_textbook_flywheel
from .diagnostics import plot_calibration, plot_identification, plot_indicated_torque, plot_torque_orders
from .engine import plot_inertia, plot_table, plot_torque
from .logs import plot_log_analysis, plot_tooth_errors
from .speed import plot_cycle_torque, plot_orders, plot_speed, plot_speed_time

__all__ = [
    "angle_axis",
    "new_axes",
    "plot_calibration",
    "plot_cycle_torque",
    "plot_disc_flywheel",
    "plot_flywheel_design",
    "plot_identification",
    "plot_indicated_torque",
    "plot_inertia",
    "plot_log_analysis",
    "plot_orders",
    "plot_speed",
    "plot_speed_time",
    "plot_table",
    "plot_textbook_flywheel",
    "plot_tooth_errors",
    "plot_torque",
    "plot_torque_orders",
    "save_figure",
]
