"""Engine-level crank mechanism: every cylinder's piston motion at the engine crank angle.

Ordinary cylinders use the closed forms of :mod:`rotor.engine.kinematics` at their own
mechanical angle; slave cylinders of articulated rods use :mod:`rotor.engine.articulated`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from jaxtyping import ArrayLike

from ..cycles import array_module
from .articulated import SlaveGeometry, slave_piston_motion
from .kinematics import PistonMotion, piston_motion
from .model import engine_jit

if TYPE_CHECKING:
    from .model import Engine

__all__ = ["slave_geometry", "engine_piston_motion"]


def slave_geometry(engine, slave: int, master: int) -> SlaveGeometry:
    """The :class:`rotor.engine.articulated.SlaveGeometry` of 0-based cylinder ``slave`` on ``master``."""
    g, art = engine.geometry, engine.articulated
    xp = array_module(engine.layout.banks_deg, art.knuckle_angle_deg)  # NumPy for a concrete engine
    banks = xp.asarray(engine.layout.banks_deg)
    return SlaveGeometry(
        g.crank_radius_m,
        g.rod_length_m,
        g.pin_offset_m,
        art.knuckle_radius_m,
        xp.deg2rad(xp.asarray(art.knuckle_angle_deg)),
        art.rod_length_m,
        xp.deg2rad(banks[slave] - banks[master]),
    )


@engine_jit  # one compiled call per shape, not dozens of eager operations
def engine_piston_motion(engine: Engine, theta: ArrayLike, model: str = "exact") -> PistonMotion:
    """Piston displacement and its crank-angle derivatives for every cylinder.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``theta``: engine crank angle [rad], any shape.
    - ``model``: ``"exact"`` or ``"series"`` (slave pistons are always exact).

    **Returns:** a :class:`rotor.engine.kinematics.PistonMotion` whose fields have shape
    ``theta.shape + (cylinders,)`` [m, m/rad, m/rad²].
    """
    g = engine.geometry
    alpha = engine.mechanical_angles(theta)
    pm = piston_motion(alpha, g.crank_radius_m, g.rod_length_m, g.pin_offset_m, model=model)
    for s, m in engine.slave_index().items():
        sg = slave_geometry(engine, s, m)
        alpha_master = alpha[..., s] + sg.bank_rad
        sm = slave_piston_motion(alpha_master, sg)
        pm = PistonMotion(*(full.at[..., s].set(part) for full, part in zip(pm, sm)))
    return pm
