"""Derivatives of the wheel equilibrium at its root, by the implicit function theorem.

`solve_wheel` finds the solver variable s of W(theta0(s)) = F_z without derivatives (its
Newton iteration runs on stopped inputs) and passes the root through `_implicit_root`
and `_root_outputs`, two custom JVP rules.  The outputs depend on s and on the cap of the
entry angle (a deeper base allows a larger theta0) only through theta0 = `entry(s, over,
cap)`, a closed form, and on the other parameters through the contact
`forces(theta0, bottomed, element)`.  At first order, `_root_outputs` alone does the
work: one tangent pass of the contact along theta0 and one along the parameters at fixed
theta0 (or one per parameter where at most two carry a tangent, `_along_parameters`)
give W_theta and W_p, hence ds from dW = dF_z, and every output's total derivative
(`jax.grad` transposes the parameter pass).  `_implicit_root` gives s its own
tangent for second derivatives (differentiating `_root_outputs`'s rule again); at first
order its computation is unused and XLA drops it.  `_along_theta0` is the pass along
theta0 with the quadrature's nodes fixed; its own derivative (second order only) moves
them with theta0.  The pass along the parameters holds theta0, so fixed nodes are exact
for it at every order (the stresses vanish at the entry for every parameter value; a
law's kink moves with its panels, `front_rim._moving`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

__all__: list[str] = []


def _partials_at_root(s, masks, target, params, t_target, t_params, entry, forces):
    """(theta0, forces) and their total tangents at the root s of W(theta0(s)) = target.

    With W_theta and W_e the partial derivatives of the contact at the root (along
    theta0 and along the contact's parameters at fixed theta0) and theta0 = entry(s,
    cap), dW = W_theta (theta0_s ds + theta0_cap dcap) + W_e de = d target gives ds, and
    every output moves by its partials along (dtheta0, de).  One tangent pass along
    theta0 and one along the parameters that carry a tangent (the others stay symbolic
    zeros) serve W and every other output together.  Elements whose theta0 is held at
    the cap (not a root) have theta0_s = 0 and take ds = 0.  Returns (outputs, their
    tangents, ds).
    """
    over, bottomed = masks
    theta_cap, element = params
    t_cap, t_element = t_params
    ones = jnp.ones_like(s)
    theta0, theta0_s = jax.jvp(lambda s: entry(s, over, theta_cap), (s,), (ones,))
    _, theta0_cap = jax.jvp(lambda c: entry(s, over, c), (theta_cap,), (ones,))
    out, along_theta0 = _along_theta0(theta0, bottomed, element, forces=forces)
    moving = jax.tree_util.tree_map(lambda t: t is not None, t_element, is_leaf=lambda t: t is None)
    free, fixed = eqx.partition(element, moving)
    t_free, _ = eqx.partition(t_element, moving, is_leaf=lambda t: t is None)
    along_e = _along_parameters(
        lambda free: forces(theta0, bottomed, eqx.combine(free, fixed)), free, t_free
    )
    d_cap = theta0_cap * _or_zero(t_cap, theta0)  # theta0's move at fixed s
    w_theta, w_e = along_theta0[0], along_e[0]
    w_s = w_theta * theta0_s
    d_target = _or_zero(t_target, theta0)
    moves = w_s != 0
    ds = jnp.where(moves, (d_target - w_e - w_theta * d_cap) / jnp.where(moves, w_s, 1.0), 0.0)
    d_theta0 = theta0_s * ds + d_cap
    tangents = jax.tree_util.tree_map(lambda de, dt: de + dt * d_theta0, along_e, along_theta0)
    return (theta0, *out), (d_theta0, *tangents), ds


# Parameters with a tangent up to which `_along_parameters` takes one tangent pass per
# parameter.
PER_PARAMETER = 2


def _along_parameters(at, free, t_free):
    """The tangent of `at(free)` (the contact's outputs at fixed theta0, elementwise
    over the batch: output k depends on element k of every leaf) along `t_free`.

    With at most `PER_PARAMETER` leaves carrying a tangent, each 1-D (a rover's slip
    and slip angle, a simulation's slip), one tangent pass per leaf with unit tangents
    gives every element's partial derivatives, and the tangent is their sum weighted
    by `t_free`'s leaves.  The passes do not depend on `t_free`: vmapped over tangents
    (the rover's three velocity tangents, `jax.jacfwd`), they run once instead of once
    per tangent; under `jax.grad` only the weighting is transposed.  Measured on the
    rover in MJX (1,024 environments, 2 cores, two alternating runs each): 34.2-34.7 ->
    33.3-34.1 us per environment step, 32.4-33.3 -> 30.6-31.8 at the simulator
    accuracy.  A single tangent along two leaves costs one pass more.

    Otherwise one pass along `t_free`, checkpointed: under `jax.grad` it is transposed,
    and the checkpoint stores only its inputs and re-runs the quadrature backwards
    instead of keeping every node's intermediates of the whole batch (hundreds of MB
    at 1e5 elements: the gradient of a batch of 1e5 took 1.5x the forward solve
    without, 1.3x with it).
    """
    t_leaves = jax.tree_util.tree_leaves(t_free)
    elementwise = all(jnp.ndim(t) == 1 and jnp.issubdtype(t.dtype, jnp.floating) for t in t_leaves)
    if 0 < len(t_leaves) <= PER_PARAMETER and elementwise:
        leaves, tree = jax.tree_util.tree_flatten(free)

        def partial(k):  # d at / d (leaf k), per element (the other leaves held)
            def along(x):
                return at(jax.tree_util.tree_unflatten(tree, [*leaves[:k], x, *leaves[k + 1 :]]))

            return jax.jvp(along, (leaves[k],), (jnp.ones_like(leaves[k]),))[1]

        partials = [partial(k) for k in range(len(leaves))]
        return jax.tree_util.tree_map(
            lambda *p: sum(t * q for t, q in zip(t_leaves, p, strict=True)), *partials
        )
    return jax.jvp(jax.checkpoint(at), (free,), (t_free,))[1]


def _or_zero(tangent, like):
    """`tangent`, or zeros like `like` for a symbolic zero (None)."""
    return jnp.zeros_like(like) if tangent is None else tangent


@eqx.filter_custom_jvp
def _along_theta0(theta0, bottomed, element, *, forces):
    """(outputs, their partial derivatives along theta0), with the quadrature's nodes fixed.

    Exact to first order (the stresses vanish at the entry, so the Leibniz term of a first
    derivative w.r.t. theta0 is 0); its own derivative, needed only for second derivatives
    of `solve_wheel`, moves the rule with theta0 (`moving_rule`), which keeps that term
    there, at the cost of tangents through the nodes that a first derivative never pays.
    """
    return jax.jvp(lambda th: forces(th, bottomed, element), (theta0,), (jnp.ones_like(theta0),))


@_along_theta0.def_jvp
def _along_theta0_jvp(primals, tangents, *, forces):
    theta0, bottomed, element = primals
    t_theta0, _, t_element = tangents  # None: a symbolic zero, which `filter_jvp` takes as such

    def moving(theta0, element):
        return jax.jvp(
            lambda th: forces(th, bottomed, element, moving_rule=True),
            (theta0,),
            (jnp.ones_like(theta0),),
        )

    return eqx.filter_jvp(moving, (theta0, element), (t_theta0, t_element))


@eqx.filter_custom_jvp
def _implicit_root(s, masks, target, params, *, entry, forces):
    """The root s itself (computed without derivatives), carrying the implicit function
    theorem's ds for the second derivatives of `_root_outputs` (its own rule ignores the
    tangent of s; unused at first order, the computation is dropped by XLA)."""
    del masks, target, params, entry, forces
    return s


@_implicit_root.def_jvp
def _implicit_root_jvp(primals, tangents, *, entry, forces):
    s, masks, target, params = primals
    _, _, t_target, t_params = tangents
    _, _, ds = _partials_at_root(s, masks, target, params, t_target, t_params, entry, forces)
    return _implicit_root(s, masks, target, params, entry=entry, forces=forces), ds


@eqx.filter_custom_jvp
def _root_outputs(s, masks, target, params, *, entry, forces):
    """(theta0, W, R, T, M, F_y, M_z) at the root s of W(theta0(s)) = target, with
    theta0 = `entry(s, over, cap)` and the rest `forces(theta0, bottomed, element)`
    (masks = (over, bottomed), params = (cap, element)).

    Pass s as `_implicit_root(stopped s, ...)`.  The rule (`_partials_at_root`) supplies
    the implicit function theorem's derivative, so a first derivative costs one tangent
    (or, under `jax.grad`, one transposed tangent) of the output quadrature along the
    parameters and one along theta0, and nothing of the Newton iteration.
    Differentiating the rule again (second derivatives) follows s's own implicit tangent.
    """
    del target
    over, bottomed = masks
    theta_cap, element = params
    theta0 = entry(s, over, theta_cap)
    return (theta0, *forces(theta0, bottomed, element))


@_root_outputs.def_jvp
def _root_outputs_jvp(primals, tangents, *, entry, forces):
    s, masks, target, params = primals
    _, _, t_target, t_params = tangents  # the tangent of s is part of the rule's own
    out, t_out, _ = _partials_at_root(s, masks, target, params, t_target, t_params, entry, forces)
    return out, t_out
