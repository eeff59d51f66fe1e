"""Plotting: draws what a result hands it; computes nothing a result could.

matplotlib is imported only here, and only when a plot is asked for. Every function takes
``ax=`` (one Axes or an array of them) and returns what it drew on. One module per room
whose results it draws: :mod:`.engine`, :mod:`.speed`, :mod:`.logs`, :mod:`.diagnostics`,
:mod:`.design`; shared helpers in :mod:`.common`.

May import: the ground floor only (:mod:`rotor.units`, :mod:`rotor.fileio`, …). The
results call these functions, not the other way round, so plotting stays a leaf.
"""

from .common import angle_axis, new_axes, save_figure
from .design import plot_flywheel_design
from .diagnostics import plot_identification
from .engine import plot_inertia, plot_table, plot_torque
from .logs import plot_log_analysis
from .speed import plot_speed

__all__ = [
    "angle_axis",
    "new_axes",
    "plot_flywheel_design",
    "plot_identification",
    "plot_inertia",
    "plot_log_analysis",
    "plot_speed",
    "plot_table",
    "plot_torque",
    "save_figure",
]
