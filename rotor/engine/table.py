"""The one-cylinder kinematic and dynamic table of a crank mechanism (seed 004, appendix 5)."""

from __future__ import annotations

import io
from dataclasses import dataclass, field

import jax.numpy as jnp
import numpy as np

from .forces import crank_forces, table_angles_deg

__all__ = ["CrankTable", "crank_table", "TABLE_COLUMNS"]

TABLE_COLUMNS = ("angle_deg", "s_m", "v_m_s", "j_m_s2", "pg_N", "pj_N", "psum_N", "n_N", "k_N", "z_N", "t_N", "m_Nm")

# text layout: (column, heading, unit, scale, decimals)
_TEXT = (
    ("angle_deg", "angle", "deg", 1.0, 1),
    ("s_m", "S", "m", 1.0, 4),
    ("v_m_s", "V", "m/s", 1.0, 3),
    ("j_m_s2", "J", "m/s2", 1.0, 2),
    ("pg_N", "Pg", "kN", 1e-3, 3),
    ("pj_N", "Pj", "kN", 1e-3, 3),
    ("psum_N", "Psum", "kN", 1e-3, 3),
    ("n_N", "N", "kN", 1e-3, 3),
    ("k_N", "K", "kN", 1e-3, 3),
    ("z_N", "Z", "kN", 1e-3, 3),
    ("t_N", "T", "kN", 1e-3, 3),
    ("m_Nm", "M", "N*m", 1.0, 1),
)


@dataclass(frozen=True)
class CrankTable:
    """Kinematics and forces of one cylinder over a cycle at constant speed.

    **Attributes:** ``columns``: dict of numpy arrays named as :data:`TABLE_COLUMNS`
    (SI units: m, m/s, m/s², N, N·m; angle in degrees); ``engine_name``, ``rpm``,
    ``kinematics`` (``"series"`` or ``"exact"``), ``cylinder``.
    """

    columns: dict
    engine_name: str
    rpm: float
    kinematics: str
    cylinder: int = 1
    meta: dict = field(default_factory=dict)

    def __getitem__(self, key):
        return self.columns[key]

    def __len__(self):
        return len(self.columns["angle_deg"])

    def to_csv(self) -> str:
        """CSV text with the header ``angle_deg,s_m,…,m_Nm`` (SI units)."""
        buf = io.StringIO()
        buf.write(",".join(TABLE_COLUMNS) + "\n")
        data = np.column_stack([self.columns[c] for c in TABLE_COLUMNS])
        for row in data:
            buf.write(",".join(f"{v + 0.0:.10g}" for v in row) + "\n")  # + 0.0: no "-0"
        return buf.getvalue()

    def to_text(self) -> str:
        """A fixed-width table as in seed 004 (forces in kN), with a header of the inputs."""
        lines = [
            f"{self.engine_name}: cylinder {self.cylinder} at {self.rpm:g} rpm, "
            f"{self.kinematics} kinematics (seed 004 uses the lambda series)",
        ]
        for k, v in self.meta.items():
            lines.append(f"  {k}: {v}")
        widths = [max(len(h), len(u) + 2, 9 if d < 3 else 10) for _, h, u, _, d in _TEXT]
        lines.append(" ".join(h.rjust(w) for (_, h, _, _, _), w in zip(_TEXT, widths)))
        lines.append(" ".join(f"[{u}]".rjust(w) for (_, _, u, _, _), w in zip(_TEXT, widths)))
        for i in range(len(self)):
            cells = []
            for (col, _, _, scale, dec), w in zip(_TEXT, widths):
                value = round(float(self.columns[col][i]) * scale, dec) + 0.0  # no "-0.000"
                cells.append(f"{value:.{dec}f}".rjust(w))
            lines.append(" ".join(cells))
        return "\n".join(lines) + "\n"

    def to_pandas(self):
        """The columns as a ``pandas.DataFrame`` (pandas must be installed)."""
        import pandas as pd

        return pd.DataFrame({c: self.columns[c] for c in TABLE_COLUMNS})

    def plot(self, which: str = "forces", ax=None):
        """Plot ``"kinematics"`` (S, V, J), ``"forces"`` (Pg, Pj, PΣ, N, K, Z, T) or ``"torque"`` (M).

        **Returns:** the matplotlib Axes (or array of Axes for kinematics).
        """
        from ..plotting import plot_table

        return plot_table(self, which, ax=ax)


def crank_table(engine, rpm=None, step_deg: float = 10.0, kinematics: str = "series", cylinder: int = 1) -> CrankTable:
    """Seed 004's kinematic and dynamic table of one cylinder over a cycle.

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``rpm``: crank speed [rev/min]; default the engine's ``[operating] rpm``.
    - ``step_deg``: angle step [deg]; must divide the cycle (720° or 360°).
    - ``kinematics``: ``"series"`` (the λ-series of seed 004 §3.2.1, the default, so that
      the table is the textbook's) or ``"exact"``. The rod angle is exact in both.
    - ``cylinder``: cylinder number (1…n).

    **Returns:** a :class:`CrankTable`, rows at 0, step, …, cycle degrees.
    """
    rpm = float(engine.operating.rpm) if rpm is None else float(rpm)
    if not (np.isfinite(rpm) and rpm > 0):
        raise ValueError(f"rpm must be a positive number, got {rpm!r}")
    angles = table_angles_deg(engine, step_deg)
    omega = rpm * np.pi / 30
    # the table is for the cylinder's own cycle angle: shift by its firing angle
    i = cylinder - 1
    if not 1 <= cylinder <= engine.cylinders:
        raise ValueError(f"cylinder {cylinder} does not exist: the engine has cylinders 1…{engine.cylinders}")
    offset = engine.firing_angles_rad[i] - (2 * np.pi if engine.strokes == 4 else 0.0)
    theta = jnp.deg2rad(jnp.asarray(angles)) + offset
    cols = {k: np.asarray(v) for k, v in crank_forces(engine, theta, omega, cylinder, kinematics).items()}
    cols = {"angle_deg": angles, **cols}
    g = engine.geometry
    m_rec, _ = engine.masses.two_mass_split(g.rod_length_m)
    meta = {
        "R [m]": f"{float(g.crank_radius_m):.4f}",
        "lambda = R/L": f"{float(g.rod_ratio):.4f}",
        "reciprocating mass [kg]": f"{float(m_rec):.4f}",
        "piston area [m2]": f"{float(g.piston_area_m2):.5f}",
        "crankcase pressure [MPa]": f"{float(engine.pressure.crankcase_pa) / 1e6:.4f}",
    }
    return CrankTable(cols, engine.name, rpm, kinematics, cylinder, meta)
