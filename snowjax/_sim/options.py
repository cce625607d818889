"""The settings the two simulations take as modules, as diffrax groups its
`stepsize_controller`, `adjoint` and `saveat`: `InitialState` (where the vehicle starts,
diffrax's `y0`) and `Stepping` (how it steps and what it saves)."""

from __future__ import annotations

import diffrax
import equinox as eqx
from jaxtyping import ArrayLike, Float

from .vehicle import DEFAULT_SPEED_EPS

__all__ = ["InitialState", "Stepping"]


class InitialState(eqx.Module):
    """The vehicle's state at t = 0 (`initial=` of `simulate_longitudinal` and
    `simulate_planar`): at the origin, heading along +X, with no lateral speed.

    **Fields:**

    - `speed`: forward speed v(0) (u(0) in the plane) [m/s]; default 0, at rest.
    - `wheel_speed`: the wheels' spins omega(0) [rad/s], a number or one per wheel;
      default None: `speed / r` (free rolling, slip 0).
    - `yaw_rate`: r(0) [rad/s] (`simulate_planar` only; `simulate_longitudinal` refuses
      a non-zero one); default 0.

    Its array leaves are traced, so trajectories differentiate w.r.t. them.
    """

    speed: Float[ArrayLike, ""] = 0.0
    wheel_speed: Float[ArrayLike, "..."] | None = None
    yaw_rate: Float[ArrayLike, ""] = 0.0


def _positive_int(name):
    def convert(value):
        if isinstance(value, bool) or int(value) != value or int(value) < 1:
            raise ValueError(f"Stepping.{name} must be a positive integer; got {value!r}")
        return int(value)

    return convert


def _adjoint(adjoint):
    return diffrax.RecursiveCheckpointAdjoint() if adjoint is None else adjoint


def _speed_eps(value):
    value = float(value)
    if not (value > 0 and value < float("inf")):
        raise ValueError(f"Stepping.speed_eps must be finite and > 0 m/s; got {value!r}")
    return value


class Stepping(eqx.Module):
    """How a simulation steps and what it saves (`stepping=` of `simulate_longitudinal`
    and `simulate_planar`); every field static (a new value compiles anew).

    **Fields:**

    - `save_every`: save every k-th step (int >= 1; default 1).
    - `adjoint`: the `diffrax.AbstractAdjoint` of reverse mode (default None:
      `diffrax.RecursiveCheckpointAdjoint()`); `diffrax.ForwardMode()` for `jax.jvp` /
      `jax.jacfwd`, much cheaper for a few parameters.
    - `newton_steps`: iteration limit of each implicit step's damped Newton solve (int
      >= 1; default 100); a step not solved within it is retried as smaller steps.
    - `wheel_max_steps`: Newton iteration limit of each wheel equilibrium
      (`solve_wheel`'s `max_steps`; int >= 1).  Default None: 64 in
      `simulate_longitudinal`; 5 in `simulate_planar`, `solve_wheel`'s batch-wide first
      phase only: warm-started, the equilibria converge in one to three steps, and cold
      (the initial state, the first step) within five on the snows checked (the
      thesis's fresh and plate-rule snows and `BekkerSoil.snow_us`, 1-8 kN, slips -1 to
      1, slip angles up to 85 degrees); without the straggler phase the program compiles
      in about 70 % of the time.  An equilibrium not converged within the limit shows
      as `Status.NOT_CONVERGED` in `status`; raise the limit then.
    - `speed_eps`: the regularisation speed at rest [m/s], > 0 (default 0.05; see
      `wheel_kinematics`).
    """

    save_every: int = eqx.field(static=True, converter=_positive_int("save_every"), default=1)
    adjoint: diffrax.AbstractAdjoint = eqx.field(static=True, converter=_adjoint, default=None)
    newton_steps: int = eqx.field(static=True, converter=_positive_int("newton_steps"), default=100)
    wheel_max_steps: int | None = eqx.field(
        static=True,
        converter=lambda v: v if v is None else _positive_int("wheel_max_steps")(v),
        default=None,
    )
    speed_eps: float = eqx.field(static=True, converter=_speed_eps, default=DEFAULT_SPEED_EPS)

    def __check_init__(self):
        if not isinstance(self.adjoint, diffrax.AbstractAdjoint):
            raise TypeError(
                f"Stepping.adjoint must be a diffrax.AbstractAdjoint, got "
                f"{type(self.adjoint).__name__}"
            )
