"""The whole batch, vmapped axes included: reductions over it (the predicates of the
solver's `lax.cond`s: a quadrature layout, an integral needed only by some elements),
and the work of a vmapped batch in chunks (`_vmapped_in_chunks`)."""

from __future__ import annotations

from collections.abc import Callable

import equinox as eqx
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


# Elements solved together: on a CPU, chunks keep the quadrature's (chunk, nodes)
# intermediates in cache and let each chunk stop iterating on its own; an accelerator
# needs wide chunks to fill it (1 GB of intermediates in float64).  A flat batch of
# `solve_wheel` (`equilibrium._in_chunks`) and a vmapped one (`_vmapped_in_chunks`).
CHUNK_SIZE = 2048
ACCELERATOR_CHUNK_SIZE = 65536


def _chunk_size() -> int:
    """Elements per chunk on the default backend (`CHUNK_SIZE` on a CPU)."""
    return CHUNK_SIZE if jax.default_backend() == "cpu" else ACCELERATOR_CHUNK_SIZE


def _vmapped_in_chunks(fn: Callable, per_call: int) -> Callable:
    """`fn`, whose `jax.vmap` runs the vmapped batch as `lax.map` over chunks of it.

    Vmapped over environments (MJX, RL), each environment's few wheels become one
    batch of all environments' wheels, whose quadrature intermediates (every wheel x
    node x tangent) outgrow the CPU's caches.  `solve_wheel` chunks its own flat
    batches (`equilibrium._in_chunks`); this does it for a vmap applied from outside,
    by a `jax.custom_batching.custom_vmap` rule: chunks of `_chunk_size() // per_call`
    calls (`per_call`: elements, e.g. wheels, per call of `fn`), the last padded by
    repeating the batch's last call.  Nested vmaps: the innermost is chunked, the
    outer ones batch that loop.  Measured on the rover in MJX (four wheels,
    warm-started equilibria at their slip angles with three forward-mode slopes each),
    1,024 environments, float64: its wheel forces' cost per wheel on one core 8.7 ->
    3.8-4.2 us in chunks of 128-1,024 wheels (`_forces_and_slopes` alone); the
    environment step on 2 cores 41.7 -> 35.2-37.2 us (chunks of 2,048 a little faster
    there than of 512).

    Derivatives: `custom_vmap` has no reverse-mode rule, so the function carries a
    `jax.custom_jvp` whose rule is the plain `fn`'s JVP (not chunked): forward and
    reverse mode, and any order, are `fn`'s own; only an undifferentiated vmapped call
    (a rollout, an RL environment's step) runs in chunks.  Outputs agree with `fn`'s
    within rounding, except where `fn` chooses by `_any_in_batch`: each chunk chooses
    for itself (the rules it chooses between agree within their accuracy).

    Arguments of `fn` may be any pytrees; their array leaves are its inputs (the rest is
    static).  Returns a function of the same arguments.
    """

    def chunked_fn(*args):
        dynamic, static = eqx.partition(args, eqx.is_array)

        def plain(dynamic):
            return fn(*eqx.combine(dynamic, static))

        @jax.custom_batching.custom_vmap
        def in_chunks(dynamic):
            return plain(dynamic)

        @in_chunks.def_vmap
        def in_chunks_vmap(axis_size, in_batched, dynamic):
            (in_batched,) = in_batched  # one per argument of `in_chunks`
            size = max(1, _chunk_size() // max(per_call, 1))
            axes = jax.tree_util.tree_map(lambda b: 0 if b else None, in_batched)
            batched_plain = jax.vmap(plain, in_axes=(axes,))
            if axis_size <= size:
                out = batched_plain(dynamic)
            else:
                n = -(-axis_size // size)
                pad = n * size - axis_size

                def split(x, b):  # (axis_size, ...) -> (n, size, ...), padded
                    if not b:
                        return x
                    if pad:
                        x = jnp.concatenate([x, jnp.broadcast_to(x[-1:], (pad, *x.shape[1:]))])
                    return x.reshape(n, size, *x.shape[1:])

                parts = jax.tree_util.tree_map(split, dynamic, in_batched)
                batched, fixed = eqx.partition(parts, in_batched)

                def one(chunk):
                    return batched_plain(eqx.combine(chunk, fixed))

                out = jax.lax.map(one, batched)
                out = jax.tree_util.tree_map(
                    lambda x: x.reshape(n * size, *x.shape[2:])[:axis_size], out
                )
            return out, jax.tree_util.tree_map(lambda _: True, out)

        @jax.custom_jvp
        def call(dynamic):
            return in_chunks(dynamic)

        @call.defjvp
        def call_jvp(primals, tangents):
            return jax.jvp(plain, primals, tangents)

        return call(dynamic)

    return chunked_fn
