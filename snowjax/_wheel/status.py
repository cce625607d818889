"""Outcome of the wheel equilibrium per element: `Status`, its messages, and the
`throw=True` check of `solve_wheel`."""

from __future__ import annotations

import enum

import equinox as eqx
import jax.numpy as jnp

__all__ = ["Status"]


class Status(enum.IntEnum):
    """Outcome of the equilibrium solve, per element; `Status.X.message` says what it
    means (the text `solve_wheel(..., throw=True)` raises with).

    - `CONVERGED` (0): W(theta0) = load within tolerance (1e-8 relative in float64).
    - `BOTTOMED_OUT` (1): the load exceeds what the snow layer can carry; the wheel
      rests on the base, `entry_angle = arccos(1 - 2 z_w / D)`, `sinkage = z_w`, and the
      forces are those of the snow contact at that angle (the base carries the rest).
    - `INVALID_INPUT` (2): a non-physical or NaN input (see `solve_wheel`); the
      element's fields are NaN.
    - `NOT_CONVERGED` (3): the root finder stopped without meeting the tolerance; fields
      hold its last iterate.
    - `ENTRY_ANGLE_LIMIT` (4): z_w > 0.46 D and the load needs an entry angle above
      85 degrees (the wheel would be buried to its axle), outside the model's geometry;
      fields are evaluated at 85 degrees.

    `CONVERGED` and `BOTTOMED_OUT` are equilibria (`Status.X.failed` is False); the other
    three are failures.
    """

    message: str
    failed: bool

    def __new__(cls, value: int, failed: bool, message: str):
        member = int.__new__(cls, value)
        member._value_ = value
        member.failed = failed
        member.message = message
        return member

    CONVERGED = 0, False, "W(theta0) = load within tolerance"
    BOTTOMED_OUT = (
        1,
        False,
        "the load exceeds what the snow layer can carry: the wheel rests on the base",
    )
    INVALID_INPUT = (
        2,
        True,
        "a non-physical or NaN input (a load <= 0, a slip outside [-1, 1], a terrain,"
        " wheel or distribution parameter out of range); the fields are NaN",
    )
    NOT_CONVERGED = (
        3,
        True,
        "the root finder stopped after max_steps without meeting the tolerance; the"
        " fields hold its last iterate",
    )
    ENTRY_ANGLE_LIMIT = (
        4,
        True,
        "the load needs an entry angle above 85 degrees (the wheel would be buried to its"
        " axle), outside the model's geometry; the fields are evaluated at 85 degrees",
    )


def _throw_on_failure(state):
    """`state` (a `WheelState`), with a run-time error (`eqx.branched_error_if`)
    carrying the message of the first failed element's status (in C order) if any
    element failed."""
    status = state.status.reshape(-1)
    if status.size == 0:
        return state
    failed = jnp.zeros(status.shape, bool)
    for member in Status:
        if member.failed:
            failed = failed | (status == member)
    code = jnp.where(jnp.any(failed), status[jnp.argmax(failed)], Status.CONVERGED)
    messages = [f"solve_wheel: Status.{m.name}: {m.message}" for m in Status]
    # On every field: under `jit`, an error attached to a field the caller drops is gone.
    return eqx.branched_error_if(state, jnp.any(failed), code, messages)
