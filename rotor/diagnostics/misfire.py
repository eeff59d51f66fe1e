"""Misfire detection from identified combustion scales: a contribution index per firing.

The identification (:func:`rotor.identify`) gives each firing's combustion scale s[k, c]
(1 = the engine file's cycle, 0 = no combustion). Its **contribution index** is that
scale relative to what the engine is burning around it,

    index[k, c] = s[k, c] / s_ref[k],   s_ref[k] = max(median of s over the firings of
                                                       cycles k − w … k + w, floor),

a robust reference that follows the load (at 20 % load the firings burn s ≈ 0.2, and a
normal firing still has index ≈ 1) and is not pulled down by the misfires themselves
while they are fewer than half of the firings around. A firing is a **misfire** where
its index is below ``threshold``.

**Coast-down** (no firing at all): the median scale is then noise around 0, and an index
relative to it would be noise over noise. The reference never falls below ``floor``
(default :data:`FLOOR_SCALE`, 5 % of the engine file's combustion, or five standard
errors of the identified scales where those are larger), so a record that does not fire
has every index near 0 and every firing a misfire, without false structure.

The default threshold (:data:`MISFIRE_THRESHOLD`) lies halfway between a misfire (0)
and the weakest normal cylinder of a ±10 % spread (0.9). Miss and false-alarm rates
measured on simulations (``benchmarks/identification.py``, results in
``benchmarks/results/identification.json``: 4chn15 and mwm6, three speeds each, ±10 %
spread, 2 % cycle-to-cycle variation, 3 % random misfires, through a 60-2 wheel with
tooth errors and 20 ns jitter):

- loads of 20 % and up (199 misfires, 6641 normal firings): no miss and no false alarm
  at any threshold from 0.1 to 0.8; the misfires' index at most 0.007, the normal
  firings' at least 0.83;
- 10 % load (66 misfires, 2214 normal firings): none missed at any threshold, false
  alarms only at 0.8 (0.05 %); normal firings' index at least 0.80;
- coast-downs of both presets (no firing): every firing flagged, |index| at most 0.17.

Below about 5 % load a normal firing's scale approaches the floor and the index loses
its meaning: the engine is then close to motoring.
"""

from __future__ import annotations

import numpy as np
from jaxtyping import ArrayLike

from ..errors import EngineError

__all__ = ["contribution_index", "MISFIRE_THRESHOLD", "FLOOR_SCALE"]

MISFIRE_THRESHOLD = 0.5
FLOOR_SCALE = 0.05
REFERENCE_CYCLES = 5  # w: the reference is the median over the cycles k − w … k + w


def contribution_index(
    scale: ArrayLike,
    scale_std: ArrayLike | None = None,
    *,
    threshold: float = MISFIRE_THRESHOLD,
    floor: float = FLOOR_SCALE,
    window: int = REFERENCE_CYCLES,
    valid: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contribution index and misfire flags of identified combustion scales.

    **Arguments:**
    - ``scale``: combustion scale per cycle and cylinder (cycles, cylinders) [-].
    - ``scale_std``: their standard errors (same shape) or None; the floor of the
      reference is at least five times their median [-].
    - ``threshold``: a firing whose index is below it is a misfire [-].
    - ``floor``: the least reference scale [-] (see the module doc: a coast-down).
    - ``window``: the reference is the median over the cycles k − window … k + window.
    - ``valid``: (cycles, cylinders) bool, the firings that take part in the reference
      (default all).

    **Returns:** (index (cycles, cylinders), misfire (cycles, cylinders) bool,
    reference (cycles,)).
    """
    s = np.asarray(scale, dtype=np.float64)
    if s.ndim != 2 or s.size == 0:
        raise EngineError(f"scale has shape {s.shape}: needs (cycles, cylinders)")
    if not (np.isfinite(threshold) and 0 < threshold < 1):
        raise EngineError(f"threshold = {threshold!r}: must lie between 0 and 1 (a fraction of a normal firing)")
    if not (np.isfinite(floor) and floor > 0):
        raise EngineError(f"floor = {floor!r}: must be a positive scale")
    ok = np.ones(s.shape, bool) if valid is None else np.asarray(valid, bool)
    fl = float(floor)
    if scale_std is not None:
        sd = np.asarray(scale_std, dtype=np.float64)[ok]
        if sd.size and np.all(np.isfinite(sd)):
            fl = max(fl, 5.0 * float(np.median(sd)))
    C = s.shape[0]
    ref = np.empty(C)
    for k in range(C):
        lo, hi = max(0, k - window), min(C, k + window + 1)
        v = s[lo:hi][ok[lo:hi]]
        if v.size == 0:
            v = s[lo:hi].ravel()
        ref[k] = max(float(np.median(v)), fl)
    index = s / ref[:, None]
    return index, index < threshold, ref
