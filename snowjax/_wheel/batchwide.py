"""Reductions over a whole batch, vmapped axes included: the predicates of the solver's
`lax.cond`s (a quadrature layout, an integral needed only by some elements)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array

__all__: list[str] = []


@jax.custom_batching.custom_vmap
def _any_in_batch(x: Array) -> Array:
    """`jnp.any(x)`, and under `jax.vmap` the same over the vmapped axes too: one
    unbatched boolean for the whole batch (a `lax.cond` on it stays a branch).

    A `lax.cond` whose predicate is batched becomes a select that runs both branches:
    vmapped over environments (the rover in MJX, each environment's four wheels one
    batch), the choice of quadrature layout per batch (`contact._with_rule_for`) ran
    both layouts, and the closed-form start's capacity (`front_rim._closed_form_bracket`)
    was always integrated.  With this predicate a vmapped batch chooses as one flat
    batch of all its elements does: the braking layout for every element when any of
    them brakes (either layout is within the rule's accuracy of the integrals).  `x`: a
    boolean array (no derivative)."""
    return jnp.any(x)


@_any_in_batch.def_vmap
def _any_in_batch_vmap(axis_size, in_batched, x):
    del axis_size, in_batched
    return _any_in_batch(x), False  # (nested vmaps: each level reduces its own axis)


def _all_in_batch(x: Array) -> Array:
    """`jnp.all(x)` over the batch and every vmapped axis (`_any_in_batch`)."""
    return ~_any_in_batch(~x)
