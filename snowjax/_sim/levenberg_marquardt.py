"""The damped Newton (Levenberg–Marquardt) root finder of the implicit time steps.

Kept instead of an optimistix root finder because none solves the first implicit step
from rest under a drive torque (the kink of the regularised forces at rest): measured with
optimistix 0.1.0 on the longitudinal vehicle under 545 N m per wheel, this solver
converges in 16 iterations, while `optimistix.LevenbergMarquardt`, `optimistix.Dogleg`
(forward- or reverse-mode Jacobian) and the undamped `optimistix.Newton` stop after 100
with residuals 18, 0.4 and 39.  (On coasting, driving and braking steps the damped ones
converge; `LevenbergMarquardt` takes 3x the iterations of this one on a driving step.)
`tests/test_sim.py::test_optimistix_root_finders_cannot_replace_the_damped_newton`, in
`make test`, fails when an optimistix release solves that step.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx
from jaxtyping import Array

__all__: list[str] = []


class _LMState(eqx.Module):
    y_acc: Array  # last accepted iterate
    f_acc: Array  # (scaled) residual there
    jac_acc: Array  # its Jacobian there
    merit_acc: Array  # 0.5 |f_acc|^2
    aux_acc: Any
    direction: Array  # step proposed from y_acc
    predicted: Array  # merit predicted by the linear model for y_acc + direction
    damping: Array  # Levenberg-Marquardt parameter mu (relative to diag(J^T J))
    growth: Array  # factor nu by which mu grows on the next rejection
    converged: Array
    result: optx.RESULTS


def _lm_direction(jac, f, damping):
    """Minimise |J d + f|^2 + mu |D d|^2, D^2 = diag(J^T J) (Marquardt scaling)."""
    n = jac.shape[1]
    d_scale = jnp.sqrt(jnp.sum(jac**2, axis=0) + jnp.finfo(jac.dtype).tiny)
    a = jnp.concatenate([jac, jnp.sqrt(damping) * jnp.diag(d_scale)])
    b = jnp.concatenate([-f, jnp.zeros(n, f.dtype)])
    return jnp.linalg.lstsq(a, b)[0]


# Kept: optimistix's root finders stall on the first step from rest (module docs).
class _LevenbergMarquardt(optx.AbstractRootFinder):
    """Levenberg–Marquardt root finder for small dense systems (Nielsen's damping update).

    Each iteration evaluates the residual f and its dense Jacobian (`jax.jvp` vmapped over
    the unit vectors) at the trial point, compares the actual decrease of `|f|^2 / 2` with the
    decrease predicted by the linear model, accepts the trial if the gain ratio is
    positive and adapts the damping (Nielsen 1999): close to a root it is Newton's method,
    in the S-shaped, kinked regions of the regularised wheel forces near rest it falls
    back to short gradient-like steps instead of cycling.  Converged when
    `|f_i| <= atol + rtol |y_i|` for all i (never on small steps alone, which also occur
    at local minima of |f| that are not roots); the result is then the last accepted
    iterate plus the Newton step computed there (the aux, the entry angles, is that of
    the accepted iterate).

    **Passive unknowns.**  The last `passive` unknowns p, with residual rows `p - g(a)`
    for a function g of the other ("active") unknowns a only, are carried along: the
    damping, the merit, the gain ratio and the convergence test see the active rows only
    (the active iterates are those of a solve without them, to rounding), the Jacobian
    is taken along the active directions only, and each step sets p to the
    linearisation `g(a_acc) + dg/da (a - a_acc)` (exact Newton on the passive rows).
    The result's p is thus g at the result's a up to the second-order term of the last
    Newton step.  The simulations carry the saved wheel outputs this way (`stepping.py`).
    """

    rtol: float
    atol: float
    norm: Callable = optx.max_norm
    initial_damping: float = 1e-8
    passive: int = eqx.field(static=True, default=0)

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        def nan_like(s):
            if jnp.issubdtype(s.dtype, jnp.floating):
                return jnp.full(s.shape, jnp.nan, s.dtype)
            return jnp.zeros(s.shape, s.dtype)

        n = y.shape[0]
        inf = jnp.array(jnp.inf, f_struct.dtype)
        return _LMState(
            y_acc=y,
            f_acc=jnp.full(f_struct.shape, jnp.inf, f_struct.dtype),
            jac_acc=jnp.eye(n, n - self.passive, dtype=y.dtype),
            merit_acc=inf,
            aux_acc=jax.tree_util.tree_map(nan_like, aux_struct),
            direction=jnp.zeros_like(y),
            predicted=inf,
            damping=jnp.array(self.initial_damping, y.dtype),
            growth=jnp.array(2.0, y.dtype),
            converged=jnp.array(False),
            result=optx.RESULTS.successful,
        )

    def step(self, fn, y, args, options, state, tags):
        # The dense Jacobian as forward-mode tangents vmapped over the unit vectors.  Not
        # `jax.linearize`: under an outer `jax.vmap` (a batch of simulations), its partial
        # evaluation leaves zeros for the residuals of the untaken branch of each `lax.cond`
        # inside `fn` (the wheel equilibrium's), the batched cond then evaluates both
        # branches' tangents, and the implicit derivative of a root find in the untaken
        # branch receives NaN, on which lineax raises.
        def tangent(direction):
            return jax.jvp(lambda z: fn(z, args), (y,), (direction,), has_aux=True)

        m = y.shape[0] - self.passive  # active unknowns, first
        basis = jnp.eye(y.shape[0], m, dtype=y.dtype)  # columns: the active unit vectors
        f, jac, aux = jax.vmap(tangent, in_axes=1, out_axes=(None, 1, None))(basis)
        merit = 0.5 * jnp.sum(f[:m] ** 2)
        finite = jnp.isfinite(merit) & jnp.all(jnp.isfinite(jac[:m]))
        first = ~jnp.isfinite(state.merit_acc)
        gain = (state.merit_acc - merit) / jnp.maximum(
            state.merit_acc - state.predicted, jnp.finfo(y.dtype).tiny
        )
        accept = finite & (first | (gain > 1e-4))
        pick = lambda a, b: jax.tree_util.tree_map(  # noqa: E731
            lambda u, v: jnp.where(accept, u, v), a, b
        )
        y_acc, f_acc, jac_acc = pick(y, state.y_acc), pick(f, state.f_acc), pick(jac, state.jac_acc)
        merit_acc = jnp.where(accept, merit, state.merit_acc)
        shrink = jnp.where(first, 1.0, jnp.maximum(1 / 3, 1 - (2 * gain - 1) ** 3))
        damping = jnp.where(accept, state.damping * shrink, state.damping * state.growth)
        growth = jnp.where(accept, 2.0, 2 * state.growth)
        damping, growth = damping.astype(y.dtype), growth.astype(y.dtype)
        active = _lm_direction(jac_acc[:m], f_acc[:m], damping)
        predicted = 0.5 * jnp.sum((f_acc[:m] + jac_acc[:m] @ active) ** 2)
        # The passive rows p - g(a) are linear in p with unit slope: their Newton step.
        direction = jnp.concatenate([active, -f_acc[m:] - jac_acc[m:] @ active])
        # Only a small residual counts: small steps alone also happen at a local minimum
        # of |f| that is not a root (then the step fails and is retried, smaller).
        scale = self.atol + self.rtol * jnp.abs(y_acc[:m])
        converged = accept & (self.norm(f[:m] / scale) <= 1.0)
        stuck = first & ~finite
        new_state = _LMState(
            y_acc=y_acc,
            f_acc=f_acc,
            jac_acc=jac_acc,
            merit_acc=merit_acc,
            aux_acc=pick(aux, state.aux_acc),
            direction=direction,
            predicted=predicted,
            damping=damping,
            growth=growth,
            converged=converged,
            result=optx.RESULTS.where(stuck, optx.RESULTS.nonfinite, optx.RESULTS.successful),
        )
        return y_acc + direction, new_state, aux

    def terminate(self, fn, y, args, options, state, tags):
        return state.converged | (state.result != optx.RESULTS.successful), state.result

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        # The last (nearly undamped) Newton step from the accepted iterate is already
        # computed: taking it squares the error, at no cost.  The aux stays that of y_acc.
        final = state.y_acc + jnp.where(state.converged, state.direction, 0.0)
        return final, state.aux_acc, {}


class _PassiveBlockSolver(lx.AbstractLinearSolver):
    """Linear solver for the implicit-function-theorem system of a root find with
    `passive` trailing unknowns (`_LevenbergMarquardt`): the Jacobian of the residual
    `(r(a), p - g(a))` w.r.t. `(a, p)` is `J = [[A, 0], [B, I]]` (A = dr/da,
    B = -dg/da).  Only the active columns `[A; B]` are computed (forward-mode tangents
    along the active unit vectors, as in the root finder) instead of the whole Jacobian
    that `lineax.SVD` materialises; then `J x = b` is `A x_a = b_a` (`lineax.SVD`: a
    least-squares solution that never raises on a singular A, as the simulations'
    steps need) and `x_p = b_p - B x_a`, and `J^T x = b` is `x_p = b_p`,
    `A^T x_a = b_a - B^T b_p`.  Flat (1-D) unknowns and residuals, real."""

    passive: int = eqx.field(static=True)

    def init(self, operator, options):
        n = operator.in_size()
        m = n - self.passive
        basis = jnp.eye(n, m, dtype=operator.in_structure().dtype)
        columns = jax.vmap(operator.mv, in_axes=1, out_axes=1)(basis)
        inner = lx.SVD().init(lx.MatrixLinearOperator(columns[:m]), options)
        return inner, columns[m:], False

    def compute(self, state, vector, options):
        inner, below, transposed = state
        m = vector.shape[0] - self.passive
        top, bottom = vector[:m], vector[m:]
        if transposed:
            x_a, result, _ = lx.SVD().compute(inner, top - below.T @ bottom, options)
            return jnp.concatenate([x_a, bottom]), result, {}
        x_a, result, _ = lx.SVD().compute(inner, top, options)
        return jnp.concatenate([x_a, bottom - below @ x_a]), result, {}

    def transpose(self, state, options):
        inner, below, transposed = state
        inner, options = lx.SVD().transpose(inner, options)
        return (inner, below, not transposed), options

    def conj(self, state, options):
        return state, options

    def assume_full_rank(self):
        return False
