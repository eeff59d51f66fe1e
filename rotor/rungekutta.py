"""Dormand and Prince's 8(7) Runge–Kutta method with its stages written out.

diffrax's :class:`diffrax.Dopri8` computes the 13 new stages of a step in a loop (a
``while`` loop in the compiled program, which serves every Runge–Kutta method diffrax has,
implicit ones included). On XLA's CPU backend each turn of that loop costs more than
what rotor's right-hand sides compute in it (a table look-up and a few products).
:class:`UnrolledDopri8` is the same method (the same Butcher tableau, error estimate,
first-same-as-last stage and dense output, all taken from diffrax's class) with the stages
written out one after the other, so that XLA compiles one straight-line step. With fixed steps it gives diffrax's values to rounding; with adaptive
steps the same steps, except that the error estimate (a sum of large terms that cancel) is
rounded differently in its last digits, which moves the solution by a small part of the
tolerance. ``benchmarks/angle_solver_parts.py`` measures what it saves.

Reference: P. J. Prince and J. R. Dormand, "High order embedded Runge–Kutta formulae",
J. Comp. Appl. Math. 7 (1981) 67–75; the dense output from P. Bogacki and L. F. Shampine,
"Interpolating high-order Runge–Kutta formulas", Comput. Math. Appl. 20 (1990) 15–24.

Imported only where a solve is traced (it imports diffrax).
"""

from __future__ import annotations

import diffrax as dfx
import equinox.internal as eqxi
import jax.tree_util as jtu

from .jaxconfig import jax, jnp

_TABLEAU = dfx.Dopri8.tableau
assert _TABLEAU.fsal and _TABLEAU.ssal and not _TABLEAU.implicit


def _combine(y0, weights, ks):
    """y0 + Σ w_j·k_j over the nonzero weights, leaf by leaf (y0 None: the sum alone)."""
    terms = [(float(w), k) for w, k in zip(weights, ks, strict=False) if w != 0.0]

    def leaf(y, *k):
        total = sum(w * kj for (w, _), kj in zip(terms, k, strict=True))
        return total if y is None else y + total

    if y0 is None:
        return jtu.tree_map(lambda *k: leaf(None, *k), *[k for _, k in terms])
    return jtu.tree_map(leaf, y0, *[k for _, k in terms])


class UnrolledDopri8(dfx.Dopri8):
    """:class:`diffrax.Dopri8` for an ordinary differential equation (an ``ODETerm``), its
    stages written out (see the module's text). A drop-in solver for
    :func:`diffrax.diffeqsolve`."""

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        if solver_state is None:  # diffrax reuses no stage here (an expensive vector field): its own step
            return super().step(terms, t0, t1, y0, args, solver_state, made_jump)
        first_step, f_last = solver_state
        dt = t1 - t0
        control = terms.contr(t0, t1)
        # the first stage is the last one of the step before, except on the first step or
        # after a jump (for a batch: where any item needs it, as diffrax decides)
        f0 = jax.lax.cond(
            eqxi.unvmap_any(first_step | made_jump),
            lambda: terms.vf(t0, y0, args),
            lambda: f_last,
        )
        ks = [terms.prod(f0, control)]
        for a_row, c in zip(_TABLEAU.a_lower, _TABLEAU.c, strict=True):
            yi = _combine(y0, a_row, ks)
            ti = t1 if c == 1 else t0 + float(c) * dt
            fi = terms.vf(ti, yi, args)
            ks.append(terms.prod(fi, control))
        y1 = yi  # the last stage is taken at (t1, y1)
        y_error = _combine(None, _TABLEAU.b_error, ks)
        k = jtu.tree_map(lambda *leaves: jnp.stack(leaves), *ks)
        dense_info = dict(y0=y0, y1=y1, k=k)
        return y1, y_error, dense_info, (False, fi), dfx.RESULTS.successful
