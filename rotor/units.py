"""Units and physical constants: each defined once, here.

rotor computes in SI (m, kg, s, Pa, rad, rad/s, N·m, J); revolutions per minute, degrees
and bar appear only at the edges (files, command line, printed output), in names that
say so (``rpm``, ``angle_deg``, ``imep_bar``). This module is in the base layer: it
imports nothing from rotor.
"""

from __future__ import annotations

import math

__all__ = [
    "RPM_PER_RAD_S",
    "RAD_S_PER_RPM",
    "PA_PER_BAR",
    "rpm_to_rad_s",
    "rad_s_to_rpm",
]

#: revolutions per minute in one rad/s (30/π)
RPM_PER_RAD_S = 30.0 / math.pi
#: rad/s in one revolution per minute (π/30)
RAD_S_PER_RPM = math.pi / 30.0
#: pascal in one bar
PA_PER_BAR = 1.0e5


def rpm_to_rad_s(rpm):
    """Crank speed [rev/min] → [rad/s]; works on floats and arrays alike."""
    return rpm * RAD_S_PER_RPM


def rad_s_to_rpm(omega):
    """Crank speed [rad/s] → [rev/min]; works on floats and arrays alike."""
    return omega * RPM_PER_RAD_S
