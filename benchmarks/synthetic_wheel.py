"""A simulated 60-2 trigger wheel with known tooth-spacing errors, shared by the round-trip
and identification tests and by benchmarks/identification.py.

``ERRORS``: each edge's angle error [rad], uniform in ±0.2° (seed 7), zero mean.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

import rotor
from rotor.logs.wheel import TWO_PI

WHEEL = rotor.Wheel(60, 2)
ERRORS = np.deg2rad(np.random.default_rng(7).uniform(-0.2, 0.2, WHEEL.edges_per_rev))
ERRORS -= ERRORS.mean()


def tooth_times(t_of_theta, theta_lo, theta_hi, gap_rad, rng, jitter_s):
    """Edge times [s] of the wheel's teeth (with ``ERRORS``) between two crank angles [rad],
    the first edge after the gap at ``gap_rad`` + k·2π, plus timer jitter of σ ``jitter_s`` [s];
    ``t_of_theta``: the time at a crank angle (e.g. a spline of a simulation)."""
    r0, r1 = int(np.floor((theta_lo - gap_rad) / TWO_PI)) - 1, int(np.ceil((theta_hi - gap_rad) / TWO_PI)) + 1
    revs = np.arange(r0, r1)
    ang = gap_rad + TWO_PI * revs[:, None] + WHEEL.pitch_rad * np.arange(WHEEL.edges_per_rev)[None, :] + ERRORS
    ang = ang.ravel()
    ang = ang[(ang >= theta_lo) & (ang <= theta_hi)]
    return t_of_theta(ang) + rng.normal(0.0, jitter_s, ang.size)


def coast_down_edges(jitter_s, seed=1):
    """Edge times of the bare wheel coasting down 3000 → 500 rpm over 300 revolutions with
    a fluctuation that scales as 1/ω², like a motored compression: ½ω² = ½ω0² − a·θ + G(θ),
    a constant drag a and a periodic work G (orders 1, 2; ±20 % speed at 500 rpm)."""
    w0, w1, revs = 3000 / 30 * np.pi, 500 / 30 * np.pi, 300
    theta = np.linspace(0.0, TWO_PI * revs, revs * 720 + 1)
    a = (w0**2 - w1**2) / 2 / theta[-1]
    G = 60.0 * (np.cos(theta) - 1) + 25.0 * (np.cos(2 * theta) - 1)
    inv = 1 / np.sqrt(w0**2 - 2 * a * theta + 2 * G)
    t = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(theta))])
    return tooth_times(CubicSpline(theta, t), theta[0], theta[-1], 0.3, np.random.default_rng(seed), jitter_s)
