"""Factories of the design subpackage's results for the result-protocol test (small grids)."""

import rotor
from rotor.design.flywheel import OperatingPoint


def _flywheel_design():
    engine = rotor.load_engine("4chn15")
    return rotor.design_flywheel(
        engine,
        0.02,
        [OperatingPoint(900, 0.6), 1250],
        grid_deg=1.0,
        shaft_inertia_kgm2=0.5,
        max_outer_diameter_m=0.6,
    )


FACTORIES = {
    "FlywheelDesign": _flywheel_design,
    "TextbookFlywheel": lambda: rotor.textbook_flywheel(rotor.load_engine("4chn15"), 0.01, grid_deg=1.0),
    "DiscFlywheel": lambda: rotor.lightest_disc(1.0, peak_rpm=1250, bore_m=0.05, max_outer_diameter_m=0.5),
}
