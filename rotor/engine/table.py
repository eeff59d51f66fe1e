"""The one-cylinder kinematic and dynamic table of a crank mechanism, as in the course-project
calculation of Shishkov, "Dinamika dvigatelei" (Engine dynamics: guide to the course project),
South Ural State University, 2014, appendix 5 (after Kolchin & Demidov and Popyk)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax.numpy as jnp
import numpy as np

from ..errors import EngineError
from ..fileio import csv_text
from ..results import Result, json_safe
from ..units import RAD_S_PER_RPM
from .forces import cylinder_forces, cylinder_index, table_angles_deg
from .model import Engine, engine_jit, require_engine
from .plausible import check_results_finite, check_speed_rpm, require_known, require_whole

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


@dataclass(frozen=True, eq=False, repr=False)
class CrankTable(Result):
    """Kinematics and forces of one cylinder over a cycle at constant speed.

    **Attributes:** ``columns``: dict of numpy arrays named as :data:`TABLE_COLUMNS`
    (SI units: m, m/s, m/s², N, N·m; angle in degrees); ``engine_name``, ``rpm``
    [rev/min], ``kinematics`` (``"series"`` or ``"exact"``), ``cylinder``; the inputs of
    the table's header: ``crank_radius_m`` [m], ``rod_ratio`` λ = R/L [-],
    ``reciprocating_kg`` [kg], ``piston_area_m2`` [m²], ``crankcase_pa`` [Pa].
    """

    columns: dict[str, np.ndarray]
    engine_name: str
    rpm: float
    kinematics: str
    cylinder: int
    crank_radius_m: float
    rod_ratio: float
    reciprocating_kg: float
    piston_area_m2: float
    crankcase_pa: float

    def __getitem__(self, key: str) -> np.ndarray:
        return self.columns[key]

    def __len__(self) -> int:
        return len(self.columns["angle_deg"])

    def _title(self) -> str:
        return (
            f"{self.engine_name}: cylinder {self.cylinder} at {self.rpm:g} rpm, "
            f"{self.kinematics} kinematics (the textbook uses the lambda series)"
        )

    def _header(self) -> list[str]:
        return [
            f"  R [m]: {self.crank_radius_m:.4f}",
            f"  lambda = R/L: {self.rod_ratio:.4f}",
            f"  reciprocating mass [kg]: {self.reciprocating_kg:.4f}",
            f"  piston area [m2]: {self.piston_area_m2:.5f}",
            f"  crankcase pressure [MPa]: {self.crankcase_pa / 1e6:.4f}",
        ]

    def to_csv(self) -> str:
        """CSV text with the header ``angle_deg,s_m,…,m_Nm`` (SI units); a NaN or an
        infinity is refused, never written (:func:`rotor.fileio.csv_text`)."""
        data = np.column_stack([self.columns[c] for c in TABLE_COLUMNS])
        return csv_text(TABLE_COLUMNS, data, what="the crank table")

    def to_text(self) -> str:
        """A fixed-width table as in Shishkov (2014) (forces in kN), with a header of the inputs."""
        lines = [self._title(), *self._header()]
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

    def summary(self) -> str:
        """The header of the table and the extreme value of every column over the cycle."""
        lines = [self._title(), *self._header(), f"  {len(self)} rows; over the cycle:"]
        for col, head, unit, scale, dec in _TEXT[1:]:
            y = np.asarray(self.columns[col]) * scale
            i_lo, i_hi = int(np.argmin(y)), int(np.argmax(y))
            a = self.columns["angle_deg"]
            lines.append(
                f"  {head:>4} [{unit}]".ljust(14)
                + f"min {y[i_lo]:12.{dec}f} at {a[i_lo]:5.1f}°,  max {y[i_hi]:12.{dec}f} at {a[i_hi]:5.1f}°"
            )
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """The columns as a ``pandas.DataFrame``, one row per angle (SI units in the names)."""
        import pandas as pd

        return pd.DataFrame({c: self.columns[c] for c in TABLE_COLUMNS})

    def to_json_dict(self) -> dict:
        """Engine, cylinder, speed [rpm], kinematics, the header's inputs and every column as a list."""
        return json_safe(
            {
                "engine": self.engine_name,
                "cylinder": self.cylinder,
                "rpm": self.rpm,
                "kinematics": self.kinematics,
                "crank_radius_m": self.crank_radius_m,
                "rod_ratio": self.rod_ratio,
                "reciprocating_kg": self.reciprocating_kg,
                "piston_area_m2": self.piston_area_m2,
                "crankcase_pa": self.crankcase_pa,
                "columns": {c: self.columns[c] for c in TABLE_COLUMNS},
            }
        )

    def plot(self, ax: Any = None, which: str = "forces") -> Any:
        """Plot ``which``: ``"kinematics"`` (S, V, J), ``"forces"`` (Pg, Pj, PΣ, N, K, Z, T)
        or ``"torque"`` (M), on ``ax`` (three Axes for kinematics) or a new figure.

        **Returns:** the matplotlib Axes (or array of Axes for kinematics).
        """
        from ..plotting.engine import plot_table

        if isinstance(ax, str):
            raise TypeError(f"CrankTable.plot(ax=None, which=...): give the plot as which={ax!r}")
        return plot_table(self, which, ax=ax)


def crank_table(
    engine: Engine, rpm: float | None = None, step_deg: float = 10.0, kinematics: str = "series", cylinder: int = 1
) -> CrankTable:
    """The textbook kinematic and dynamic table of one cylinder over a cycle (Shishkov (2014),
    appendix 5).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``rpm``: crank speed [rev/min]; default the engine's ``[operating] rpm``.
    - ``step_deg``: angle step [deg]; must divide the cycle (720° or 360°).
    - ``kinematics``: ``"series"`` (the λ-series of Shishkov (2014) §3.2.1, the default, so that
      the table is the textbook's) or ``"exact"``. The rod angle is exact in both.
    - ``cylinder``: cylinder number (1…n).

    **Returns:** a :class:`CrankTable`, rows at 0, step, …, cycle degrees.
    """
    require_known("crank_table", "a table for people, computed on the host", engine=engine)
    require_engine(engine, "crank_table(engine)").check()
    rpm = float(engine.operating.rpm) if rpm is None else check_speed_rpm(rpm, "rpm")
    if kinematics not in ("series", "exact"):
        raise EngineError(f"kinematics = {kinematics!r}: 'series' (the textbook's) or 'exact'")
    cylinder = require_whole(cylinder, "cylinder")
    index = cylinder_index(engine, cylinder)
    angles = table_angles_deg(engine, step_deg)
    cols, header = _table_columns(engine, angles, np.asarray(rpm * RAD_S_PER_RPM), index, kinematics)
    cols = {"angle_deg": angles, **{k: np.asarray(v) for k, v in cols.items()}}
    header = {k: float(v) for k, v in header.items()}
    check_results_finite(f"the table of engine {engine.name!r} at {rpm:g} rpm", {**header, **cols})
    return CrankTable(cols, engine.name, rpm, kinematics, cylinder, **header)


@engine_jit  # one compiled call (kept by the persistent compilation cache), not dozens of eager ones
def _table_columns(engine, angles_deg, omega, i, kinematics):
    """The forces of the table of cylinder index ``i`` (an array: one program for every
    cylinder) at ``angles_deg`` (the cylinder's own cycle angle [deg]) and the inputs of its
    header."""
    # the table is for the cylinder's own cycle angle: shift by its firing angle
    offset = engine.firing_angles_rad[i] - (2 * np.pi if engine.strokes == 4 else 0.0)
    theta = jnp.deg2rad(angles_deg) + offset
    cols = cylinder_forces(engine, theta, omega, i, kinematics)
    g = engine.geometry
    m_rec, _ = engine.masses.two_mass_split(g.rod_length_m)
    header = {
        "crank_radius_m": g.crank_radius_m,
        "rod_ratio": g.rod_ratio,
        "reciprocating_kg": m_rec,
        "piston_area_m2": g.piston_area_m2,
        "crankcase_pa": engine.pressure.crankcase_pa,
    }
    return cols, header
