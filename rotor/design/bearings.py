"""Loads on the crank pins, big-end bearings, main journals and main bearings, the wear
diagrams and the running torques on the main journals: the textbook dynamic calculation at
constant crank speed (Shishkov, "Dinamika dvigatelei" [Engine dynamics: guide to the
course project], South Ural State University, 2014, §3.2.4–3.2.9; the same method in
Kolchin & Demidov, "Design of automotive engines", and in Popyk).

**Frames and signs.** Everything lies in the plane of the crank; angles grow in the
direction of rotation.

- *Block frame*: x along the axis of an unbanked cylinder (bank angle 0) towards its head,
  y across it, 90° on in the direction of rotation.
- *Throw frame* of throw k: e_r from the crank axis through the pin centre, e_t 90° on in
  the direction of rotation. At engine angle θ the throw points at θ − (its throw angle)
  in the block frame.
- A force F has the textbook's components in a frame: ``t`` = F·e_t (T, positive in the
  direction of rotation) and ``z`` = −F·e_r (Z, positive towards the crank axis, i.e.
  compressing the web). Every ``*_t_N``, ``*_z_N`` pair uses them, each in its own frame.
  Polar diagrams draw t to the right and z downward (§3.2.4), so that the radial axis of
  the frame points up and a drawn vector has the force's direction.
- *Crank pin* (throw frame): the force of the rods on the pin, T and Z₁ = Z + S₂ with S₂ =
  −m₂·R·ω² for each rod (m₂: the rod's mass at the crank pin).
- *Big-end bearing* (rod frame, the bearing turns with the rod): the same rod's force on
  the pin with e_r replaced by the rod's axis u, from the crank pin towards the piston pin
  (u = e_r at TDC): z along the rod, positive towards the crank pin, and t across it. The
  rod frame is the throw frame turned by −(φ + β), so the vector turns by φ + β (§3.2.5).
  Two rods side by side on one pin (a V engine) each have their own bearing and their own
  share: the rod's own T, Z and S₂.
- *Main journal* (shaft frame): the frame of the nearest throw in front of the journal
  (throw 1 for journal 1). *Main bearing* (block frame, §3.2.9): t across and z along the
  unbanked cylinder axis, positive towards the crank axis (downward). Both are the force
  the crankshaft puts on the journal's bearing (the bearing's reaction is its negative).

**Articulated rods.** A slave rod is a two-force member: its force, along the rod from its
piston pin to the knuckle pin, is P_Σ / cos(angle between the rod and the slave's axis).
The master rod (two-mass model: no mass of its own between its ends) is then in
equilibrium under its piston pin's force (P_Σ along the master's axis plus the liner's
side force n), the slave rod's force and the knuckle mass's inertia force at the knuckle
pin, and the crank pin's force at the big end. Moments about the big end give n; the sum
of the forces gives what the master rod puts on the crank pin. With no slave this is the
textbook N = P_Σ·tan β, T = K·sin(φ + β), Z = K·cos(φ + β). By virtual work the crank
pins' T·R add up to :func:`rotor.total_torque` plus the knuckle masses' inertia torque
(which :func:`rotor.total_torque` leaves out). A slave rod has no big end on the pin: its
cylinder's ``rotating_kg`` is not counted (as in the reduced inertia), and its share at
the knuckle pin is ``[articulated] rod_knuckle_kg``.

**Main journals.** Each span between two neighbouring main journals is simply supported
(the split beam of :mod:`rotor.engine.shaft`): a force applied to the crankshaft in the
span (a crank pin's force, the throw's own unbalanced rotating mass (m_rot − m₂ per
cylinder at R) and each counterweight at its web, each a centrifugal force m·r·ω²) is shared between
the span's two journals by the lever rule. A journal's load is the sum of what the spans
beside it put on it.

**Wear diagram** (§3.2.6): ``rays`` directions, ray 0 along e_r (outward along the crank
radius, the top of the polar diagram), the others every 360°/rays in the direction of
rotation, in the throw frame for a crank pin and the journal's shaft frame for a main
journal. Each load Q acts on the rays within ±``sector_deg`` of the direction of its
vector on the polar diagram (the textbook's convention); a ray's wear index is the cycle
mean of the loads acting on it [N] (a mean, not the textbook's sum, so that it does not
depend on the angle step). The least loaded ray is where the oil hole goes.

**Running torques** (§3.2.7): the torque a main journal passes on is the sum of T·R of the
throws in front of it (nearer the front); journal 1 passes none, the last the engine's
whole torque (gas and reciprocating inertia, :func:`rotor.total_torque`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..checks import check_size
from ..engine.forces import cylinder_pressure
from ..engine.mechanism import engine_piston_motion
from ..engine.model import Engine, engine_jit, require_engine
from ..engine.plausible import check_results_finite, check_speed_rpm, require_number, require_whole
from ..engine.shaft import journal_count, journal_positions_m, span_of_throw, throw_positions_m, web_positions_m
from ..errors import EngineError
from ..results import Result, json_safe
from ..units import RAD_S_PER_RPM

__all__ = ["BearingLoads", "bearing_loads", "wear_indices", "rod_pin_forces", "load_direction_rad"]

OIL_HOLE_TIE = 0.02
"""Another ray that is a least loaded one of its own neighbourhood, with a wear index within
this fraction of the least [-], is a near tie for the oil hole: the choice between them
follows the angle step, and both are reported."""
BEARING_ROW_BYTES = 4096
"""Memory one crank angle of the calculation takes per cylinder [bytes] (its arrays and
intermediates), to refuse a step too small for memory before anything is allocated."""

JSON_MAX_SAMPLES = 144
"""The most crank angles per cycle :meth:`BearingLoads.to_json_dict` writes its arrays at
(a finer result is decimated), which keeps the JSON of an engine well under 200 kB."""


def load_direction_rad(t: Any, z: Any) -> np.ndarray:
    """Direction of a load of components ``t``, ``z`` [N] (textbook signs, see the module)
    from e_r in the direction of rotation [rad], in [0, 2π): atan2(t, −z)."""
    return np.mod(np.arctan2(np.asarray(t), -np.asarray(z)), 2 * np.pi)


def wear_indices(direction_rad: Any, load_N: Any, rays: int, sector_deg: float) -> np.ndarray:
    """Wear index of each ray [N]: the mean over the samples of the loads whose direction
    lies within ±``sector_deg`` of the ray (ray r at 360°·r/``rays``), Shishkov (2014) §3.2.6.

    **Arguments:** ``direction_rad``: the direction of each load (same frame as the rays)
    [rad], shape (n,); ``load_N``: its magnitude [N], shape (n,); ``rays``: the number of
    rays; ``sector_deg``: the half-width of the sector a load acts on [deg].

    **Returns:** shape (rays,). A load exactly on a sector's edge (to 1e-9°) counts.
    """
    d = np.asarray(direction_rad, dtype=np.float64)[:, None]
    q = np.asarray(load_N, dtype=np.float64)[:, None]
    ray = 2 * np.pi * np.arange(rays) / rays
    diff = np.abs(np.mod(d - ray[None, :] + np.pi, 2 * np.pi) - np.pi)
    acts = diff <= np.deg2rad(sector_deg) + np.deg2rad(1e-9)
    return np.mean(q * acts, axis=0)


@engine_jit  # one compiled call instead of hundreds of eagerly compiled operations
def _piston_forces(engine, theta, omega, model):
    """P_Σ = P_g + P_j of every cylinder [N] and its mechanical angle [rad], each of shape
    ``theta.shape + (cylinders,)``."""
    g = engine.geometry
    d2s = engine_piston_motion(engine, theta, model).d2s
    m_rec, _ = engine.masses.two_mass_split(g.rod_length_m)
    pg = (cylinder_pressure(engine, theta) - engine.pressure.crankcase_pa) * g.piston_area_m2
    return pg - m_rec * omega**2 * d2s, engine.mechanical_angles(theta)


def rod_pin_forces(
    engine: Engine, theta: Any, omega: float, model: str = "exact"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The force of each rod on its crank pin, without the rod's own S₂: its T and Z [N]
    (textbook signs, in its throw's frame), and φ + β, the angle [rad] by which the rod's
    frame is turned back from the throw's; each of shape ``(len(theta), cylinders)``. T and
    Z are zero for a slave rod, whose force reaches the pin through its master (see the module).

    **Arguments:** ``engine``; ``theta``: engine crank angle [rad], shape (n,); ``omega``:
    crank speed [rad/s]; ``model``: piston kinematics, ``"exact"`` or ``"series"``.
    """
    g = engine.geometry
    R, L, k = float(g.crank_radius_m), float(g.rod_length_m), float(g.pin_offset_m)
    # arrays, traced by the compiled call (no recompile per speed), made without a program of their own
    th, w = np.asarray(theta, dtype=np.float64), np.asarray(omega, dtype=np.float64)
    psum, alpha = (np.asarray(x) for x in _piston_forces(engine, th, w, model))
    sin_b = (R * np.sin(alpha) - k) / L
    cos_b = np.sqrt(1.0 - sin_b**2)
    # each rod's force on its pin in its cylinder's frame (x along the axis to the head)
    fx = -psum
    moment = np.zeros_like(psum)  # moments about the big end of the forces at the knuckle pins
    fy = np.zeros_like(psum)
    slaves = engine.slave_index()
    if slaves:
        art = engine.articulated
        assert art is not None  # slaves exist only on an articulated engine
        banks = np.deg2rad(np.asarray(engine.layout.banks_deg, dtype=np.float64))
        r1 = float(art.knuckle_radius_m)
        gam = float(np.deg2rad(art.knuckle_angle_deg))
        l1 = float(art.rod_length_m)
        mk = float(art.rod_knuckle_kg)
        for s, m in slaves.items():
            a = alpha[:, m]
            sb, cb = sin_b[:, m], cos_b[:, m]
            c = np.stack([R * np.cos(a), R * np.sin(a)])
            # rod axis u (big end -> piston pin) and its first two derivatives in α
            u = np.stack([cb, -sb])
            db = R * np.cos(a) / (L * cb)
            d2b = sb / cb * db**2 - R * np.sin(a) / (L * cb)
            u_perp = np.stack([-sb, -cb])  # du/dβ
            d2u = d2b * u_perp - db**2 * u
            rot = np.array([[np.cos(gam), -np.sin(gam)], [np.sin(gam), np.cos(gam)]])
            w = np.einsum("ij,j...->i...", rot, u)  # big end -> knuckle pin, unit
            knuckle = c + r1 * w
            d2knuckle = -c + r1 * np.einsum("ij,j...->i...", rot, d2u)
            big = banks[s] - banks[m]
            axis = np.array([np.cos(big), np.sin(big)])[:, None]
            across = np.array([-np.sin(big), np.cos(big)])[:, None]
            along = np.sum(knuckle * axis, axis=0)
            off = np.sum(knuckle * across, axis=0)
            pin = (along + np.sqrt(l1**2 - off**2)) * axis
            v = (knuckle - pin) / l1  # slave piston pin -> knuckle pin, unit
            force = psum[:, s] / -np.sum(v * axis, axis=0) * v - mk * omega**2 * d2knuckle
            fx[:, m] += force[0]
            fy[:, m] += force[1]
            moment[:, m] += r1 * (w[0] * force[1] - w[1] * force[0])
    # the liner's side force n at the piston pin from the master rod's moments about the big end
    n = (psum * L * sin_b - moment) / (L * cos_b)
    fy = fy + n
    for s in slaves:
        fx[:, s] = 0.0
        fy[:, s] = 0.0
    t = fy * np.cos(alpha) - fx * np.sin(alpha)
    z = -(fx * np.cos(alpha) + fy * np.sin(alpha))
    return t, z, alpha + np.arcsin(sin_b)


@dataclass(frozen=True, eq=False, repr=False)
class BearingLoads(Result):
    """Crank-pin, big-end, main-journal and main-bearing loads, wear diagrams and running
    torques over one cycle at constant speed (frames and signs: :mod:`rotor.design.bearings`).

    **Attributes:** ``engine_name``; ``rpm`` [rev/min]; ``model`` (piston kinematics);
    ``step_deg`` [deg]; ``crank_radius_m`` R [m]; ``angle_deg``: engine crank angle, 0 …
    cycle − step [deg], shape (n,); ``throw_cylinders``: the cylinders (1-based) on each
    throw; ``pin_t_N``, ``pin_z1_N``, ``pin_q_N``: crank-pin T, Z₁ and Q [N], shape (n,
    throws); ``big_end_cylinders``: the cylinders whose rod has a big end on a pin (not
    the slaves); ``big_end_t_N``, ``big_end_z_N`` [N], shape (n, big ends), rod frame;
    ``throw_positions_m``, ``journal_positions_m``: axial positions [m];
    ``journal_frame_throw``: the throw (1-based) whose frame each journal's shaft-frame
    loads are in; ``journal_t_N``, ``journal_z_N`` [N], shape (n, journals), shaft frame;
    ``bearing_t_N``, ``bearing_z_N`` [N], block frame; ``running_torque_Nm`` [N·m], shape
    (n, journals); ``ray_angles_deg`` [deg], shape (rays,); ``sector_deg`` [deg];
    ``pin_wear_N``: shape (throws, rays); ``journal_wear_N``: shape (journals, rays) [N].
    """

    engine_name: str
    rpm: float
    model: str
    step_deg: float
    cycle_deg: float
    crank_radius_m: float
    angle_deg: np.ndarray
    throw_cylinders: tuple[tuple[int, ...], ...]
    pin_t_N: np.ndarray
    pin_z1_N: np.ndarray
    big_end_cylinders: tuple[int, ...]
    big_end_t_N: np.ndarray
    big_end_z_N: np.ndarray
    throw_positions_m: np.ndarray
    journal_positions_m: np.ndarray
    journal_frame_throw: tuple[int, ...]
    journal_t_N: np.ndarray
    journal_z_N: np.ndarray
    bearing_t_N: np.ndarray
    bearing_z_N: np.ndarray
    running_torque_Nm: np.ndarray
    ray_angles_deg: np.ndarray
    sector_deg: float
    pin_wear_N: np.ndarray
    journal_wear_N: np.ndarray

    # ------------------------------------------------------------------ derived
    @property
    def pin_q_N(self) -> np.ndarray:
        """Crank-pin load Q = √(T² + Z₁²) [N], shape (n, throws)."""
        return np.hypot(self.pin_t_N, self.pin_z1_N)

    @property
    def big_end_q_N(self) -> np.ndarray:
        """Big-end load [N], shape (n, big ends)."""
        return np.hypot(self.big_end_t_N, self.big_end_z_N)

    @property
    def journal_q_N(self) -> np.ndarray:
        """Main journal (and bearing) load [N], shape (n, journals)."""
        return np.hypot(self.journal_t_N, self.journal_z_N)

    @property
    def throws(self) -> int:
        """The number of crank throws."""
        return len(self.throw_cylinders)

    @property
    def journals(self) -> int:
        """The number of main journals."""
        return len(self.journal_positions_m)

    @property
    def worst_journal(self) -> int:
        """The main journal (1-based) with the largest peak load (the front one of equals)."""
        return _first_largest(np.max(self.journal_q_N, axis=0)) + 1

    @property
    def worst_torque_journal(self) -> int:
        """The main journal (1-based) whose running torque has the largest range (max − min;
        the front one of equals)."""
        return _first_largest(np.ptp(self.running_torque_Nm, axis=0)) + 1

    def pin_oil_hole_deg(self, throw: int = 1) -> float:
        """The least loaded ray of throw ``throw``'s crank pin (1-based), where the oil hole
        goes [deg from the crank radius, in the direction of rotation]."""
        k = self._throw(throw)
        return float(self.ray_angles_deg[int(np.argmin(self.pin_wear_N[k]))])

    def journal_oil_hole_deg(self, journal: int = 1) -> float:
        """The least loaded ray of main journal ``journal`` (1-based) [deg, in its shaft frame]."""
        j = self._journal(journal)
        return float(self.ray_angles_deg[int(np.argmin(self.journal_wear_N[j]))])

    def pin_oil_hole_candidates_deg(self, throw: int = 1) -> list[float]:
        """The oil hole's candidate rays of throw ``throw``'s crank pin [deg]: the least loaded
        first, then every other ray least loaded in its neighbourhood within
        :data:`OIL_HOLE_TIE` of it (a near tie, which the angle step may decide)."""
        return self._candidates(self.pin_wear_N[self._throw(throw)])

    def journal_oil_hole_candidates_deg(self, journal: int = 1) -> list[float]:
        """The oil hole's candidate rays of main journal ``journal`` [deg], as
        :meth:`pin_oil_hole_candidates_deg`."""
        return self._candidates(self.journal_wear_N[self._journal(journal)])

    def _candidates(self, wear: np.ndarray) -> list[float]:
        w = np.asarray(wear, dtype=np.float64)
        best = int(np.argmin(w))
        local = (w <= np.roll(w, 1)) & (w <= np.roll(w, -1))
        near = local & (w <= w[best] + OIL_HOLE_TIE * abs(w[best]))
        others = [int(i) for i in np.argsort(w) if near[i] and i != best]
        return [float(self.ray_angles_deg[i]) for i in [best, *others]]

    def _oil_hole_text(self, candidates: list[float], wear: np.ndarray) -> str:
        text = f"oil hole at {candidates[0]:g}°"
        if len(candidates) > 1:
            w = np.asarray(wear, dtype=np.float64)
            least = float(np.min(w))
            ties = ", ".join(
                f"{a:g}° ({(w[list(self.ray_angles_deg).index(a)] - least) / abs(least):+.1%})" for a in candidates[1:]
            )
            text += f" (near tie: {ties}; the angle step may choose either)"
        return text

    def _throw(self, throw: Any) -> int:
        t = require_whole(throw, "BearingLoads(throw)")
        if not 1 <= t <= self.throws:
            raise EngineError(f"throw {t} does not exist: the engine has throws 1…{self.throws}")
        return t - 1

    def _journal(self, journal: Any) -> int:
        if journal is None:
            return self.worst_journal - 1
        j = require_whole(journal, "BearingLoads(journal)")
        if not 1 <= j <= self.journals:
            raise EngineError(f"main journal {j} does not exist: the engine has journals 1…{self.journals}")
        return j - 1

    def _big_end(self, cylinder: Any) -> int:
        c = require_whole(cylinder, "BearingLoads(cylinder)")
        if c not in self.big_end_cylinders:
            raise EngineError(
                f"cylinder {c} has no big end on a crank pin: give one of {', '.join(map(str, self.big_end_cylinders))}"
                " (a slave rod's force reaches the pin through its master)"
            )
        return self.big_end_cylinders.index(c)

    def _stats(self, y: np.ndarray) -> dict[str, float]:
        i_hi, i_lo = int(np.argmax(y)), int(np.argmin(y))
        a = self.angle_deg
        return {
            "max_N": float(y[i_hi]),
            "max_angle_deg": float(a[i_hi]),
            "mean_N": float(np.mean(y)),
            "min_N": float(y[i_lo]),
            "min_angle_deg": float(a[i_lo]),
        }

    # ------------------------------------------------------------------ protocol
    def summary(self) -> str:
        """Per throw the peak crank-pin load and its angle, mean and minimum and the oil
        hole's ray; the peak big-end loads; per main journal the peak load and the
        running torque's range; the worst journals."""
        q, qb, qj = self.pin_q_N, self.big_end_q_N, self.journal_q_N
        lines = [
            f"{self.engine_name}: bearing loads at {self.rpm:g} rpm ({self.model} kinematics, step {self.step_deg:g}°, "
            f"wear: {len(self.ray_angles_deg)} rays, ±{self.sector_deg:g}°)",
            "  crank pins (T, Z1 = Z + S2; angle = engine crank angle):",
        ]
        rows = _capped(range(self.throws), np.max(q, axis=0))
        for k in rows:
            if k is None:
                lines.append(f"    … {self.throws - len(rows) + 1} more throws (to_pandas() has them all)")
                continue
            s = self._stats(q[:, k])
            cyl = ",".join(map(str, self.throw_cylinders[k]))
            lines.append(
                f"    throw {k + 1} (cyl {cyl}): Q max {s['max_N'] / 1e3:9.2f} kN at {s['max_angle_deg']:5.1f}°, "
                f"mean {s['mean_N'] / 1e3:8.2f}, min {s['min_N'] / 1e3:8.2f} kN; "
                f"{self._oil_hole_text(self.pin_oil_hole_candidates_deg(k + 1), self.pin_wear_N[k])}"
            )
        lines.append("  big-end bearings (rod frame):")
        rows = _capped(range(len(self.big_end_cylinders)), np.max(qb, axis=0))
        for b in rows:
            if b is None:
                lines.append(f"    … {len(self.big_end_cylinders) - len(rows) + 1} more (to_pandas() has them all)")
                continue
            s = self._stats(qb[:, b])
            lines.append(
                f"    cylinder {self.big_end_cylinders[b]}: max {s['max_N'] / 1e3:9.2f} kN at {s['max_angle_deg']:5.1f}°, "
                f"mean {s['mean_N'] / 1e3:8.2f} kN"
            )
        lines.append("  main journals (load; running torque passed on, min … max):")
        tq = self.running_torque_Nm
        rows = _capped(range(self.journals), np.max(qj, axis=0))
        for j in rows:
            if j is None:
                lines.append(f"    … {self.journals - len(rows) + 1} more journals (to_pandas() has them all)")
                continue
            s = self._stats(qj[:, j])
            lines.append(
                f"    journal {j + 1}: max {s['max_N'] / 1e3:8.2f} kN at {s['max_angle_deg']:5.1f}°, mean "
                f"{s['mean_N'] / 1e3:7.2f} kN; torque {tq[:, j].min():9.1f} … {tq[:, j].max():9.1f} N·m; "
                f"{self._oil_hole_text(self.journal_oil_hole_candidates_deg(j + 1), self.journal_wear_N[j])}"
            )
        wj, wt = self.worst_journal, self.worst_torque_journal
        lines.append(
            f"  most loaded main journal: {wj} ({np.max(qj[:, wj - 1]) / 1e3:.2f} kN); largest running torque "
            f"range: journal {wt} ({np.ptp(tq[:, wt - 1]):.1f} N·m)"
        )
        return "\n".join(lines) + "\n"

    def to_pandas(self) -> Any:
        """A tidy table: one row per crank angle and element (``crank_pin`` by throw,
        ``big_end`` by cylinder, ``main_journal`` in its shaft frame and ``main_bearing`` in
        the block frame by journal), with ``t_N``, ``z_N``, ``q_N`` and, on the
        ``main_journal`` rows, ``running_torque_Nm`` (NaN on the others)."""
        import pandas as pd

        n = len(self.angle_deg)
        parts = []

        def add(element, numbers, t, z, torque=None):
            m = t.shape[1]
            parts.append(
                pd.DataFrame(
                    {
                        "angle_deg": np.repeat(self.angle_deg, m),
                        "element": element,
                        "number": np.tile(np.asarray(numbers, dtype=int), n),
                        "t_N": t.ravel(),
                        "z_N": z.ravel(),
                        "q_N": np.hypot(t, z).ravel(),
                        "running_torque_Nm": np.full(n * m, np.nan) if torque is None else torque.ravel(),
                    }
                )
            )

        add("crank_pin", range(1, self.throws + 1), self.pin_t_N, self.pin_z1_N)
        add("big_end", self.big_end_cylinders, self.big_end_t_N, self.big_end_z_N)
        js = range(1, self.journals + 1)
        add("main_journal", js, self.journal_t_N, self.journal_z_N, self.running_torque_Nm)
        add("main_bearing", js, self.bearing_t_N, self.bearing_z_N)
        return pd.concat(parts, ignore_index=True)

    def wear_to_pandas(self) -> Any:
        """The wear diagrams as a tidy table: ``element`` (``crank_pin``/``main_journal``),
        ``number``, ``ray``, ``ray_angle_deg``, ``wear_N`` and ``oil_hole`` (the least loaded ray)."""
        import pandas as pd

        rows = []
        for element, table in (("crank_pin", self.pin_wear_N), ("main_journal", self.journal_wear_N)):
            for i, w in enumerate(table):
                best = int(np.argmin(w))
                for r, (ang, value) in enumerate(zip(self.ray_angles_deg, w)):
                    rows.append((element, i + 1, r, float(ang), float(value), r == best))
        return pd.DataFrame(rows, columns=["element", "number", "ray", "ray_angle_deg", "wear_N", "oil_hole"])

    def to_json_dict(self) -> dict:
        """Engine, speed, the per-throw, per-big-end and per-journal statistics (peaks and
        their angles, means, running torque ranges, wear indices and oil holes) and the
        arrays, decimated to at most :data:`JSON_MAX_SAMPLES` angles per cycle, rounded to 1 mN."""
        n = len(self.angle_deg)
        stride = max(1, int(np.ceil(n / JSON_MAX_SAMPLES)))
        pick = slice(None, None, stride)

        def arr(x):
            return np.round(np.asarray(x)[pick].T, 3)

        q, qb, qj = self.pin_q_N, self.big_end_q_N, self.journal_q_N
        tq = self.running_torque_Nm
        return json_safe(
            {
                "engine": self.engine_name,
                "rpm": self.rpm,
                "model": self.model,
                "step_deg": self.step_deg,
                "cycle_deg": self.cycle_deg,
                "crank_radius_m": self.crank_radius_m,
                "sector_deg": self.sector_deg,
                "ray_angles_deg": self.ray_angles_deg,
                "throws": [
                    {
                        "throw": k + 1,
                        "cylinders": list(self.throw_cylinders[k]),
                        "position_m": self.throw_positions_m[k],
                        **self._stats(q[:, k]),
                        "wear_N": np.round(self.pin_wear_N[k], 3),
                        "oil_hole_deg": self.pin_oil_hole_deg(k + 1),
                        "oil_hole_candidates_deg": self.pin_oil_hole_candidates_deg(k + 1),
                    }
                    for k in range(self.throws)
                ],
                "big_ends": [{"cylinder": c, **self._stats(qb[:, b])} for b, c in enumerate(self.big_end_cylinders)],
                "journals": [
                    {
                        "journal": j + 1,
                        "position_m": self.journal_positions_m[j],
                        "frame_throw": self.journal_frame_throw[j],
                        **self._stats(qj[:, j]),
                        "running_torque_min_Nm": float(tq[:, j].min()),
                        "running_torque_max_Nm": float(tq[:, j].max()),
                        "running_torque_range_Nm": float(np.ptp(tq[:, j])),
                        "wear_N": np.round(self.journal_wear_N[j], 3),
                        "oil_hole_deg": self.journal_oil_hole_deg(j + 1),
                        "oil_hole_candidates_deg": self.journal_oil_hole_candidates_deg(j + 1),
                    }
                    for j in range(self.journals)
                ],
                "worst_journal": self.worst_journal,
                "worst_torque_journal": self.worst_torque_journal,
                "arrays": {
                    "step_deg": self.step_deg * stride,
                    "angle_deg": self.angle_deg[pick],
                    "pin_t_N": arr(self.pin_t_N),
                    "pin_z1_N": arr(self.pin_z1_N),
                    "big_end_t_N": arr(self.big_end_t_N),
                    "big_end_z_N": arr(self.big_end_z_N),
                    "journal_t_N": arr(self.journal_t_N),
                    "journal_z_N": arr(self.journal_z_N),
                    "bearing_t_N": arr(self.bearing_t_N),
                    "bearing_z_N": arr(self.bearing_z_N),
                    "running_torque_Nm": arr(tq),
                },
            }
        )

    # ------------------------------------------------------------------ plots
    def _label_every(self) -> float:
        return 30.0 if self.cycle_deg <= 360 else 60.0

    def plot(self, ax: Any = None) -> Any:
        """The main diagrams on a 2 × 3 grid (``ax``: six Axes, or None for a new figure):
        crank pin and big end of throw 1, the developed load, the wear of crank pin 1, the
        most loaded main journal and the running torques.

        **Returns:** the array of Axes.
        """
        from ..plotting.bearings import plot_bearing_loads

        return plot_bearing_loads(self, ax=ax)

    def plot_crank_pin(self, ax: Any = None, throw: int = 1) -> Any:
        """Polar diagram of the load on crank pin ``throw`` (1-based) in the T–Z₁ plane, Z₁
        downward, equal scales, the crank angle marked along the curve. **Returns:** the Axes."""
        from ..plotting.bearings import plot_polar_load

        k = self._throw(throw)
        cyl = ",".join(map(str, self.throw_cylinders[k]))
        return plot_polar_load(
            self.angle_deg,
            self.pin_t_N[:, k],
            self.pin_z1_N[:, k],
            title=f"crank pin {k + 1} (cyl {cyl}), {self.rpm:g} rpm",
            t_label="T [kN]",
            z_label="Z₁ [kN]",
            label_every_deg=self._label_every(),
            ax=ax,
        )

    def plot_big_end(self, ax: Any = None, cylinder: int = 1) -> Any:
        """Polar diagram of the big-end bearing load of ``cylinder``'s rod (rod frame).
        **Returns:** the Axes."""
        from ..plotting.bearings import plot_polar_load

        b = self._big_end(cylinder)
        return plot_polar_load(
            self.angle_deg,
            self.big_end_t_N[:, b],
            self.big_end_z_N[:, b],
            title=f"big-end bearing, cylinder {self.big_end_cylinders[b]}",
            t_label="across the rod [kN]",
            z_label="along the rod [kN]",
            label_every_deg=self._label_every(),
            ax=ax,
        )

    def plot_developed(self, ax: Any = None, throw: int = 1) -> Any:
        """The developed diagram Q(φ) of crank pin ``throw`` with its mean. **Returns:** the Axes."""
        from ..plotting.bearings import plot_developed_load

        k = self._throw(throw)
        return plot_developed_load(
            self.angle_deg,
            self.pin_q_N[:, k],
            title=f"crank pin {k + 1}: developed load, {self.rpm:g} rpm",
            cycle_deg=self.cycle_deg,
            ax=ax,
        )

    def plot_wear(self, ax: Any = None, throw: int = 1, journal: int | None = None) -> Any:
        """Wear diagram of crank pin ``throw``, or of main journal ``journal`` if given,
        drawn inward from a circle, the oil hole's ray marked. **Returns:** the Axes."""
        from ..plotting.bearings import plot_wear

        if journal is None:
            k = self._throw(throw)
            w, title = self.pin_wear_N[k], f"wear of crank pin {k + 1} (ray 0: crank radius)"
        else:
            j = self._journal(journal)
            w = self.journal_wear_N[j]
            title = f"wear of main journal {j + 1} (frame of throw {self.journal_frame_throw[j]})"
        return plot_wear(self.ray_angles_deg, w, title=title, ax=ax)

    def plot_main_journal(self, ax: Any = None, journal: int | None = None) -> Any:
        """Polar diagram of main journal ``journal``'s load in its shaft frame (default: the
        most loaded journal). **Returns:** the Axes."""
        from ..plotting.bearings import plot_polar_load

        j = self._journal(journal)
        return plot_polar_load(
            self.angle_deg,
            self.journal_t_N[:, j],
            self.journal_z_N[:, j],
            title=f"main journal {j + 1} (frame of throw {self.journal_frame_throw[j]})",
            t_label="T [kN]",
            z_label="Z [kN]",
            label_every_deg=self._label_every(),
            ax=ax,
        )

    def plot_main_bearing(self, ax: Any = None, journal: int | None = None) -> Any:
        """Polar diagram of main bearing ``journal``'s load in the block frame (default: the
        most loaded). **Returns:** the Axes."""
        from ..plotting.bearings import plot_polar_load

        j = self._journal(journal)
        return plot_polar_load(
            self.angle_deg,
            self.bearing_t_N[:, j],
            self.bearing_z_N[:, j],
            title=f"main bearing {j + 1} (block frame)",
            t_label="across the cylinder axis [kN]",
            z_label="along the cylinder axis [kN]",
            label_every_deg=self._label_every(),
            ax=ax,
        )

    def plot_running_torques(self, ax: Any = None) -> Any:
        """The running torques on main journals 2… over the cycle. **Returns:** the Axes."""
        from ..plotting.bearings import plot_running_torques

        return plot_running_torques(
            self.angle_deg,
            self.running_torque_Nm,
            title=f"{self.engine_name}: running torques on the main journals",
            cycle_deg=self.cycle_deg,
            ax=ax,
        )


def _first_largest(x: np.ndarray) -> int:
    """Index of the first value within 1e-9 (relative) of the largest, so that journals
    equal by symmetry are not told apart by rounding."""
    return int(np.flatnonzero(x >= np.max(x) * (1 - 1e-9))[0])


def _capped(indices: range, peaks: np.ndarray, limit: int = 10) -> list:
    """At most ``limit`` of ``indices`` for a summary: all if they fit, else the largest
    ``peaks`` in order and a ``None`` that stands for the rest."""
    if len(indices) <= limit:
        return list(indices)
    keep = sorted(np.argsort(peaks)[::-1][: limit - 1].tolist())
    return [*keep, None]


def _checked_arguments(engine: Engine, rpm: Any, step_deg: Any, rays: Any, sector_deg: Any, model: Any):
    """:func:`bearing_loads`' arguments checked: (rpm, the cycle [deg], the step [deg], the
    number of angles, of rays, the sector's half-width [deg])."""
    rpm = float(engine.operating.rpm) if rpm is None else check_speed_rpm(rpm, "bearing_loads(rpm)")
    cycle = 360.0 * engine.strokes / 2
    step = require_number(step_deg, "bearing_loads(step_deg)", "deg")
    if not (np.isfinite(step) and 0 < step <= cycle / 4):
        raise EngineError(
            f"bearing_loads(step_deg) = {step_deg!r}: give a positive angle step of at most {cycle / 4:g}° "
            f"(a quarter of the {cycle:g}° cycle), e.g. 1"
        )
    check_size(
        cycle / step * BEARING_ROW_BYTES * max(engine.cylinders, 4),
        f"bearing loads at a step of {step:g}°",
        "use a larger step, e.g. step_deg=1",
    )
    n = int(round(cycle / step))
    if not np.isclose(n * step, cycle, rtol=1e-12, atol=1e-9):
        raise EngineError(
            f"bearing_loads(step_deg) = {step:g}: must divide the {cycle:g}° cycle evenly, e.g. 1, 2, 5 or 10"
        )
    n_rays = require_whole(rays, "bearing_loads(rays)", lo=3)
    if n_rays > 360:
        raise EngineError(f"bearing_loads(rays) = {n_rays}: at most 360 rays (12, every 30°, is the textbook's)")
    sector = require_number(sector_deg, "bearing_loads(sector_deg)", "deg")
    if not (np.isfinite(sector) and 0 < sector <= 180):
        raise EngineError(f"bearing_loads(sector_deg) = {sector_deg!r}: give a half-width in (0, 180] degrees, e.g. 60")
    if not isinstance(model, str):
        raise TypeError(f"bearing_loads(model): expected 'exact' or 'series', got {type(model).__name__}")
    if model not in ("exact", "series"):
        raise EngineError(
            f"bearing_loads(model) = {model!r}: 'exact' (the default) or 'series' (the textbook's λ-series)"
        )
    return rpm, cycle, step, n, n_rays, sector


def _journal_forces(engine: Engine, omega: float, on: list, pin_t: np.ndarray, pin_z1: np.ndarray, psi: np.ndarray):
    """The forces on the crankshaft in the block frame (the throws' pin loads less their
    unbalanced rotating masses, the counterweights), each shared between the two main
    journals on either side by the lever rule: (x, y components on each journal (n,
    journals) [N], the throws' and the journals' axial positions [m], the journal count).
    ``on``: the cylinders of each throw; ``psi``: each throw's angle (n, throws) [rad]."""
    g = engine.geometry
    R = float(g.crank_radius_m)
    m2 = float(engine.masses.big_end_kg(g.rod_length_m))
    m_rot = engine.masses.rotating_at_pin_kg(g.rod_length_m)
    cp, sp = np.cos(psi), np.sin(psi)
    unbalanced = (float(m_rot) - m2) * np.array([len(c) for c in on], dtype=np.float64)
    z_throw = pin_z1 - unbalanced * R * omega**2
    fx = [-pin_t * sp - z_throw * cp]  # block-frame components of each force, (n, forces)
    fy = [pin_t * cp - z_throw * sp]
    xs = [np.asarray(throw_positions_m(engine), dtype=np.float64)]
    spans = [span_of_throw(engine)]
    cw = engine.counterweights
    if cw is not None:
        webs = np.asarray(cw.webs, dtype=int) - 1
        k_of = webs // 2
        c = np.asarray(cw.mass_kg, dtype=np.float64) * np.asarray(cw.radius_m, dtype=np.float64) * omega**2
        ang = psi[:, k_of] + np.deg2rad(np.asarray(cw.angle_deg, dtype=np.float64))[None, :]
        fx.append(c * np.cos(ang))
        fy.append(c * np.sin(ang))
        xs.append(np.asarray(web_positions_m(engine), dtype=np.float64)[webs])
        spans.append(span_of_throw(engine)[k_of])
    fx_all, fy_all = np.concatenate(fx, axis=1), np.concatenate(fy, axis=1)
    x_all, span_all = np.concatenate(xs), np.concatenate(spans)
    xj = np.asarray(journal_positions_m(engine), dtype=np.float64)
    nj = journal_count(engine)
    share = np.zeros((len(x_all), nj))  # the lever rule: force i's share on journal j
    for i, (x, s) in enumerate(zip(x_all, span_all)):
        length = xj[s + 1] - xj[s]
        share[i, s] = (xj[s + 1] - x) / length
        share[i, s + 1] = (x - xj[s]) / length
    jx, jy = fx_all @ share, fy_all @ share  # (n, journals), block frame
    return jx, jy, xs[0], xj, nj


def bearing_loads(
    engine: Engine,
    rpm: float | None = None,
    *,
    step_deg: float = 1.0,
    rays: int = 12,
    sector_deg: float = 60.0,
    model: str = "exact",
) -> BearingLoads:
    """Crank-pin, big-end, main-journal and main-bearing loads, wear diagrams and running
    torques over one cycle at constant crank speed (Shishkov (2014) §3.2.4–3.2.9; frames and
    signs in :mod:`rotor.design.bearings`).

    **Arguments:**
    - ``engine``: a :class:`rotor.Engine`.
    - ``rpm``: crank speed [rev/min]; default the engine's ``[operating] rpm``.
    - ``step_deg``: angle step [deg]; must divide the cycle (720° or 360°); angles 0 … cycle − step.
    - ``rays``: rays of the wear diagrams (3 or more; 12 = every 30°).
    - ``sector_deg``: half-width of the sector a load acts on in the wear diagram [deg], in (0, 180].
    - ``model``: piston kinematics, ``"exact"`` (default) or ``"series"`` (the λ-series of
      the textbook's table; the rod angle is exact in both, as in :func:`rotor.crank_forces`,
      so with ``"series"`` the pins' T·R differs from the series torque by O(λ³), about 0.5 %).

    **Returns:** a :class:`BearingLoads`.
    """
    require_engine(engine, "bearing_loads(engine)").check()
    rpm, cycle, step, n, n_rays, sector = _checked_arguments(engine, rpm, step_deg, rays, sector_deg, model)
    omega = rpm * RAD_S_PER_RPM
    angle_deg = np.arange(n) * step
    theta = np.deg2rad(angle_deg)
    g = engine.geometry
    R = float(g.crank_radius_m)
    t_cyl, z_cyl, delta = rod_pin_forces(engine, theta, omega, model)
    slaves = engine.slave_index()
    own = [i for i in range(engine.cylinders) if i not in slaves]
    m2 = float(engine.masses.big_end_kg(g.rod_length_m))
    s2 = -m2 * R * omega**2
    z1_cyl = z_cyl + s2  # slaves' columns are not used below

    # big ends: each rod's own load turned into the rod's frame by φ + β
    cd, sd = np.cos(delta[:, own]), np.sin(delta[:, own])
    big_t = t_cyl[:, own] * cd - z1_cyl[:, own] * sd
    big_z = z1_cyl[:, own] * cd + t_cyl[:, own] * sd

    # crank pins: the rods on each throw
    throw_of = engine.throw_index
    nt = engine.throw_count
    on = [[i for i in own if throw_of[i] == k] for k in range(nt)]
    pin_t = np.stack([t_cyl[:, c].sum(axis=1) for c in on], axis=1)
    pin_z1 = np.stack([z1_cyl[:, c].sum(axis=1) for c in on], axis=1)
    throw_cylinders = tuple(tuple(i + 1 for i in range(engine.cylinders) if throw_of[i] == k) for k in range(nt))

    # forces on the crankshaft in the block frame, shared out onto the main journals
    throw_deg = np.asarray(engine.layout.throw_angles_deg, dtype=np.float64)
    psi = theta[:, None] - np.deg2rad(np.array([throw_deg[c[0]] for c in on]))[None, :]  # (n, throws)
    cp, sp = np.cos(psi), np.sin(psi)
    jx, jy, x_throw, xj, nj = _journal_forces(engine, omega, on, pin_t, pin_z1, psi)
    # shaft frame: the nearest throw in front of each journal (throw 1 for journal 1)
    frame = [max([k for k in range(nt) if x_throw[k] < xj[j]], default=0) for j in range(nj)]
    cf, sf = cp[:, frame], sp[:, frame]
    journal_t = jx * -sf + jy * cf
    journal_z = -(jx * cf + jy * sf)
    bearing_t, bearing_z = jy, -jx

    # running torques: T·R of the throws in front of each journal
    in_front = (x_throw[:, None] < xj[None, :]).astype(np.float64)  # (throws, journals)
    running = (pin_t * R) @ in_front

    ray_deg = 360.0 * np.arange(n_rays) / n_rays
    pin_q = np.hypot(pin_t, pin_z1)
    pin_dir = load_direction_rad(pin_t, pin_z1)
    pin_wear = np.stack([wear_indices(pin_dir[:, k], pin_q[:, k], n_rays, sector) for k in range(nt)])
    jq = np.hypot(journal_t, journal_z)
    j_dir = load_direction_rad(journal_t, journal_z)
    journal_wear = np.stack([wear_indices(j_dir[:, j], jq[:, j], n_rays, sector) for j in range(nj)])

    arrays = {
        "pin_t_N": pin_t,
        "pin_z1_N": pin_z1,
        "big_end_t_N": big_t,
        "big_end_z_N": big_z,
        "journal_t_N": journal_t,
        "journal_z_N": journal_z,
        "bearing_t_N": bearing_t,
        "bearing_z_N": bearing_z,
        "running_torque_Nm": running,
    }
    check_results_finite(f"the bearing loads of engine {engine.name!r} at {rpm:g} rpm", arrays)
    return BearingLoads(
        engine_name=engine.name,
        rpm=rpm,
        model=model,
        step_deg=step,
        cycle_deg=cycle,
        crank_radius_m=R,
        angle_deg=angle_deg,
        throw_cylinders=throw_cylinders,
        big_end_cylinders=tuple(i + 1 for i in own),
        throw_positions_m=x_throw,
        journal_positions_m=xj,
        journal_frame_throw=tuple(k + 1 for k in frame),
        ray_angles_deg=ray_deg,
        sector_deg=sector,
        pin_wear_N=pin_wear,
        journal_wear_N=journal_wear,
        **arrays,
    )
