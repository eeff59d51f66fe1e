"""The phase a wheel log states in its header: where TDC lies and which revolution fires.

A log may state its phase in comment lines before its header, ``# tdc_after_gap_deg: DEG``
(cylinder 1's TDC after the gap [deg]) and ``# firing_parity: 0|1`` (which revolutions,
counted from the first gap, hold cylinder 1's firing TDC, as :func:`rotor.analyze_log`
counts them). ``rotor simulate --record`` writes them (:mod:`rotor.diagnostics.record`);
:func:`rotor.diagnose` takes them where no calibration or option gives TDC. A module of
its own, importing nothing of rotor, so that the diagnosis can read it.
"""

from __future__ import annotations

import math
import os

__all__ = ["PHASE_KEYS", "stated_phase"]

PHASE_KEYS = ("tdc_after_gap_deg", "firing_parity")
"""The keys of the comment lines ``# key: value`` by which a log states its phase."""


def stated_phase(path: str | os.PathLike, max_lines: int = 20) -> tuple[float, int] | None:
    """The phase a log states in its leading comment lines, ``# tdc_after_gap_deg: DEG``
    (cylinder 1's TDC after the gap [deg]) and ``# firing_parity: 0|1`` (which revolutions
    from the first gap hold its firing TDC, as :func:`rotor.analyze_log` counts them), as
    ``(tdc_deg, firing)``; None where the file states neither (or cannot be read as text).
    Written by :func:`rotor.diagnostics.record.record_run`, so that a recorded run is read
    back at its own phase."""
    found: dict[str, str] = {}
    if not os.path.isfile(path):
        return None  # a folder, a named pipe, a device: not opened here (a pipe would block)
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            for _, line in zip(range(max_lines), f):
                text = line.strip()
                if not text.startswith("#"):
                    break
                key, sep, value = text[1:].partition(":")
                if sep and key.strip() in PHASE_KEYS:
                    found[key.strip()] = value.strip()
    except (OSError, UnicodeError):
        return None
    if set(found) != set(PHASE_KEYS):
        return None
    try:
        tdc, parity = float(found["tdc_after_gap_deg"]), int(found["firing_parity"])
    except ValueError:
        return None
    return (tdc, parity) if math.isfinite(tdc) and parity in (0, 1) else None
