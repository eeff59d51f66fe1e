"""Per-cycle, per-cylinder combustion: IMEP scaling, misfires and cycle-to-cycle variation.

A cylinder's gas torque in its k-th firing is

    M_c = M_motored,c + s[k, c] · (M_fired,c − M_motored,c)

where the fired trace is the engine's ``[pressure]`` and the motored one its
``motored()`` trace (see :mod:`rotor.engine.pressure`). s = 1 is the engine file's cycle, s = 0
a misfire (the cylinder is only compressed and expanded), s = 1.1 a cylinder burning 10 %
more. The cylinder's IMEP is affine in s: IMEP = IMEP_motored + s·(IMEP_fired − IMEP_motored);
the simulation results report it per cycle and cylinder.

Cycles and cylinders count from 1. The firing of cylinder c in cycle k is the one at
engine angle θ_fire,c + (k − 1)·Θ (Θ the cycle angle, θ_fire,c in [0, Θ) the first firing
TDC of the cylinder), and its scale, s[k − 1, c − 1] of the pattern array, applies from
half a cycle before to half a cycle after that TDC (where fired and motored traces agree).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from jaxtyping import ArrayLike

from ..engine.plausible import require_known
from ..errors import EngineError

__all__ = ["combustion_pattern"]


def combustion_pattern(
    cycles: int,
    cylinders: int,
    *,
    imep_scale: ArrayLike = 1.0,
    misfires: Iterable[tuple[int, int]] = (),
    misfire_rate: float = 0.0,
    cov: float = 0.0,
    seed: int | None = 0,
) -> np.ndarray:
    """Combustion scale s[k, c] for ``cycles`` firings of each of ``cylinders`` cylinders.

    **Arguments:**
    - ``cycles``, ``cylinders``: the shape of the pattern.
    - ``imep_scale``: nominal scale, a number, one per cylinder, or a (cycles, cylinders) array [-].
    - ``misfires``: (cycle, cylinder) pairs that misfire (s = 0), both counted from 1:
      cycle 1 … ``cycles``, cylinder 1 … ``cylinders`` as numbered in the engine file.
    - ``misfire_rate``: probability that any firing misfires at random [-].
    - ``cov``: coefficient of variation of s from cycle to cycle (normal, clipped at 0) [-].
    - ``seed``: seed of the random generator (``numpy.random.default_rng``), so that a
      pattern can be drawn again.

    **Returns:** float64 array (cycles, cylinders).

    **Raises:** :class:`rotor.EngineError` for values out of range; a :class:`TypeError`
    for a value traced by ``jax.jit``/``vmap``/``grad`` (the pattern is drawn in NumPy:
    draw it outside and pass it, or an array of scales, as ``simulate(combustion=...)``,
    which may be traced).
    """
    require_known(
        "combustion_pattern",
        "the pattern is drawn in NumPy; traced scales go to rotor.simulate(combustion=...) as they are",
        imep_scale=imep_scale,
        misfire_rate=misfire_rate,
        cov=cov,
    )
    if not (isinstance(cycles, (int, np.integer)) and cycles >= 1):
        raise EngineError(f"cycles = {cycles!r}: must be a whole number, 1 or more")
    if not (isinstance(cylinders, (int, np.integer)) and cylinders >= 1):
        raise EngineError(f"cylinders = {cylinders!r}: must be a whole number, 1 or more")
    try:
        s = np.broadcast_to(np.asarray(imep_scale, dtype=np.float64), (cycles, cylinders)).copy()
    except ValueError:
        raise EngineError(
            f"imep_scale of shape {np.shape(imep_scale)}: give a number, one value per cylinder ({cylinders}) "
            f"or a ({cycles}, {cylinders}) array"
        ) from None
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise EngineError("imep_scale must be finite and not negative")
    if not (np.isfinite(misfire_rate) and 0.0 <= misfire_rate <= 1.0):
        raise EngineError(f"misfire_rate = {misfire_rate!r}: must lie in 0…1")
    if not (np.isfinite(cov) and cov >= 0):
        raise EngineError(f"cov = {cov!r}: must be zero or positive")
    rng = np.random.default_rng(seed)
    if cov > 0:
        s = np.clip(s * (1.0 + cov * rng.standard_normal(s.shape)), 0.0, None)
    if misfire_rate > 0:
        s[rng.random(s.shape) < misfire_rate] = 0.0
    for pair in misfires:
        try:
            k, c = (int(v) for v in pair)
        except (TypeError, ValueError):
            raise EngineError(f"misfires: {pair!r} is not a (cycle, cylinder) pair") from None
        if not (1 <= k <= cycles and 1 <= c <= cylinders):
            raise EngineError(
                f"misfires: ({k}, {c}) is outside the run: cycles 1…{cycles}, cylinders 1…{cylinders} (both "
                "counted from 1)"
            )
        s[k - 1, c - 1] = 0.0
    return s
