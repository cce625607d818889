"""Derivatives of the wheel equilibrium at its root, by the implicit function theorem.

`solve_wheel` finds the solver variable s of W(theta0(s)) = F_z without derivatives (its
Newton iteration runs on stopped inputs) and passes the root through `_implicit_root`
and `_root_outputs`, two custom JVP rules.  At first order, `_root_outputs` alone does
the work: one tangent pass of the output quadrature along s and one along the parameters
give W_s and W_p, hence ds = (dF_z - W_p dp) / W_s, and every output's total derivative
(`jax.grad` transposes the parameter pass).  `_implicit_root` gives s its own tangent
for second derivatives (differentiating `_root_outputs`'s rule again); at first order
its computation is unused and XLA drops it.  `_along_s` is the pass along s with the
quadrature's nodes fixed; its own derivative (second order only) moves them with theta0.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

__all__: list[str] = []


def _partials_at_root(s, masks, target, params, t_target, t_params, forces):
    """`forces` and its total tangent at the root s of W(theta0(s)) = target.

    With W_s and W_p the partial derivatives at the root, the implicit function theorem
    gives ds = (d target - W_p dp) / W_s, and every output moves by its partials along
    (ds, dp).  One tangent pass along s and one along the parameters that carry a tangent
    (the others stay symbolic zeros) serve W and every other output together.  Elements
    whose theta0 is held at the cap (not a root; `forces` ignores s there) have W_s = 0
    and take ds = 0.  Returns (outputs, their tangents, ds).
    """
    moving = jax.tree_util.tree_map(lambda t: t is not None, t_params, is_leaf=lambda t: t is None)
    free, fixed = eqx.partition(params, moving)
    t_free, _ = eqx.partition(t_params, moving, is_leaf=lambda t: t is None)
    out, along_s = _along_s(s, masks, params, forces=forces)
    # Under `jax.grad` the pass along the parameters is transposed.  Checkpointed, it
    # stores only its inputs and re-runs the quadrature backwards, instead of keeping
    # every node's intermediates of the whole batch (hundreds of MB at 1e5 elements):
    # the gradient of a batch of 1e5 took 1.5x the forward solve without, 1.3x with it.
    _, along_p = jax.jvp(
        jax.checkpoint(lambda free: forces(s, masks, eqx.combine(free, fixed))),
        (free,),
        (t_free,),
    )
    w_s, w_p = along_s[1], along_p[1]
    d_target = jnp.zeros_like(w_p) if t_target is None else t_target
    moves = w_s != 0
    ds = jnp.where(moves, (d_target - w_p) / jnp.where(moves, w_s, 1.0), 0.0)
    tangents = jax.tree_util.tree_map(lambda dp, dsv: dp + dsv * ds, along_p, along_s)
    return out, tangents, ds


@eqx.filter_custom_jvp
def _along_s(s, masks, params, *, forces):
    """(outputs, their partial derivatives along s), with the quadrature's nodes fixed.

    Exact to first order (the stresses vanish at the entry, so the Leibniz term of a first
    derivative w.r.t. theta0 is 0); its own derivative, needed only for second derivatives
    of `solve_wheel`, moves the rule with theta0 (`moving_rule`), which keeps that term
    there, at the cost of tangents through the nodes that a first derivative never pays.
    """
    return jax.jvp(lambda s: forces(s, masks, params), (s,), (jnp.ones_like(s),))


@_along_s.def_jvp
def _along_s_jvp(primals, tangents, *, forces):
    s, masks, params = primals
    t_s, _, t_params = tangents  # None: a symbolic zero, which `filter_jvp` takes as such

    def moving(s, params):
        return jax.jvp(
            lambda s: forces(s, masks, params, moving_rule=True), (s,), (jnp.ones_like(s),)
        )

    return eqx.filter_jvp(moving, (s, params), (t_s, t_params))


@eqx.filter_custom_jvp
def _implicit_root(s, masks, target, params, *, forces):
    """The root s itself (computed without derivatives), carrying the implicit function
    theorem's ds for the second derivatives of `_root_outputs` (its own rule ignores the
    tangent of s; unused at first order, the computation is dropped by XLA)."""
    del masks, target, params, forces
    return s


@_implicit_root.def_jvp
def _implicit_root_jvp(primals, tangents, *, forces):
    s, masks, target, params = primals
    _, _, t_target, t_params = tangents
    _, _, ds = _partials_at_root(s, masks, target, params, t_target, t_params, forces)
    return _implicit_root(s, masks, target, params, forces=forces), ds


@eqx.filter_custom_jvp
def _root_outputs(s, masks, target, params, *, forces):
    """`forces(s, masks, params)` -> (theta0, W, ...) at the root s of W(theta0(s)) = target.

    Pass s as `_implicit_root(stopped s, ...)`.  The rule (`_partials_at_root`) supplies
    the implicit function theorem's derivative, so a first derivative costs one tangent
    (or, under `jax.grad`, one transposed tangent) of the output quadrature along the
    parameters and one along s, and nothing of the Newton iteration.  Differentiating the
    rule again (second derivatives) follows s's own implicit tangent.
    """
    del target
    return forces(s, masks, params)


@_root_outputs.def_jvp
def _root_outputs_jvp(primals, tangents, *, forces):
    s, masks, target, params = primals
    _, _, t_target, t_params = tangents  # the tangent of s is part of the rule's own
    out, t_out, _ = _partials_at_root(s, masks, target, params, t_target, t_params, forces)
    return out, t_out
