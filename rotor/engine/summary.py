"""A one-screen summary of an engine at an operating speed, and its curves over a cycle."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..checks import check_size
from ..errors import EngineError
from ..results import Result, json_safe
from ..units import RAD_S_PER_RPM
from .forces import gas_torque, imep_pa, mean_gas_torque, total_torque
from .inertia import inertia_coefficients, mean_reduced_inertia, reduced_inertia
from .kinematics import mean_piston_speed
from .model import Engine, engine_jit, require_engine
from .plausible import check_results_finite, check_speed_rpm, require_known, require_whole

__all__ = ["EngineSummary", "engine_summary", "EngineCurves", "engine_curves"]


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class EngineSummary(Result):
    """Key figures of an engine at one speed (what ``rotor info`` prints), in SI units.

    **Fields:** ``name``, ``strokes``, ``cylinders``; ``rpm`` [rev/min];
    ``displacement_m3`` (all cylinders) [m³]; ``crank_radius_m`` [m]; ``rod_ratio`` λ = R/L
    [-]; ``mean_piston_speed_m_s`` [m/s]; ``imep_pa`` [Pa]; ``mean_gas_torque_Nm`` [N·m];
    ``indicated_power_w`` [W]; ``total_torque_min_Nm``, ``total_torque_max_Nm``: range of
    the textbook total torque (gas + reciprocating inertia at constant speed) [N·m];
    ``excess_work_J``: the largest swing of ∫(M − M_mean)dθ (the flywheel's excess work,
    Shishkov, "Dinamika dvigatelei", SUSU 2014, §3.2.12) [J];
    ``inertia_mean_kgm2``, ``inertia_min_kgm2``, ``inertia_max_kgm2``: of the reduced
    inertia I(θ) [kg·m²]; ``inertia_coefficients_kgm2``: cylinder 1's A, B, C of I ≈ A·cos²α + B·cosα + C
    (Anisimov, Yelenich & Melnyk)
    [kg·m²]. **Curves** (not in the JSON): ``angle_deg`` [deg], ``total_torque_Nm`` [N·m]
    and ``inertia_kgm2`` [kg·m²] over one cycle.
    """

    name: str
    strokes: int
    cylinders: int
    rpm: float
    displacement_m3: float
    crank_radius_m: float
    rod_ratio: float
    mean_piston_speed_m_s: float
    imep_pa: float
    mean_gas_torque_Nm: float
    indicated_power_w: float
    total_torque_min_Nm: float
    total_torque_max_Nm: float
    excess_work_J: float
    inertia_mean_kgm2: float
    inertia_min_kgm2: float
    inertia_max_kgm2: float
    inertia_coefficients_kgm2: dict[str, float]
    angle_deg: np.ndarray
    total_torque_Nm: np.ndarray
    inertia_kgm2: np.ndarray

    def to_json_dict(self) -> dict:
        """What ``rotor info --json`` prints: every figure, no curves."""
        keys = [f.name for f in dataclasses.fields(self)][:-3]
        return json_safe({k: getattr(self, k) for k in keys})

    def summary(self) -> str:
        """What ``rotor info`` prints: the figures as aligned text."""
        rows = [
            ("engine", f"{self.name} ({self.cylinders} cylinders, {self.strokes}-stroke)"),
            ("speed", f"{self.rpm:g} rpm"),
            ("displacement", f"{self.displacement_m3 * 1e3:.3f} L"),
            ("crank radius R, lambda", f"{self.crank_radius_m * 1e3:.2f} mm, {self.rod_ratio:.4f}"),
            ("mean piston speed", f"{self.mean_piston_speed_m_s:.2f} m/s"),
            ("IMEP", f"{self.imep_pa / 1e6:.4f} MPa"),
            ("mean gas torque", f"{self.mean_gas_torque_Nm:.1f} N*m"),
            ("indicated power", f"{self.indicated_power_w / 1e3:.1f} kW"),
            (
                "total torque (gas + inertia)",
                f"{self.total_torque_min_Nm:.0f} ... {self.total_torque_max_Nm:.0f} N*m",
            ),
            ("excess work (Shishkov 3.2.12)", f"{self.excess_work_J:.1f} J"),
            (
                "reduced inertia I(theta)",
                f"mean {self.inertia_mean_kgm2:.4f}, {self.inertia_min_kgm2:.4f} ... "
                f"{self.inertia_max_kgm2:.4f} kg*m^2",
            ),
            (
                "A cos^2 + B cos + C, cylinder 1",
                "A = {A:.5f}, B = {B:.5f}, C = {C:.5f} kg*m^2".format(**self.inertia_coefficients_kgm2),
            ),
        ]
        w = max(len(k) for k, _ in rows)
        return "\n".join(f"{k.ljust(w)}  {v}" for k, v in rows) + "\n"

    def to_pandas(self) -> Any:
        """The curves over one cycle: ``angle_deg``, ``total_torque_Nm``, ``inertia_kgm2``."""
        import pandas as pd

        return pd.DataFrame(
            {"angle_deg": self.angle_deg, "total_torque_Nm": self.total_torque_Nm, "inertia_kgm2": self.inertia_kgm2}
        )

    def plot(self, ax: Any = None) -> Any:
        """The textbook total torque over the cycle with its mean, on ``ax`` (or a new
        figure); returns the Axes."""
        from ..plotting.engine import plot_torque

        return plot_torque(
            self.angle_deg,
            self.total_torque_Nm,
            float(np.mean(self.total_torque_Nm)),
            f"{self.name}: total torque at {self.rpm:g} rpm",
            360.0 * self.strokes / 2,
            ax=ax,
        )


def engine_summary(engine: Engine, rpm: float | None = None) -> EngineSummary:
    """Key figures of an engine at ``rpm`` [rev/min] (default ``[operating] rpm``), in SI units.

    **Returns:** an :class:`EngineSummary`: displacement, crank radius, λ, mean piston
    speed, IMEP, mean gas torque, indicated power, the range of the textbook total torque
    and its excess work (the largest swing of ∫(M − M_mean)dθ, Shishkov (2014) §3.2.12), and the
    mean, minimum and maximum of the reduced inertia I(θ).
    """
    require_known("engine_summary", "a table for people, computed on the host", engine=engine)
    require_engine(engine, "engine_summary(engine)").check()
    rpm = float(engine.operating.rpm) if rpm is None else check_speed_rpm(rpm, "rpm")
    omega = rpm * RAD_S_PER_RPM
    theta = np.linspace(0.0, engine.cycle_rad, int(720 * engine.strokes / 2), endpoint=False)
    out = {k: np.asarray(v) for k, v in _summary_arrays(engine, theta, np.asarray(omega)).items()}
    total, inertia = out.pop("total"), out.pop("inertia")
    A, B, C = out.pop("A"), out.pop("B"), out.pop("C")
    torque = float(out["mean_gas_torque_Nm"])
    work = np.cumsum(total - np.mean(total)) * (engine.cycle_rad / theta.shape[0])
    figures = {
        "displacement_m3": float(out["displacement_m3"]),
        "crank_radius_m": float(out["crank_radius_m"]),
        "rod_ratio": float(out["rod_ratio"]),
        "mean_piston_speed_m_s": float(out["mean_piston_speed_m_s"]),
        "imep_pa": float(out["imep_pa"]),
        "mean_gas_torque_Nm": torque,
        "indicated_power_w": torque * omega,
        "total_torque_min_Nm": float(np.min(total)),
        "total_torque_max_Nm": float(np.max(total)),
        "excess_work_J": float(work.max() - work.min()),
        "inertia_mean_kgm2": float(out["inertia_mean_kgm2"]),
        "inertia_min_kgm2": float(np.min(inertia)),
        "inertia_max_kgm2": float(np.max(inertia)),
    }
    coefficients = {"A": float(A[0]), "B": float(B[0]), "C": float(C[0])}
    check_results_finite(
        f"the summary of engine {engine.name!r} at {rpm:g} rpm",
        {**figures, **{f"inertia coefficient {k}": v for k, v in coefficients.items()}},
    )
    if not figures["inertia_min_kgm2"] > 0:
        raise EngineError(
            f"engine {engine.name!r}: the reduced inertia I(θ) falls to {figures['inertia_min_kgm2']:g} kg·m²; it "
            "must stay positive: check [crankshaft] inertia_kgm2 and [masses]"
        )
    return EngineSummary(
        name=engine.name,
        strokes=engine.strokes,
        cylinders=engine.cylinders,
        rpm=rpm,
        **figures,
        inertia_coefficients_kgm2=coefficients,
        angle_deg=np.rad2deg(theta),
        total_torque_Nm=total,
        inertia_kgm2=inertia,
    )


@engine_jit  # one compiled call (kept by the persistent compilation cache), not dozens of eager ones
def _summary_arrays(engine, theta, omega):
    """What :func:`engine_summary` computes with JAX, at crank angles ``theta`` [rad] and
    speed ``omega`` [rad/s]."""
    g = engine.geometry
    A, B, C = inertia_coefficients(engine)
    return {
        "total": total_torque(engine, theta, omega),
        "inertia": reduced_inertia(engine, theta),
        "A": A,
        "B": B,
        "C": C,
        "displacement_m3": g.displacement_m3 * engine.cylinders,
        "crank_radius_m": g.crank_radius_m,
        "rod_ratio": g.rod_ratio,
        "mean_piston_speed_m_s": mean_piston_speed(g.stroke_m, omega),
        "imep_pa": imep_pa(engine),
        "mean_gas_torque_Nm": mean_gas_torque(engine),
        "inertia_mean_kgm2": mean_reduced_inertia(engine),
    }


_INERTIA_MODELS = ("exact", "coefficients", "mean")
CURVE_ROW_BYTES = 4096
"""Memory one angle of :func:`engine_curves` takes while it is computed [bytes] (every
cylinder's intermediates and the seven curves)."""


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class EngineCurves(Result):
    """Torque and reduced inertia of an engine over one cycle at a constant speed.

    **Fields:** ``engine_name``; ``rpm`` [rev/min]; ``strokes``; ``angle_deg``: crank
    angle of cylinder 1 over the cycle, ends included [deg]; ``gas_torque_Nm``,
    ``inertia_torque_Nm`` (the reciprocating masses' textbook inertia torque) and
    ``total_torque_Nm`` [N·m]; ``inertia_exact_kgm2``, ``inertia_coefficients_kgm2`` (the
    A·cos²α + B·cosα + C form of Anisimov et al.) and ``inertia_mean_kgm2`` (its cycle mean) of I(θ) [kg·m²].
    """

    engine_name: str
    rpm: float
    strokes: int
    angle_deg: np.ndarray
    gas_torque_Nm: np.ndarray
    inertia_torque_Nm: np.ndarray
    total_torque_Nm: np.ndarray
    inertia_exact_kgm2: np.ndarray
    inertia_coefficients_kgm2: np.ndarray
    inertia_mean_kgm2: np.ndarray

    @property
    def cycle_deg(self) -> float:
        """Length of the cycle [deg]."""
        return 360.0 * self.strokes / 2

    @property
    def mean_torque_Nm(self) -> float:
        """Cycle mean of the total torque [N·m] (the end point, which repeats the start, left out)."""
        return float(self.total_torque_Nm[:-1].mean())

    def summary(self) -> str:
        """Range and mean of the torques and of I(θ)."""
        lines = [f"{self.engine_name}: torque and inertia over the {self.cycle_deg:g}° cycle at {self.rpm:g} rpm"]
        for label, y, unit, fmt in (
            ("gas torque", self.gas_torque_Nm, "N·m", ".1f"),
            ("inertia torque", self.inertia_torque_Nm, "N·m", ".1f"),
            ("total torque", self.total_torque_Nm, "N·m", ".1f"),
            ("I(θ) exact", self.inertia_exact_kgm2, "kg·m²", ".5f"),
            ("I(θ) A·cos² + B·cos + C", self.inertia_coefficients_kgm2, "kg·m²", ".5f"),
        ):
            y = np.asarray(y)[:-1]
            lines.append(f"  {label:15s} mean {y.mean():{fmt}}, {y.min():{fmt}} … {y.max():{fmt}} {unit}")
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """One row per crank angle: the torques [N·m] and the three forms of I(θ) [kg·m²]."""
        import pandas as pd

        return pd.DataFrame(
            {
                "angle_deg": self.angle_deg,
                "gas_torque_Nm": self.gas_torque_Nm,
                "inertia_torque_Nm": self.inertia_torque_Nm,
                "total_torque_Nm": self.total_torque_Nm,
                "inertia_exact_kgm2": self.inertia_exact_kgm2,
                "inertia_coefficients_kgm2": self.inertia_coefficients_kgm2,
                "inertia_mean_kgm2": self.inertia_mean_kgm2,
            }
        )

    def to_json_dict(self) -> dict:
        """Engine, speed and every curve as lists."""
        return json_safe(
            {"engine": self.engine_name, "rpm": self.rpm, "strokes": self.strokes, **self.to_pandas().to_dict("list")}
        )

    def plot(self, ax: Any = None, which: str = "torque") -> Any:
        """``which="torque"``: total torque (gas + reciprocating inertia), its parts and its
        mean over the cycle; ``"inertia"``: I(θ) over a revolution, exact, the
        A·cos²α + B·cosα + C form and the mean. On ``ax`` (or a new figure); returns the Axes."""
        from ..plotting.engine import plot_inertia, plot_torque

        if which == "torque":
            return plot_torque(
                self.angle_deg,
                self.total_torque_Nm,
                self.mean_torque_Nm,
                f"{self.engine_name}: total torque at {self.rpm:g} rpm",
                self.cycle_deg,
                gas_Nm=self.gas_torque_Nm,
                inertia_Nm=self.inertia_torque_Nm,
                xlabel="crank angle of cylinder 1 [deg]",
                ax=ax,
            )
        if which == "inertia":
            rev = self.angle_deg <= 360.0 + 1e-9
            curves = {
                "exact": self.inertia_exact_kgm2[rev],
                "coefficients": self.inertia_coefficients_kgm2[rev],
                "mean": self.inertia_mean_kgm2[rev],
            }
            return plot_inertia(self.angle_deg[rev], curves, f"{self.engine_name}: reduced moment of inertia", ax=ax)
        raise ValueError(f"which = {which!r}: 'torque' or 'inertia'")


def engine_curves(engine: Engine, rpm: float | None = None, points_per_deg: int = 2) -> EngineCurves:
    """Torque (gas, reciprocating inertia, total) and the reduced inertia I(θ) (exact, the
    A·cos²α + B·cosα + C form, mean) over one cycle at constant speed: what ``rotor plot`` draws.

    **Arguments:** ``engine``: a :class:`rotor.Engine`; ``rpm``: crank speed [rev/min]
    (default ``[operating] rpm``); ``points_per_deg``: samples per degree [1/deg].
    """
    require_known("engine_curves", "a table for people, computed on the host", engine=engine)
    require_engine(engine, "engine_curves(engine)").check()
    rpm = float(engine.operating.rpm) if rpm is None else check_speed_rpm(rpm, "rpm")
    points_per_deg = require_whole(points_per_deg, "engine_curves(points_per_deg)")
    cycle_deg = 360 * engine.strokes / 2
    rows = cycle_deg * points_per_deg + 1
    check_size(
        rows * CURVE_ROW_BYTES,
        f"curves at {points_per_deg} points per degree ({rows:.3g} angles)",
        "use fewer points per degree, e.g. 2",
    )
    deg = np.linspace(0, cycle_deg, int(rows))
    curves = {
        k: np.asarray(v) for k, v in _curve_arrays(engine, np.deg2rad(deg), np.asarray(rpm * RAD_S_PER_RPM)).items()
    }
    gas, total = curves.pop("gas"), curves.pop("total")
    inertia = {m: curves[m] for m in _INERTIA_MODELS}
    check_results_finite(
        f"the curves of engine {engine.name!r} at {rpm:g} rpm",
        {"gas_torque_Nm": gas, "total_torque_Nm": total, **{f"inertia_{m}_kgm2": v for m, v in inertia.items()}},
    )
    return EngineCurves(
        engine_name=engine.name,
        rpm=rpm,
        strokes=engine.strokes,
        angle_deg=deg,
        gas_torque_Nm=gas,
        inertia_torque_Nm=total - gas,
        total_torque_Nm=total,
        inertia_exact_kgm2=inertia["exact"],
        inertia_coefficients_kgm2=inertia["coefficients"],
        inertia_mean_kgm2=inertia["mean"],
    )


@engine_jit  # one compiled call (kept by the persistent compilation cache), not dozens of eager ones
def _curve_arrays(engine, theta, omega):
    """What :func:`engine_curves` computes with JAX, at crank angles ``theta`` [rad] and
    speed ``omega`` [rad/s]."""
    out = {"gas": gas_torque(engine, theta), "total": total_torque(engine, theta, omega)}
    return out | {m: reduced_inertia(engine, theta, m) for m in _INERTIA_MODELS}
