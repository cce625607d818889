"""Time stepping of the longitudinal vehicle simulation: `simulate_longitudinal`.

The equations of motion, the slip and the regularisation at rest are those of `vehicle.py`;
the state is `y = (v, x, omega_1, ..., omega_n)` (speed [m/s], distance [m], wheel spins
[rad/s]).

**Time stepping** is implicit Euler (first order, L-stable) in `diffrax.diffeqsolve`: the
wheel-spin equation is stiff (the resisting torque changes with slip on a time scale
`I omega^2 r / (v dM_w/di)`, milliseconds near the self-propelled point) and the torque–slip
curve is S-shaped in braking.  Each step's implicit equation `y1 = y0 + dt f(t1, y1)` is
solved by a Levenberg–Marquardt-damped Newton iteration (`levenberg_marquardt.py`, an
`optimistix` root finder; dense forward-mode Jacobian) from a quadratic extrapolation of
the last two steps (linear after the first step), to `|residual_i| <= atol + rtol |y1_i|`.
A step it cannot solve in `newton_steps` iterations (in practice only the first steps
from rest and some braking steps) is rejected and retried with 5x smaller steps by
diffrax's step-size controller, whose error test is otherwise switched off; every other
step is `dt`, ending exactly on the grid `k dt`.  **Warm start:** the entry angles of the
last accepted Newton evaluation are kept in the diffrax *solver state* and passed to the
next `solve_wheel` as `initial_entry_angle`; they change only the inner iteration count,
never a converged value, and carry no gradient.  The solver is this module's
`_WarmStartImplicitEuler`, not `diffrax.ImplicitEuler`, whose solver state is empty (no
warm start) and which keeps a step whose root find failed (`tests/test_sim.py`).

**Saved outputs.**  The wheel outputs of the trajectory (forces, sinkage, entry angles,
slips, status) are those of each step's own wheel solves, carried in the diffrax state
next to y: they are passive unknowns of the step's root find (`_LevenbergMarquardt`'s
`passive`), equal to the force function at the step's result up to the second-order term
of the last Newton step (measured on the thesis snow, with and without ruts: within 2e-11
relative of a separate, cold-started solve at the saved states, the wheel equilibria's
own convergence), and differentiated with y by the implicit function theorem.  The
initial state's come from a first step of zero length (from -dt to 0).  (Solving the
saved states again after the integration instead took a fifth to a quarter of each
simulation's compile time.)

**Gradients** are those of the discrete trajectory (discretise-then-optimise): reverse
mode through `diffrax.RecursiveCheckpointAdjoint` (default), forward mode (`jax.jvp`,
`jax.jacfwd`) with `adjoint=diffrax.ForwardMode()` — much cheaper to compile and run for a
handful of parameters.  Each implicit step and each wheel equilibrium is differentiated
by the implicit function theorem (`optimistix.ImplicitAdjoint`).
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import Any, ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import ArrayLike, Float

from .._leaves import _is_traced
from .._terrain.base import Terrain
from .._wheel.equilibrium import _check_model
from .._wheel.model import ContactModel, _as_model, _takes_model
from .._wheel.passes import Ruts, _resolved, _VirginGround
from .._wheel.status import Status
from .levenberg_marquardt import _LevenbergMarquardt, _PassiveBlockSolver
from .options import InitialState, Stepping
from .vehicle import (
    TorqueProfile,
    Trajectory,
    Vehicle,
    _check_concrete,
    _check_dynamic_shear,
    _check_parameters,
    _check_profile,
    _torque_at,
    _wheel_forces,
)

__all__ = ["simulate_longitudinal"]


# ---------------------------------------------------------------------------------------
# The ODE term and the implicit solver
# ---------------------------------------------------------------------------------------


class _WarmStartTerm(diffrax.AbstractTerm):
    """An ODE term whose `vf(t, (y, ...), hint)` returns `(dy/dt, entry_angles, outputs,
    status)` at the state y (the first element of the diffrax state; the others, the
    carried outputs, are not read): the entry angles are the warm start of the wheel
    equilibria for the next call, `outputs` the wheel outputs that the simulation saves
    (the fields `OUTPUTS` of the term's force record, concatenated, each of length
    `num_wheels`) and `status` the equilibria's `Status` codes, which is why this is not
    a plain `diffrax.ODETerm`.  Base of the simulations' terms."""

    OUTPUTS: ClassVar[tuple[str, ...]]

    @abc.abstractmethod
    def num_wheels(self, y0) -> int:
        """Number of wheel equilibria (length of the warm start) for the state y0."""

    def pack(self, f):
        """The outputs of force record `f`: its `OUTPUTS` fields, concatenated."""
        return jnp.concatenate([getattr(f, name) for name in self.OUTPUTS])

    def unpack(self, outputs):
        """{field: (..., num_wheels)} from packed outputs (..., k)."""
        parts = jnp.split(outputs, len(self.OUTPUTS), axis=-1)
        return dict(zip(self.OUTPUTS, parts, strict=True))

    def contr(self, t0, t1, **kwargs):
        return t1 - t0

    def prod(self, vf, control):
        return vf[0] * control


class _VehicleTerm(_WarmStartTerm):
    """Right-hand side of the equations of motion, y = (v, x, omega_1..n)."""

    vehicle: Vehicle
    contact: ContactModel
    torque: Any
    speed_eps: float = eqx.field(static=True)
    max_wheel_steps: int = eqx.field(static=True)
    ground: Ruts | _VirginGround  # the terrain state the wheels run on (`_resolved`)
    OUTPUTS: ClassVar = ("longitudinal_force", "resisting_torque", "sinkage", "entry_angle", "slip")

    def forces(self, y, hint):
        """Wheel forces at state(s) y [..., n + 2] (warm start `hint`, or None)."""
        return _wheel_forces(
            y[..., :1],
            y[..., 2:],
            self.vehicle.wheel_load,
            self.vehicle.wheel,
            self.contact,
            self.speed_eps,
            hint,
            self.max_wheel_steps,
            self.ground,
        )

    def vf(self, t, y, args):
        y = y[0]
        f = self.forces(y, args)
        applied = _torque_at(self.torque, t, y[0], y[2:])
        inertia = jnp.broadcast_to(self.vehicle.wheel_inertia, applied.shape)
        dv = jnp.sum(f.longitudinal_force) / self.vehicle.mass
        domega = (applied - f.resisting_torque) / inertia
        rates = jnp.concatenate([dv[None], y[:1], domega])
        return rates, f.entry_angle, self.pack(f), f.status

    def num_wheels(self, y0):
        return y0.shape[0] - 2


# Kept: diffrax.ImplicitEuler has no state for the warm start and keeps failed steps.
class _WarmStartImplicitEuler(diffrax.AbstractAdaptiveSolver):
    """Implicit Euler for a `_WarmStartTerm`, warm-starting the wheel equilibria.

    Kept instead of `diffrax.ImplicitEuler`, which has no solver state for the warm start
    and keeps a step whose root find failed, ending the integration (see the tests).

    The diffrax state is `(y, outputs, status)`: the state y of the equations of motion
    and, carried along for saving, the term's wheel outputs and `Status` codes (as
    floats) at y.  Solves `y1 = y0 + h f(t1, y1)` for y1 with `_LevenbergMarquardt`,
    starting from a quadratic extrapolation of the last two increments; the outputs at
    y1 are passive unknowns of the same root find (residual `outputs - g(y1)`), so that
    they come from the step's own wheel solves and carry exact derivatives (implicit
    function theorem, `_PassiveBlockSolver`); they equal g at the returned y1 up to the
    second-order term of the root finder's last Newton step (of size ~tolerance).  The
    status is that of the last accepted Newton evaluation.  A step ending at or before
    t = 0 has no dynamics (`y1 = y0`): `_integrate` starts with one from -dt to 0, whose
    only result is the outputs at the initial state, and which leaves the solver state
    as it found it.  The solver state is (entry angles of the last accepted Newton
    evaluation, the last two increments of y, NaN before they are known, the last step
    size), none of which carries a gradient.  The "error estimate" is 0 for a solved step
    and inf for a step whose implicit equation was not solved, so that a step-size
    controller retries such a step with a smaller one; if it keeps the step anyway (at
    its `dtmin`), the root finder's failure is the step's result and ends the
    integration.
    """

    term_structure: ClassVar = _WarmStartTerm
    interpolation_cls: ClassVar = diffrax.LocalLinearInterpolation
    rtol: float
    atol: float
    max_steps: int = 100

    def order(self, terms):
        return 1

    def init(self, terms, t0, t1, y0, args):
        y0 = y0[0]
        term = terms
        while not isinstance(term, _WarmStartTerm):  # unwrap diffrax's WrapTerm
            term = term.term
        hint = jnp.full((term.num_wheels(y0),), jnp.nan, y0.dtype)
        unknown = jnp.full_like(y0, jnp.nan)  # no increments yet
        return hint, unknown, unknown, jnp.asarray(t1 - t0, y0.dtype)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        hint, increment, previous, h_prev = solver_state
        y0, outputs0, status0 = y0
        m = y0.shape[0]
        h = t1 - t0
        still = t1 <= 0  # the step onto t = 0: y1 = y0, for the outputs there
        # Predictor: quadratic extrapolation of the last two increments (scaled to h);
        # linear after the first step, constant before it.
        ratio = h / h_prev
        known = jnp.isfinite(increment)
        last = jnp.where(known, increment, 0.0)
        before = jnp.where(jnp.isfinite(previous), previous, last)
        predictor = y0 + ratio * last + ratio * (ratio + 1) / 2 * (last - before)

        def residual(z, _):
            y1, outputs1 = z[:m], z[m:]
            dydt, entry_angle, outputs, status = terms.vf(t1, (y1, outputs1), hint)
            rate = jnp.where(still, 0.0, h * dydt)
            return jnp.concatenate([y1 - y0 - rate, outputs1 - outputs]), (entry_angle, status)

        k = outputs0.shape[0]
        sol = optx.root_find(
            residual,
            _LevenbergMarquardt(rtol=self.rtol, atol=self.atol, passive=k),
            jnp.concatenate([predictor, jnp.zeros_like(outputs0)]),
            has_aux=True,
            throw=False,
            max_steps=self.max_steps,
            # Derivatives are also evaluated for steps the controller then rejects, at
            # whatever iterate the failed solve stopped: a least-squares (SVD) solve of
            # the implicit-function-theorem system never raises on a singular Jacobian.
            adjoint=optx.ImplicitAdjoint(linear_solver=_PassiveBlockSolver(passive=k)),
        )
        y1, outputs1 = sol.value[:m], sol.value[m:]
        entry_angle, status = sol.aux
        hint = jax.lax.stop_gradient(jnp.where(jnp.isfinite(entry_angle), entry_angle, hint))
        new_increment = jax.lax.stop_gradient(y1 - y0)
        new_increment = jnp.where(jnp.isfinite(new_increment), new_increment, 0.0)
        previous = jnp.where(known, increment * ratio, jnp.nan)
        state = (hint, new_increment, previous, jax.lax.stop_gradient(h))
        state = jax.tree.map(lambda old, new: jnp.where(still, old, new), solver_state, state)
        solved = sol.result == optx.RESULTS.successful
        y1 = (y1, outputs1, status.astype(y1.dtype))
        y_error = (
            jnp.where(solved, jnp.zeros_like(y0), jnp.inf),
            jnp.zeros_like(outputs1),
            jnp.zeros_like(status0),
        )
        y0 = (y0, outputs0, status0)
        return y1, y_error, dict(y0=y0, y1=y1), state, diffrax.RESULTS.promote(sol.result)

    def func(self, terms, t0, y0, args):
        _, outputs, status = y0
        return terms.vf(t0, y0, None)[0], jnp.zeros_like(outputs), jnp.zeros_like(status)


def _tolerances(dtype):
    return (1e-9, 1e-9) if dtype == jnp.float64 else (1e-5, 1e-6)


def _y_norm(scaled_error):
    """The step-size controller's error norm: that of y's error only (the carried outputs'
    error is 0, but their scale in it, 0 * |output|, is NaN for an inf output)."""
    return optx.rms_norm(scaled_error[0])


def _integrate(term, y0, n_steps, dt, save_every, adjoint, newton_steps):
    """Implicit Euler steps of `dt` from y0 over `n_steps` of a `_WarmStartTerm`: (saved
    times, saved states, {output field: saved values}, saved `Status` codes, diffrax
    result).  Shared by the simulations of this package."""
    dtype = y0.dtype
    rtol, atol = _tolerances(dtype)
    ts = jnp.arange(n_steps + 1, dtype=dtype) * jnp.asarray(dt, dtype)
    save_ts = ts[::save_every]
    solver = _WarmStartImplicitEuler(rtol=rtol, atol=atol, max_steps=newton_steps)
    # Steps of dt onto the grid ts.  The controller's error test is switched off (the
    # solver reports error 0); it only retries a step whose implicit equation was not
    # solved (error inf) with a 5x smaller one, then grows back.  Its dtmax (2 dt) is
    # above dt so that the grid ts, not a rounded t + dt, ends every step: with dtmax = dt
    # a step could stop 3e-17 s short of a grid time, and the steps after that remainder
    # regrew from dtmin (about 40 % more steps).
    controller = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=0.0, atol=1.0, dtmax=2 * dt, dtmin=1e-4 * dt, norm=_y_norm),
        step_ts=ts,
    )
    # The outputs of the wheels are carried in the state (the solver's docstring): the
    # first step, from -dt to 0, only sets those at y0.
    k = len(term.OUTPUTS) * term.num_wheels(y0)
    status = jnp.zeros(term.num_wheels(y0), dtype)
    sol = diffrax.diffeqsolve(
        term,
        solver,
        -ts[1],
        ts[-1],
        dt0=dt,
        y0=(y0, jnp.zeros(k, dtype), status),
        stepsize_controller=controller,
        saveat=diffrax.SaveAt(ts=save_ts),
        adjoint=adjoint,
        max_steps=2 * n_steps + 65,
        throw=False,
    )
    assert sol.ys is not None  # saveat=SaveAt(ts=...) saves the states
    ys, outputs, status = sol.ys
    # Rows after a failed step hold inf (diffrax's fill value).
    status = jnp.where(jnp.isfinite(status), status, Status.INVALID_INPUT).astype(jnp.int32)
    return save_ts, ys, term.unpack(outputs), status, sol.result


def _check_run(wheel, model, t1, dt, initial, stepping) -> int:
    """Checks shared by the simulations' entry points; returns the number of steps."""
    if not isinstance(initial, InitialState):
        raise TypeError(f"initial must be a snowjax.InitialState, got {type(initial).__name__}")
    if not isinstance(stepping, Stepping):
        raise TypeError(f"stepping must be a snowjax.Stepping, got {type(stepping).__name__}")
    for name in ("speed", "wheel_speed", "yaw_rate"):
        value = getattr(initial, name)
        _check_concrete(f"initial.{name}", value, lambda x: np.ones_like(x, bool), "a number")
    _check_dynamic_shear(model.shear, "the simulations")
    _check_model(wheel, model)
    _check_parameters(wheel, model)
    for name, value in (("t1", t1), ("dt", dt)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0; got {value!r}")
    n_steps = int(round(t1 / dt))
    if n_steps < 1:
        raise ValueError(f"t1 / dt must be >= 1 step; got t1={t1!r}, dt={dt!r}")
    return n_steps


# The keywords the simulations grouped into `InitialState` and `Stepping`.
_MOVED_TO_OPTIONS = {
    "initial_speed": "initial=InitialState(speed=...)",
    "initial_wheel_speed": "initial=InitialState(wheel_speed=...)",
    "initial_yaw_rate": "initial=InitialState(yaw_rate=...)",
    **{
        name: f"stepping=Stepping({name}=...)"
        for name in ("speed_eps", "save_every", "adjoint", "newton_steps", "wheel_max_steps")
    },
}


@eqx.filter_jit
def _simulate_jit(term, y0, n_steps, dt, save_every, adjoint, newton_steps):
    save_ts, ys, f, status, result = _integrate(
        term, y0, n_steps, dt, save_every, adjoint, newton_steps
    )
    applied = jax.vmap(lambda t, y: _torque_at(term.torque, t, y[0], y[2:]))(save_ts, ys)
    return Trajectory(
        time=save_ts,
        speed=ys[:, 0],
        distance=ys[:, 1],
        wheel_speed=ys[:, 2:],
        slip=f["slip"],
        sinkage=f["sinkage"],
        entry_angle=f["entry_angle"],
        drawbar_pull=f["longitudinal_force"],
        resisting_torque=f["resisting_torque"],
        applied_torque=applied,
        status=status,
        result=result,
    )


@_takes_model(positional=5, **_MOVED_TO_OPTIONS)
def simulate_longitudinal(
    vehicle: Vehicle,
    snow: Terrain | ContactModel,
    torque: Float[ArrayLike, "..."] | TorqueProfile | Callable,
    t1: float,
    dt: float,
    *,
    initial: InitialState = InitialState(),
    ruts: Ruts | None = None,
    stepping: Stepping = Stepping(),
) -> Trajectory:
    """Simulate a vehicle driving straight on snow; differentiable end to end.

    Integrates `m dv/dt = sum_k F_k`, `dx/dt = v`, `I domega_k/dt = T_k - M_k` (vehicle
    speed, distance, every wheel's spin; F_k and M_k of `wheel_forces`: the quasi-static
    equilibrium (4.14) via `solve_wheel` at the slip of eq. 2.6, regularised at rest)
    from t = 0 to `t1` with implicit Euler steps of `dt` inside `diffrax.diffeqsolve`,
    each solved by a damped Newton (Levenberg–Marquardt) iteration; a step whose implicit
    equation is not solved (rare: the first steps from rest) is retried as smaller steps
    by the step-size controller, so the saved times are always the grid `k dt`.
    Gradients w.r.t. every array leaf of `vehicle`, `snow` (the model's distribution and
    terms too) and `torque` (and the initial state) are exact derivatives of the discrete
    trajectory: `jax.grad` uses `stepping.adjoint` (default
    `diffrax.RecursiveCheckpointAdjoint()`); for `jax.jvp`/`jax.jacfwd` pass
    `stepping=Stepping(adjoint=diffrax.ForwardMode())`, which compiles and runs much
    faster for a few parameters.  The entry point is jitted (`eqx.filter_jit`):
    calls with new array values reuse the compiled program; new shapes, `t1`, `dt`,
    static options or a new Python callable as `torque` compile anew.

    **Arguments:**

    - `vehicle`: `Vehicle` (mass [kg], wheel inertia [kg m^2], wheel, number of wheels).
    - `snow`: the terrain, any `snowjax.Terrain` (`WongSnow`, `BekkerSoil`,
      `ReeceSoil`, `LayeredSnow`; SI); scalar leaves.  Or a `ContactModel` (its stress
      distribution, nodes per panel and force terms, scalar leaves; its shear law
      `JanosiHanamoto()` or `NoShear()`: `ThesisSimplified()` is refused, its braking
      extension can push a braked wheel forward).
    - `torque`: applied torque per wheel T [N m], positive driving forwards: a number
      or an array of shape (n,) (constant), a `TorqueProfile` (piecewise linear in t),
      or a callable `torque(t, speed, wheel_speed) -> () or (n,)` (a controller; make it
      an `eqx.Module` so that its parameters are traced and differentiable).
    - `t1`: final time [s]; `dt`: time step [s] (`round(t1 / dt)` steps; both static:
      each new value compiles anew).
    - `initial`: `InitialState(speed [m/s], wheel_speed [rad/s], yaw_rate=0)`, the
      state at t = 0 (default: at rest; `wheel_speed` a number or (n,), default
      `speed / r`, free rolling).
    - `ruts`: None (default: every wheel on virgin snow, as before), or `Ruts(k_0,
      a_u, follows)`: the wheels run in the ruts of the wheels ahead (by default the
      last half behind the first half; `multi_pass`'s model at every instant).  A
      following wheel's `sinkage` is then measured below the floor of its rut.
    - `stepping`: `Stepping(save_every, adjoint, newton_steps, wheel_max_steps,
      speed_eps)`, how the run steps and what it saves (default: every step saved,
      `RecursiveCheckpointAdjoint`, 100 Newton steps per implicit step, 64 per wheel
      equilibrium, `speed_eps` 0.05 m/s).

    **Returns:** `Trajectory` with `1 + round(t1 / dt) // stepping.save_every` rows.

    **Accuracy.**  First order in `dt`: on the thesis tyre and snow the speed of a
    0.05 s (0.1 s) step run is within 0.35 % (0.7 %) of a 0.004 s run over 8 s of
    acceleration; the quasi-static steady state (drawbar pull 0, constant slip) is
    reproduced exactly whatever `dt`.  Each implicit step is solved to
    `|y1 - y0 - dt f(t1, y1)| <= 1e-9 (1 + |y1|)` componentwise in float64
    (`1e-6 + 1e-5 |y1|` in float32).

    **Cost.**  About 1–3 damped Newton iterations per step (more in hard braking and on
    the first steps from rest), each one `solve_wheel` of all wheels (warm-started) plus
    its forward-mode Jacobian: measured 14 us per step per wheel (4 wheels, 400 N m,
    dt = 10 ms, float64, on the project's shared 2-core CPU machine; the README's
    benchmark table has the current figure).

    **Errors.**  `ValueError` for a non-positive or non-finite `t1`, `dt`, `speed_eps`,
    `save_every`, mass, wheel inertia, a malformed `TorqueProfile` or non-finite initial
    speeds (with concrete values).  A step that cannot be solved even after the
    retries stops the integration: `result` is set (no exception) and the remaining rows
    hold inf states with `Status.INVALID_INPUT`.  Concrete snow or wheel parameters
    outside `solve_wheel`'s valid range (say tan phi < 0, or NaN) raise `ValueError`
    naming the field; traced ones give NaN forces and a failed `result`, and
    differentiated they make lineax raise on the non-finite values inside the implicit
    solves, so optimise positive parameters through their logarithms.
    """
    model = _as_model(snow, "snow")
    if not isinstance(vehicle, Vehicle):
        raise TypeError(f"vehicle must be a snowjax.Vehicle, got {type(vehicle).__name__}")
    n_steps = _check_run(vehicle.wheel, model, t1, dt, initial, stepping)
    _check_concrete("vehicle.mass", vehicle.mass, lambda x: x > 0, "> 0 kg")
    _check_concrete("vehicle.wheel_inertia", vehicle.wheel_inertia, lambda x: x > 0, "> 0 kg m^2")
    if not (_is_traced(initial.yaw_rate) or np.all(np.asarray(initial.yaw_rate) == 0)):
        raise ValueError(
            f"simulate_longitudinal drives straight: initial.yaw_rate must be 0, got "
            f"{initial.yaw_rate!r} (simulate_planar steers)"
        )
    n = vehicle.num_wheels
    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"vehicle.num_wheels must be a positive int; got {n!r}")
    if isinstance(torque, TorqueProfile):
        _check_profile(torque, n)
    dtype = jnp.result_type(
        vehicle.mass, *jax.tree_util.tree_leaves((model.terrain, model.distribution)), float
    )
    speed0 = jnp.asarray(initial.speed, dtype)
    wheel_speed0 = initial.wheel_speed
    if wheel_speed0 is None:
        wheel_speed0 = speed0 / (vehicle.wheel.diameter / 2)
    y0 = jnp.concatenate(
        [
            speed0.reshape(1),
            jnp.zeros(1, dtype),
            jnp.broadcast_to(jnp.asarray(wheel_speed0, dtype), (n,)),
        ]
    )
    if not callable(torque):
        _check_concrete("torque", torque, lambda x: np.ones_like(x, bool), "[N m]")
        torque = jnp.asarray(torque, dtype)
    ground = _resolved(ruts, n)
    term = _VehicleTerm(
        vehicle=vehicle,
        contact=model,
        torque=torque,
        speed_eps=stepping.speed_eps,
        max_wheel_steps=64 if stepping.wheel_max_steps is None else stepping.wheel_max_steps,
        ground=ground,
    )
    return _simulate_jit(
        term, y0, n_steps, float(dt), stepping.save_every, stepping.adjoint, stepping.newton_steps
    )
