"""The equation of motion of the crank train and its integrators.

    I(θ)·θ'' + ½·I'(θ)·θ'² = M_engine(θ, ω, t) − M_loss(ω, t)

M_engine is the gas torque (each cylinder's motored torque plus its combustion part,
scaled per firing and by the governor's fuel) plus, at the ``"constant"`` fidelity only,
the explicit reciprocating inertia torque k(θ)·ω². M_loss is friction plus the load.

Formulations (``method``):

- ``"closed"``: the angle domain in energy form, E = ½·I(θ)·ω², dE/dθ = F(θ) − G(θ)·E.
  When the losses are a + c·ω² (no linear speed term, no governor, nothing changing in
  time) this is linear in E: F = M_gas − a, G = 2(c − k)/I, and every cycle is solved on
  the grid in closed form, E(θ) = Φ(θ)·[E₀ + ∫ F/Φ dθ], Φ = exp(−∫G dθ), with the time
  t(θ) = ∫ dθ/ω; the integrals use the fourth-order Hermite rule on the table nodes.
- ``"grid"``: the same energy form with time (and the governor's integral) as states,
  classic RK4 with fixed steps (two per degree by default) in a ``lax.scan``; any load
  and the governor.
- ``"angle"``: that system integrated adaptively in θ by diffrax (Dopri8, steps of at
  most 4°), for a chosen tolerance.
- ``"time"``: θ and ω integrated in time by diffrax (Dopri8): a start from rest, a stall.

The two adaptive ones live in :mod:`rotor.dynamics.adaptive`, so that what does not need
them (the steady state, ``closed``, ``grid``) does not import diffrax.

A run in the angle domain that slows below 2 % of its starting speed hands over to the
time domain, which ends the run where ω reaches zero (a stall). So does a cycle in which
the angle domain's time quadrature t = ∫ dθ/ω cannot be trusted (:data:`MAX_ENERGY_RATIO`):
the kinetic energy changing by more than that factor within one step (a starter torque
of 10¹² N·m takes the speed from 1250 rpm to 10⁶ rpm within a quarter of a degree), time not
increasing, or a state that is not finite. The time domain's adaptive steps follow such a
change; the hand-over starts at the beginning of that cycle.
"""

from __future__ import annotations

import functools
import operator

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..cycles import array_module
from ..programs import kept_program
from ..progress import report
from .crank_train import COL_COMBUSTION, COL_I, COL_K, COL_MOTORED, CrankTrain, firing_window
from .loads import Governor, Load


def _to_bar(meter, fraction):
    report(int(meter), float(np.max(np.asarray(fraction))))


def report_progress(meter, fraction):
    """From inside a compiled run: tell the progress bar whose key is ``meter`` (an int32
    argument of the kernel, :attr:`rotor.progress.Progress.key`) that ``fraction`` of its
    running part is done. A host callback: the kernel is compiled once for every bar."""
    jax.debug.callback(_to_bar, meter, fraction)


def _report_every(meter, k, cycles: int):
    """Report cycle ``k`` (from 0) of ``cycles`` done to ``meter``, about a hundred times a run."""
    every = max(1, cycles // 100)
    jax.lax.cond((k + 1) % every == 0, lambda: report_progress(meter, (k + 1) / cycles), lambda: None)


def sum_columns(x):
    """The sum over the last axis of ``x``, a few columns (one per cylinder), written out
    column by column: XLA's CPU backend hands a reduction over a short last axis to a
    library call (a YNNPACK fusion), where additions fused into their neighbours do."""
    columns = [x[..., i] for i in range(x.shape[-1])]
    return functools.reduce(operator.add, columns) if columns else jnp.zeros(x.shape[:-1], x.dtype)


class Scene(eqx.Module):
    """Everything numeric that the equation of motion of a run needs.

    **Fields:** ``train`` (:class:`CrankTrain`); ``scales``: combustion scale per firing and
    cylinder (cycles, n); ``friction``: (a, b, c) of M_f = a + b·ω + c·ω² [N·m]; ``load``;
    ``governor``.
    """

    train: CrankTrain
    scales: jnp.ndarray
    friction: jnp.ndarray
    load: Load | None = None
    governor: Governor | None = None

    def scale_at(self, theta):
        idx = self.train.scale_index(theta, self.scales.shape[0])
        return self.scales[idx, jnp.arange(self.train.cylinders)]

    def loss(self, omega, t, signed: bool = False):
        """Friction plus load [N·m]. ``signed``: friction as an odd function of ω (for the
        time domain, where ω may reach zero): M_f(|ω|)·tanh(ω / 0.1 rad/s)."""
        fa, fb, fc = self.friction
        if signed:
            w = jnp.abs(omega)
            m = (fa + fb * w + fc * w**2) * jnp.tanh(omega / 0.1)
        else:
            m = fa + fb * omega + fc * omega**2
        if self.load is not None:
            m = m + self.load.torque(omega, t)
        return m

    def fuel(self, omega, z):
        if self.governor is None:
            return jnp.ones_like(omega)
        return self.governor.fuel(omega, z)

    def terms(self, theta):
        """(values, slopes, scales) at angle θ (scalar or array)."""
        val, der = self.train.at(theta)
        return val, der, self.scale_at(theta)

    def engine_torque(self, val, s, omega, z):
        comb = sum_columns(s * val[..., COL_COMBUSTION:])
        return val[..., COL_MOTORED] + self.fuel(omega, z) * comb + val[..., COL_K] * omega**2


#: the largest factor by which the kinetic energy may change within one step (a table node
#: of ``closed_run``, an RK4 step of ``grid_run``) before the cycle is handed over to the time
#: domain: the quadrature of dt = dθ/ω stays within about 1e-4 of the step's time below it
#: (ω changing by 22 %), while ordinary runs change E by well under 1 % a step
MAX_ENERGY_RATIO = 1.5


def untrusted_steps(E: jax.Array, t: jax.Array) -> jax.Array:
    """Whether the steps between consecutive states (E [J], t [s] along the last axis) leave
    the angle domain's time quadrature untrustworthy: E changing by more than
    :data:`MAX_ENERGY_RATIO` within a step, t not increasing, or anything not finite."""
    E0, E1 = E[..., :-1], E[..., 1:]
    jump = (E1 > MAX_ENERGY_RATIO * E0) | (E0 > MAX_ENERGY_RATIO * E1)
    backwards = ~(t[..., 1:] > t[..., :-1])
    finite = jnp.all(jnp.isfinite(E)) & jnp.all(jnp.isfinite(t))
    return jnp.any(jump) | jnp.any(backwards) | ~finite


def speed_from_energy(E, inertia):
    """ω [rad/s] of the kinetic energy ``E`` [J] at the inertia ``inertia`` [kg·m²]."""
    return jnp.sqrt(2 * jnp.maximum(E, 1e-300) / inertia)


# ----------------------------------------------------------------------------- closed form
def hermite_cumulative(f, df, h):
    """∫ from node 0 to each node by the Hermite rule: h/2·(f₀+f₁) + h²/12·(f₀′−f₁′)."""
    seg = 0.5 * h * (f[:-1] + f[1:]) + h * h / 12.0 * (df[:-1] - df[1:])
    return jnp.concatenate([jnp.zeros(1), jnp.cumsum(seg)])


def hermite_sum(f, df, h):
    """∫ over all the nodes by the Hermite rule (:func:`hermite_cumulative`'s last value,
    without the running sum): h·(Σf − (f₀+f_N)/2) + h²/12·(f₀′ − f_N′)."""
    return h * (jnp.sum(f) - 0.5 * (f[0] + f[-1])) + h * h / 12.0 * (df[0] - df[-1])


def wrap_periodic(x):
    """Node values 0…N−1 → 0…N (the periodic table's node N is node 0)."""
    return jnp.concatenate([x, x[:1]], axis=0)


def node_offsets(train: CrankTrain):
    """Firing-window offset of each node (0…N) and cylinder relative to the engine cycle."""
    theta = jnp.arange(train.points + 1) * train.step_rad
    return firing_window(theta[:, None], train.firing_rad, train.cycle_rad)


def linear_parts(train: CrankTrain, s_nodes, a, c):
    """Pieces of the linear energy equation over one cycle on the nodes 0…N.

    Returns (I, I', F, F', G, G', ΔM-sum, its slope): F = M_motored + Σ s·ΔM − a,
    G = 2(c − k)/I.
    """
    v, d = wrap_periodic(train.values), wrap_periodic(train.slopes)
    inertia, dinertia = v[:, COL_I], d[:, COL_I]
    k, dk = v[:, COL_K], d[:, COL_K]
    comb = jnp.sum(s_nodes * v[:, COL_COMBUSTION:], axis=1)
    dcomb = jnp.sum(s_nodes * d[:, COL_COMBUSTION:], axis=1)
    F = v[:, COL_MOTORED] + comb - a
    dF = d[:, COL_MOTORED] + dcomb
    G = 2 * (c - k) / inertia
    dG = 2 * (-dk * inertia - (c - k) * dinertia) / inertia**2
    return inertia, dinertia, F, dF, G, dG


def linear_cycle(train: CrankTrain, parts, E0, t0):
    """E, ω, t on the nodes 0…N of one cycle from E(0) = E0, t(0) = t0 (closed form)."""
    inertia, dinertia, F, dF, G, dG = parts
    h = train.step_rad
    cumG = hermite_cumulative(G, dG, h)
    phi = jnp.exp(-cumG)
    q = F / phi
    dq = (dF + F * G) / phi
    E = phi * (E0 + hermite_cumulative(q, dq, h))
    omega = speed_from_energy(E, inertia)
    dE = F - G * E
    domega = 0.5 * omega * (dE / jnp.maximum(E, 1e-300) - dinertia / inertia)
    r, dr = 1.0 / omega, -domega / omega**2
    t = t0 + hermite_cumulative(r, dr, h)
    return E, omega, t, dE


@kept_program(static_argnames=("cycles", "stride", "meter"))
@eqx.filter_jit
def closed_run(scene: Scene, a, c, E0, t0, first_cycle, cycles: int, stride: int, meter=None):
    """``cycles`` cycles in closed form from E0, t0; the combustion scale of cycle k is
    ``scene.scales[first_cycle + k]``. Returns per cycle the node values every ``stride``
    nodes (E, ω, t) of shape (cycles, N/stride), the end state, and the first cycle in
    which E reached zero or the time quadrature cannot be trusted (:func:`untrusted_steps`;
    or ``cycles``). ``meter``: the key of a progress bar to report to (:func:`report_progress`),
    or None."""
    train = scene.train
    offsets = node_offsets(train)
    n_total = scene.scales.shape[0]
    cyl = jnp.arange(train.cylinders)

    def body(carry, k):
        E0, t0, stalled_at = carry
        idx = jnp.clip(first_cycle + k + offsets, 0, n_total - 1)
        s_nodes = scene.scales[idx, cyl]
        parts = linear_parts(train, s_nodes, a, c)
        E, omega, t, dE = linear_cycle(train, parts, E0, t0)
        bad = (jnp.min(E) <= 0) | ~jnp.all(jnp.isfinite(E)) | untrusted_steps(E, t)
        stalled_at = jnp.where((stalled_at == cycles) & bad, k, stalled_at)
        keep = stalled_at == cycles
        E_end = jnp.where(keep, E[-1], E0)
        t_end = jnp.where(keep, t[-1], t0)
        out = (E[:-1:stride], t[:-1:stride])
        if meter is not None:
            _report_every(meter, k, cycles)
        return (E_end, t_end, stalled_at), out

    (E_end, t_end, stalled_at), (E, t) = jax.lax.scan(body, (E0, t0, jnp.asarray(cycles)), jnp.arange(cycles))
    return E, t, E_end, t_end, stalled_at


# ----------------------------------------------------------------------------- set-up helpers
def friction_coefficients(engine, friction):
    """(a, b, c) of the friction torque: ``friction`` if given, else the engine file's, else none.

    ``friction=False`` switches off the engine file's friction.
    """
    fr = engine.friction if friction is None else friction
    if fr is None or fr is False:
        return np.zeros(3)
    abc = fr.torque_coefficients(engine)
    xp = array_module(*abc)  # NumPy where concrete: no JAX operation on every call
    return xp.stack([xp.asarray(v, dtype=xp.float64) for v in abc])


def is_zero(x):
    if x is None:
        return True
    if isinstance(x, jax.core.Tracer):
        return False
    if isinstance(x, float):  # the usual case (NumPy's float64 too), without an array's round trip
        return bool(x == 0)
    return bool(np.all(np.asarray(x) == 0))  # numpy: under a jit trace jnp would give a tracer


def quadratic_losses(load, friction_abc):
    """(a, c): the part a + c·ω² of friction plus a load that is not time dependent
    (friction's and a polynomial load's constant and ω² terms); the rest (friction's
    speed-linear term, the load's) is what :func:`rotor.dynamics.steady.speed_remainder` gives."""
    fa, _, fc = friction_abc
    poly = None if load is None else load.polynomial()
    if poly is None:
        return fa, fc
    parts = (fa, fc, 0.0 if poly[0] is None else poly[0], 0.0 if poly[2] is None else poly[2])
    xp = array_module(*parts)  # NumPy where concrete: no JAX operation
    fa, fc, la, lc = (xp.asarray(v, dtype=xp.float64) for v in parts)
    return fa + la, fc + lc


def linear_losses(load, friction_abc):
    """(a, c) when friction plus load is a + c·ω² with no speed-linear term and nothing
    changing in time (the closed form applies), else None."""
    fa, fb, fc = friction_abc
    if not is_zero(fb):
        return None
    if load is None:
        return fa, fc
    if load.time_dependent:
        return None
    poly = load.polynomial()
    if poly is None or not is_zero(poly[1]):
        return None
    parts = (fa, fc, 0.0 if poly[0] is None else poly[0], 0.0 if poly[2] is None else poly[2])
    xp = array_module(*parts)  # NumPy where concrete: no JAX operation
    fa, fc, la, lc = (xp.asarray(v, dtype=xp.float64) for v in parts)
    return fa + la, fc + lc


# ----------------------------------------------------------------------------- fixed steps on the grid
@kept_program(static_argnames=("cycles", "steps_per_cycle", "stride", "meter"))
@eqx.filter_jit
def grid_run(scene: Scene, theta0, y0, cycles: int, steps_per_cycle: int, stride: int, e_switch, meter=None):
    """Classic RK4 in the angle domain with ``steps_per_cycle`` equal steps per cycle, on the
    table nodes when it divides their number (then the right-hand side is one smooth cubic
    within each step). A lax.scan: no step-size control, no per-step overhead.

    Returns the states (E, t, z) every ``stride`` steps (cycles, steps_per_cycle/stride),
    the end state and the first cycle where E fell to ``e_switch`` or the time quadrature
    cannot be trusted (:func:`untrusted_steps`; or ``cycles``).
    ``meter``: the key of a progress bar to report to (:func:`report_progress`), or None."""
    h = scene.train.cycle_rad / steps_per_cycle

    def field(theta, y):
        E, t, z = y
        val, der, s = scene.terms(theta)
        omega = speed_from_energy(E, val[COL_I])
        dz = scene.governor.error(omega) / omega if scene.governor is not None else jnp.zeros_like(omega)
        return jnp.stack([scene.engine_torque(val, s, omega, z) - scene.loss(omega, t), 1.0 / omega, dz])

    def step(y, theta):
        k1 = field(theta, y)
        k2 = field(theta + h / 2, y + h / 2 * k1)
        k3 = field(theta + h / 2, y + h / 2 * k2)
        k4 = field(theta + h, y + h * k3)
        return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def cycle(carry, k):
        y, stalled_at = carry
        thetas = theta0 + (k * steps_per_cycle + jnp.arange(steps_per_cycle)) * h

        def inner(y, theta):
            return step(y, theta), y

        y_end, ys = jax.lax.scan(inner, y, thetas)
        E_all = jnp.concatenate([ys[:, 0], y_end[:1]])
        t_all = jnp.concatenate([ys[:, 1], y_end[1:2]])
        bad = (jnp.min(ys[:, 0]) <= e_switch) | (y_end[0] <= e_switch) | ~jnp.all(jnp.isfinite(y_end))
        bad = bad | untrusted_steps(E_all, t_all)
        stalled_at = jnp.where((stalled_at == cycles) & bad, k, stalled_at)
        keep = stalled_at == cycles
        if meter is not None:
            _report_every(meter, k, cycles)
        return (jnp.where(keep, y_end, y), stalled_at), ys[::stride]

    y0 = jnp.stack([jnp.asarray(v, dtype=jnp.float64) for v in y0])
    (y_end, stalled_at), ys = jax.lax.scan(cycle, (y0, jnp.asarray(cycles)), jnp.arange(cycles))
    return (ys[..., 0], ys[..., 1], ys[..., 2]), y_end, stalled_at
