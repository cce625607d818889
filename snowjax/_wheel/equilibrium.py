"""The sinkage-versus-slip equilibrium of a rigid wheel on shallow snow (eq. 4.14).

`solve_wheel` finds the entry angle theta0 at which the vertical resultant of the rim
stresses carries the wheel load, W(theta0) = F_z, with `optimistix.root_find` (kept
inside a bracket, `bracketed.py`): one solver (`_solve_layout`) for every terrain,
stress distribution, shear law and slip angle, which takes its contact integrals, its
start and its steps from the contact rule (`rules.py`: the any-terrain rule, whose cold
start on a law that rises is a power-law model of the law, on a law that can fall W at
a few entry angles, and whose steps are secant steps, `BracketedSecant`; or the
closed-form accelerations of `front_rim.py` where the terrain offers them, started from
the closed-form no-shear balance, and warm starts, by Newton steps, `BracketedNewton`).
The unknown is s >= s_min with `theta0 = theta_cap exp(-s^2)` and the residual is
`ln(W / F_z)`.  Near the base W approaches the layer's capacity like
`W_cap - k sqrt(theta_cap - theta0)`, i.e. linearly in s, and for shallow sinkage
W ~ theta0^3, i.e. `ln W ~ -3 s^2`: in these variables the residual is smooth and
Newton's method converges in a few steps from either start (the secant interpolates in
s^2, where a power law is linear).  The bound
s >= s_min = 1e-6 keeps every iterate strictly inside the snow layer (theta_cap - theta0
>= 1e-12 theta_cap), where the residual and its derivative are finite.

Gradients with respect to every parameter leaf, the load and the slip come from the
implicit function theorem at the root (`_root_outputs`, a custom JVP rule), not from
unrolling the Newton iterations: the root finder runs on stopped inputs, and one
linearisation of the output quadrature at the root gives dtheta0 and the forces' total
derivatives together (one tangent pass along the solver variable, one along the
parameters; `jax.grad` transposes the latter).
"""

from __future__ import annotations

import functools
import math
from typing import cast

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

from .._leaves import _is_traced
from .._terrain.base import Terrain, _half_angle_arc
from .batchwide import _all_in_batch, _any_in_batch, _chunk_size
from .bracketed import solve_elementwise
from .contact import _broadcast_leaves, _contact_batch, _layout, _with_rule_for
from .front_rim import _contact_rule
from .geometry import AbstractWheel
from .inputs import (
    _broadcast_shape,
    _check_lateral_and_terms,
    _check_model,
    _check_options,
    _check_rules,
    _fits,
    _magnitude_window,
    _numeric_argument,
    _valid_mask,
    _validate_eagerly,
)
from .model import ContactModel, _as_model, _takes_model
from .root import _implicit_root, _root_outputs
from .running import _STRAIGHT, AbstractRunning, SlipAngle, _angle_rules, _default_lateral
from .start import _balance_residual, _power_law_root, _theta_from_s
from .status import Status, _throw_on_failure
from .terms import _term_rules

__all__ = ["Status", "WheelState", "solve_wheel", "MAX_ENTRY_ANGLE"]

# The rim geometry (4.5)-(4.8) and the simplified model's tau2 = 1/cos(theta0) - 1 need
# theta0 below 90 degrees; the solver stops at 85 degrees (z0 = 0.46 D).
MAX_ENTRY_ANGLE = float(np.deg2rad(85.0))


class WheelState(eqx.Module):
    """Equilibrium of a rigid wheel on snow; every field has the broadcast input shape.

    - `entry_angle`: theta0 [rad].
    - `sinkage`: z0 = D/2 (1 - cos theta0), eq. (4.15) [m]; for a `DeflectingTire` the
      sinkage of its flat (`AbstractWheel.contact_sinkage`).
    - `motion_resistance`: R_x, eq. (4.16) [N].
    - `thrust`: horizontal component of the shear stress, eq. (2.9) times r b [N].
    - `drawbar_pull`: thrust - motion resistance, eq. (2.10) [N].
    - `torque`: M_w, eq. (2.12) [N m] (the wheel torque the snow resists).
    - `lateral_force`: F_y [N], along the axle, positive when the slip angle is positive
      (it resists the side-slip; see `solve_wheel`'s `slip_angle`); 0 without a slip angle.
    - `aligning_torque`: M_z [N m], moment of the lateral stresses (and the bulldozing
      resistance) about the vertical through the wheel centre, positive counter-clockwise
      seen from above (x forward, y left, z up); 0 without a slip angle.
    - `status`: `Status` code (int32).
    """

    entry_angle: Float[Array, "..."]
    sinkage: Float[Array, "..."]
    motion_resistance: Float[Array, "..."]
    thrust: Float[Array, "..."]
    drawbar_pull: Float[Array, "..."]
    torque: Float[Array, "..."]
    lateral_force: Float[Array, "..."]
    aligning_torque: Float[Array, "..."]
    status: Int[Array, "..."]


# ---------------------------------------------------------------------------------------
# The per-element solve
# ---------------------------------------------------------------------------------------


def _tolerance(dtype, accuracy: str = "reference") -> float:
    # The solvers stop once |ln(W / F_z)| < tol at the iterate before their last step (or
    # the last steps predict it below tol / 10), so the returned root is balanced below
    # tol (typically 1e-15 in float64 after Newton, 1e-11 after secant steps).  The
    # simulator accuracy's quadrature errs by up to ~3e-4 of the load: its solves stop
    # at 1e-6 in float64 (Newton after one step from |f| <= 3.2e-4,
    # `bracketed._finished`), balanced within 1e-5 (`_solve_layout`'s check).
    if dtype != jnp.float64:
        return 2e-5
    return 1e-6 if accuracy == "simulator" else 1e-9


def _entry_angle_cap(depth, diameter):
    """(theta_cap, reaches_base): the largest admissible entry angle [rad], the base's
    arccos(1 - 2 depth / D) capped at 85 degrees, and whether the base lies within it.

    The base angle is pi for a layer deeper than the wheel and for an infinitely deep
    terrain, 0 for a base at the surface; `where` keeps gradients finite there (arccos'
    is infinite at +-1, and reverse mode would otherwise form 0 * inf w.r.t. the
    diameter).
    """
    finite = jnp.isfinite(depth)
    cos_base = jnp.where(finite, 1 - 2 * jnp.where(finite, depth, 0.0) / diameter, -jnp.inf)
    inside = (cos_base > -1) & (cos_base < 1)
    theta_base = jnp.where(inside, jnp.arccos(jnp.where(inside, cos_base, 0.0)), jnp.pi)
    # A base at the surface (a rut pressed to the base): no contact, a finite gradient.
    theta_base = jnp.where(cos_base >= 1, 0.0, theta_base)
    return jnp.minimum(theta_base, MAX_ENTRY_ANGLE), theta_base <= MAX_ENTRY_ANGLE


# ---------------------------------------------------------------------------------------
# The solve
# ---------------------------------------------------------------------------------------


def _solve_layout(
    wheel, terrain, distribution, load, slip, guess, running, terms, *, options, braking
):
    """Equilibrium of a flat batch (every leaf of shape (B,)) with one quadrature layout.

    Every terrain, distribution, shear law and slip angle: the contact integrals come from
    `_contact_batch`, the start from the contact rule in `options` (`rules.py`).  The
    batch is one `optx.root_find` (`BracketedNewton`, or `BracketedSecant` where the start
    gives the secant's options: kept inside a bracket, bisecting where a step would leave
    it) with a diagonal Jacobian (the elements are independent), so a Newton step is one
    tangent evaluation, a secant step one evaluation of W.  Every element's root lies in
    [lower, upper]: W > target at the
    deep end, W < target at the shallow one; W need not be monotone in between (a braked
    wheel's backward shear pulls it down; a layered snow's crust breaks).

    `running` (`running.py`: straight or a slip angle) and `terms`, the model's own force
    terms, have leaves per element.
    Returns (theta0, R, T, M, F_y, M_z, status).
    """
    shear, n, max_steps, rule, accuracy = options
    # Everything up to the root carries no derivative (`_root_outputs` supplies it there):
    # the solve runs on stopped copies of the inputs.
    differentiable = (wheel, terrain, distribution, load, slip, running, terms)
    wheel, terrain, distribution, load, slip, running, terms = jax.lax.stop_gradient(differentiable)
    tol = _tolerance(load.dtype, accuracy)
    reach = type(wheel).deepest_reach(wheel, terrain)
    theta_cap, reaches_base = _entry_angle_cap(reach, wheel.diameter)
    contact = functools.partial(
        _contact_batch,
        shear=shear,
        n=n,
        braking=braking,
        rule=rule,
    )

    def vertical(theta0) -> Array:  # W of every element
        return cast(
            Array,
            contact(theta0, slip, wheel, terrain, distribution, running, terms, vertical_only=True),
        )

    if guess is None:
        start = rule.start(
            vertical, theta_cap, load, slip, wheel, terrain, distribution, shear, braking
        )
    else:
        start = rule.warm_start(vertical, theta_cap, load, slip, guess, wheel, terrain)
    over, target, lower, upper, s0, secant = start

    # An element the layer cannot carry is held at the cap (`forces`): its residual is 0,
    # so it leaves the batch's Newton iteration at once (a layer that carries nothing,
    # e.g. a rut pressed to the base, has no positive target to solve for).
    target = jnp.where(over, load, target)

    def residual(s, params):
        th_cap, tgt, held, *element = params
        w = contact(_theta_from_s(s, th_cap), *element, vertical_only=True)
        return jnp.where(held, 0.0, _balance_residual(w, tgt))

    # A start that is not finite (a layer of no depth, a rut pressed to the base, where
    # the closed-form start divides by its cap) would stop the whole batch's iteration:
    # such an element starts at its bracket's shallow end.
    s0 = jnp.where(jnp.isfinite(s0), s0, upper)
    s, f_end = solve_elementwise(
        residual,
        jnp.clip(s0, lower, upper),
        lower,
        upper,
        (theta_cap, target, over, slip, wheel, terrain, distribution, running, terms),
        tol,
        max_steps,
        secant,
        one_step=accuracy == "simulator",
    )
    if secant:
        # The power-law start holds no element at the cap: one that ended on it is
        # beyond the layer's capacity where W there falls short of the load.  W at the
        # cap is target exp(f) where the solver's last evaluation was there (an element
        # whose bracket collapsed onto the cap), else evaluated, only where some element
        # needs it.  A scan start's elements held at the cap stay held.
        at_cap = (s <= lower) & ~over
        known = jnp.isfinite(f_end)
        seen = jnp.where(known, target * jnp.exp(jnp.where(known, f_end, 0.0)), jnp.inf)
        capacity = jax.lax.cond(
            _any_in_batch(at_cap & ~known),
            lambda: jnp.where(known, seen, vertical(_theta_from_s(lower, theta_cap))),
            lambda: seen,
        )
        newly = at_cap & (load >= capacity)
        over = over | newly
        target = jnp.where(newly, 0.5 * capacity, target)

    def entry(s, over, th_cap):  # theta0 at s (held at the cap where over it)
        return jnp.where(over, th_cap, _theta_from_s(s, th_cap))

    def forces(theta0, bottomed, element, moving_rule=False):  # (W, R, T, M, F_y, M_z)
        return contact(theta0, *element, bottomed=bottomed, moving_rule=moving_rule)

    # Derivatives at the root: w.r.t. the load where balanced (the targets of elements
    # held at the cap do not enter their outputs).
    wheel, terrain, distribution, load, slip, running, terms = differentiable
    reach = type(wheel).deepest_reach(wheel, terrain)
    theta_cap = _entry_angle_cap(reach, wheel.diameter)[0]
    root = (
        (over, over & reaches_base),
        load,
        (theta_cap, (slip, wheel, terrain, distribution, running, terms)),
    )
    s = _implicit_root(jax.lax.stop_gradient(s), *root, entry=entry, forces=forces)
    theta0, w, r, t, m, fy, mz = _root_outputs(s, *root, entry=entry, forces=forces)
    balanced = jnp.abs(w / target - 1) <= 10 * tol  # 1e-8 in float64
    status = jnp.where(
        over,
        jnp.where(reaches_base, Status.BOTTOMED_OUT, Status.ENTRY_ANGLE_LIMIT),
        jnp.where(balanced, Status.CONVERGED, Status.NOT_CONVERGED),
    )
    return theta0, r, t, m, fy, mz, status.astype(jnp.int32)


def _safe_inputs(valid, wheel, terrain, distribution, terms, load, slip):
    """Replace invalid elements by valid reference values so their (discarded) solve is finite."""
    pick = lambda x, ref: jnp.where(valid, x, jnp.asarray(ref, x.dtype))  # noqa: E731
    wheel = jax.tree_util.tree_map(pick, wheel, type(wheel).reference())
    terrain = jax.tree_util.tree_map(pick, terrain, type(terrain).stand_in(terrain))
    distribution = jax.tree_util.tree_map(pick, distribution, type(distribution).reference())
    terms = tuple(jax.tree_util.tree_map(pick, t, type(t).reference(t)) for t in terms)
    return wheel, terrain, distribution, terms, pick(load, 5000.0), pick(slip, 0.2)


def _in_chunks(fn, args, size):
    """`fn(args)` on 1-D leaves of length `size`, as `lax.map` over fixed-size chunks
    (`batchwide.CHUNK_SIZE` elements on a CPU: one Newton iteration each)."""
    chunk = _chunk_size()
    if size <= chunk:
        return fn(args)
    n_chunks = -(-size // chunk)
    pad = n_chunks * chunk - size

    def split(x):
        # Pad by repeating the last element (a valid input), then cut into chunks.
        x = jnp.concatenate([x, jnp.broadcast_to(x[-1:], (pad,))]) if pad else x
        return x.reshape(n_chunks, chunk)

    out = jax.lax.map(fn, jax.tree_util.tree_map(split, args))
    return jax.tree_util.tree_map(lambda x: x.reshape(-1)[:size], out)


def _solves_as_rim(wheel, rim, terrain, distribution, running, rule_type) -> bool:
    """Whether a batch of `wheel` may be solved with `rim`, its `round_rim`, where every
    tread stays round (static): only a wheel with a rim other than itself (a
    `DeflectingTire`), on a law without a base whose pressure rises, where the rim's cap
    on the entry angle is the wheel's, and where the rim takes the same contact rule
    (the same nodes and options)."""
    if rim is wheel or terrain.has_base() or not terrain.pressure_rises():
        return False
    return type(_contact_rule(terrain, distribution, rim, running)) is rule_type


# How much deeper than the rim's power-law start (in sinkage) a batch's treads must stay
# round for `_round_first` to try the rim.
ROUND_MARGIN = 1.5


def _round_first(ops, rim, solve):
    """`solve(ops)` of a flat batch of wheels whose treads may stay round, by
    `solve((rim, *ops[1:]))` where every element's does at its root.

    A tyre far stiffer than the ground runs as its rim (`stays_round`: deflection <=
    1e-12 of the sinkage), yet its contact carries a flat of zero length, whose panel
    and law costs every W (the 100 kPa thesis tyre on Bekker's snow: 1.23 us against
    the rim's 0.59 us per W).  Where every element's tread stays round ROUND_MARGIN
    times deeper than the rim's power-law start (`start._power_law_root`, no
    quadrature), the batch is solved with the rim; where every root of that solve keeps
    its tread round (on a law that rises, the deflection grows with the entry angle),
    those are the outputs; otherwise, and where the start already says a tread
    flattens, the batch is solved with the wheel.  `lax.cond`s on `_all_in_batch`
    predicates: a chunk, or a vmapped batch, chooses once.
    """
    wheel, terrain, distribution, load, slip = ops[:5]
    kind = type(wheel)
    theta_cap = _entry_angle_cap(kind.deepest_reach(wheel, terrain), wheel.diameter)[0]
    estimate = _power_law_root(rim, terrain, load, theta_cap, distribution, slip)[0]
    depth = ROUND_MARGIN * jnp.sin(estimate / 2) ** 2  # per D
    deeper = jnp.minimum(_half_angle_arc(jnp.minimum(depth, 1.0)), theta_cap)
    stopped = jax.lax.stop_gradient((wheel, terrain))
    likely = _all_in_batch(kind.stays_round(stopped[0], deeper, stopped[1]))
    # Not tried: `_solve_layout`'s outputs (theta0, R, T, M, F_y, M_z, status) as zeros.
    untried = (*(jnp.zeros_like(load) for _ in range(6)), jnp.zeros(load.shape, jnp.int32))
    rim_out = jax.lax.cond(likely, lambda: solve((rim, *ops[1:])), lambda: untried)
    root = jax.lax.stop_gradient(rim_out[0])
    rounded = likely & _all_in_batch(kind.stays_round(stopped[0], root, stopped[1]))
    return jax.lax.cond(rounded, lambda: rim_out, lambda: solve(ops))


@eqx.filter_jit
def _solve_jit(wheel, terrain, distribution, terms, load, slip, guess, running, options, layout):
    """The solve of `solve_wheel` (checked inputs of any shape): `WheelState`.

    `running` is `Straight()` or a `SlipAngle` (`running.py`); `options` = (shear law,
    nodes, max_steps, the contact rule's class, the accuracy), static; `layout` "driving",
    "braking" or "auto" (`_with_rule_for`).
    """
    shear, n, max_steps, rule_type, accuracy = options
    rule = rule_type()
    trees = (wheel, terrain, distribution, terms, load, slip, guess, running)
    shape, dtype, trees = _broadcast_leaves(*trees)
    wheel, terrain, distribution, terms, load, slip, guess, running = trees
    valid = _valid_mask(wheel, terrain, distribution, load, slip, shear)
    small, large = _magnitude_window(dtype)
    for name, value, ok, _ in type(running).rules(running) + _term_rules(terms):
        valid &= jnp.isfinite(value) & ok & _fits(value, name, small, large)
    wheel, terrain, distribution, terms, load, slip = _safe_inputs(
        valid, wheel, terrain, distribution, terms, load, slip
    )
    slip = rule.prepare_slip(slip)
    running = type(running).safe(running, valid)

    def solve_with(ops):  # ops[0]: the wheel, or its round rim
        def layout_solve(braking):
            return _solve_layout(
                *ops, options=(shear, n[braking], max_steps, rule, accuracy), braking=braking
            )

        return _with_rule_for(ops[4], shear, layout_solve, layout)

    def solve(ops):
        rim = type(ops[0]).round_rim(ops[0])
        if _solves_as_rim(ops[0], rim, ops[1], ops[2], ops[6], rule_type):
            return _round_first(ops, rim, solve_with)
        return solve_with(ops)

    theta0, r, t, m, fy, mz, status = _in_chunks(
        solve, (wheel, terrain, distribution, load, slip, guess, running, terms), load.shape[0]
    )
    nan = jnp.asarray(jnp.nan, dtype)
    out = lambda x: jnp.where(valid, x, nan).reshape(shape)  # noqa: E731
    return WheelState(
        entry_angle=out(theta0),
        sinkage=out(type(wheel).contact_sinkage(wheel, theta0, terrain)),
        motion_resistance=out(r),
        thrust=out(t),
        drawbar_pull=out(t - r),
        torque=out(m),
        lateral_force=out(fy),
        aligning_torque=out(mz),
        status=jnp.where(valid, status, Status.INVALID_INPUT).astype(jnp.int32).reshape(shape),
    )


@_takes_model(positional=4)
def solve_wheel(
    wheel: AbstractWheel,
    terrain: Terrain | ContactModel,
    load: Float[ArrayLike, "..."],
    slip: Float[ArrayLike, "..."],
    *,
    slip_angle: Float[ArrayLike, "..."] | None = None,
    max_steps: int = 64,
    initial_entry_angle: Float[ArrayLike, "..."] | None = None,
    throw: bool = False,
) -> WheelState:
    """Sinkage-versus-slip equilibrium of a rigid wheel on snow or soil, eq. (4.14).

    Finds the entry angle theta0 with `W(theta0) = load`, W the vertical resultant of
    the normal stress (the terrain's pressure–sinkage law at the rim sinkage) and the
    shear stress (`shear` model), then evaluates sinkage (4.15), motion resistance
    (4.16), thrust (2.9), drawbar pull (2.10) and torque (2.12) there.  Without a
    `distribution` the stresses act on the front contact 0 <= theta <= theta0 (the
    thesis's model); with `WongReece` on theta_r <= theta <= theta0.

    `load`, `slip` and every leaf of `wheel`, `terrain` and `distribution` broadcast
    against each other with NumPy rules; every field of the result has the broadcast
    shape.  One call therefore sweeps slips x loads x parameter sets.  Works under
    `jax.jit`, `jax.vmap` and `jax.grad`; gradients w.r.t. every leaf, the load and the
    slip come from the implicit function theorem (second derivatives too: the rule at
    the root is itself differentiable).

    **Arguments:**

    - `wheel`: `RigidWheel(diameter [m], width [m])`, or `DeflectingTire(diameter,
      width, section_height [m], inflation_pressure, carcass_pressure [Pa])`, a tyre
      whose tread flattens where the ground would press harder than it can carry
      (every terrain, distribution and slip angle; not `shear="simplified"`); then
      `sinkage` is that of its flat.  On a law without a base whose pressure rises, a
      batch whose every tread stays round at its root (`stays_round`) is solved as the
      tyre's `round_rim`, whose outputs agree within rounding.
    - `terrain`: any `snowjax.Terrain`: `WongSnow(p_w [Pa], z_w [m], cohesion [Pa],
      tan_phi [-], shear_modulus [m])`, `BekkerSoil(n [-], k_c [N/m^(n+1)],
      k_phi [N/m^(n+2)], cohesion [Pa], tan_phi [-], shear_modulus=[m])`,
      `ReeceSoil(n, k_c_prime [-], k_phi_prime [-], unit_weight [N/m^3], cohesion [Pa],
      tan_phi, shear_modulus=[m])` or `LayeredSnow(top, bottom, ice_failure_pressure [Pa])`;
      or a `ContactModel(terrain, distribution, shear, lateral, nodes_per_panel, terms,
      accuracy)` (a bare terrain is `ContactModel(terrain)`: the front region,
      Janosi–Hanamoto shear, the reference quadrature, no terms of your own):
      - `shear`: the shear law, a module or its name: `JanosiHanamoto()` / `"classic"`
        (4.11), `ThesisSimplified()` / `"simplified"` (the thesis's model, 4.13;
        `WongSnow` on the front region only) or `NoShear()` / `"none"` (normal stress
        only).
      - `distribution`: `FrontRegion()` or None (the thesis's front region),
        `WongReece(c1, c2, c3)`, or any `AbstractStressDistribution`.
      - `lateral`: `Lateral(shear_modulus=K_y [m] or None, unit_weight [N/m^3],
        bulldozing=False)`; default `Lateral()`: K_y = the terrain's modulus, no
        sidewall bulldozing.  Used only with a `slip_angle`.
      - `nodes_per_panel`: Gauss–Legendre nodes per quadrature panel.  `WongSnow`
        without a distribution: two panels when all slips are >= 0, four with braking;
        defaults classic 10 + 10 (two panels) and 10 + 10 + 10 + 8 (four), simplified
        24 + 24 and 4 x 16, none 8 + 8.  Other terrains / Wong–Reece: 12 nodes per
        half-panel, 16 when the batch brakes; a driven rim on a law without a base or
        breakpoints (and a driven tyre's arc beyond its flat there), and on Wong snow
        with Wong–Reece a driven rim whose theta_m is at least a quarter of theta0
        (every element of the batch), is one panel graded towards its entry, of
        ceil(5 n / 3) nodes for n per half-panel (20 by default); a driven contact
        under Wong–Reece cut inside (a tyre's flat, layered snow's ice) takes n nodes
        on each piece and ceil(5 n / 3) on the piece at the entry.  With the defaults
        every contact integral is within 1e-7 (relative) of adaptive quadrature over
        the documented range.  An integer sets all.
      - `accuracy`: `"reference"` (the defaults above) or `"simulator"` (6 nodes per
        panel of Wong snow's front-region rule, 8 per half-panel of the others, and a
        solver tolerance of 1e-6 instead of 1e-9: errors up to ~3e-4 of the load over
        random cases, ~1e-8 typically, for vehicle simulations and RL; measured in the
        performance guide).
    - `load`: vertical wheel load F_z [N], > 0.
    - `slip`: driving slip i [-] in [-1, 1] (eq. 2.6: 0 free rolling, 1 spinning in
      place).  Negative slip is braking: the shear displacement, and with it the shear
      stress, thrust and torque, change sign (the Janosi–Hanamoto factor is mirrored,
      `-(1 - exp(-|j|/K))`), so a braked wheel gets a negative thrust.
    - `slip_angle`: beta [rad], |beta| < pi/2, broadcasts like `slip`: the angle between
      the wheel's heading and its direction of travel, positive when the wheel moves
      towards -y of its own frame (velocity (V cos beta, -V sin beta); x along the heading,
      y along the axle, z up).  The slip is then the driving slip of the heading's
      component, `i = 1 - V cos(beta) / (omega r)`.  The shear stress becomes the
      combined law of `snowjax.Lateral` (the resultant of the rim and axle shear
      displacements mobilises Janosi–Hanamoto, capped by Mohr–Coulomb; see its
      docstring for the formulation and sources), which also changes the sinkage and
      the longitudinal forces, and `lateral_force` / `aligning_torque` are filled in.
      `None` (default) is straight running: the straight-running solver paths, with
      `lateral_force = aligning_torque = 0`; so is a concrete all-zero `slip_angle`.  A
      traced or non-zero `slip_angle` takes the any-terrain quadrature (also for
      `WongSnow` without a distribution), which at beta = 0 agrees with the straight
      results within its accuracy (1e-7); `shear="simplified"` is refused with it.
    - `max_steps`: Newton iteration limit.
    - `initial_entry_angle`: optional warm start theta0 [rad] (broadcasts like `load`),
      e.g. the previous time step's `entry_angle` inside a simulation; it replaces the
      initial guess (and, for other terrains, W at the start's entry angles).  Non-finite or
      non-positive values fall back to half the largest admissible entry angle.  It
      carries no gradient.  For a `LayeredSnow` whose W(theta0) is not monotone, a warm
      start continues from the previous root instead of taking the shallowest one.
    - `throw`: False (default): every element reports its outcome in `status` and the
      rest of the batch is solved normally.  True: if any element ends
      `INVALID_INPUT`, `NOT_CONVERGED` or `ENTRY_ANGLE_LIMIT`, raise an error carrying
      that status's `Status.message` (of the first such element, in C order; eagerly
      and under `jax.jit`, as `equinox.EquinoxRuntimeError`).  `BOTTOMED_OUT` is an
      equilibrium and does not raise.

    **Returns:** `WheelState`.

    **Errors and status.**  With concrete inputs, a non-finite or out-of-range value
    raises `ValueError` naming it (`load`, `slip`, `wheel.width`, `snow.p_w`,
    `terrain.n`, `terrain.k_c / b + k_phi`, `snow.bottom.z_w`,
    `distribution.c1 + c2 * slip`, ...); a wrong type raises `TypeError` (lists and
    Python scalars are accepted; None, strings, booleans and complex numbers are not),
    shapes that do not broadcast raise `ValueError` naming them, and an empty batch
    returns empty fields.  A value whose fourth power over- or underflows the working
    precision (magnitudes above 1.1e77 or below 1.2e-77 in float64, 1.4e9 / 1.1e-10 in
    float32; 0 is allowed) is invalid; on `WongSnow` without a distribution a slip below
    that lower limit counts as 0.
    A refused terrain / distribution / shear combination raises
    `ValueError`.  Under `jax.jit`/`jax.vmap` invalid elements get `Status.INVALID_INPUT`
    and NaN fields instead, and the rest of the batch is solved normally.  A load beyond
    the capacity of a snow layer gives `Status.BOTTOMED_OUT` with `sinkage = depth`; one
    needing theta0 > 85 degrees (always possible on an infinitely deep terrain)
    `Status.ENTRY_ANGLE_LIMIT`, with the forces at 85 degrees; never NaN.

    **Documented range** (tested), `WongSnow` front region: p_w 5-200 kPa, z_w 5-35 cm
    and below 0.45 D, cohesion 0.1-20 kPa, tan phi 0.02-0.8, shear modulus 2-80 mm,
    diameter 0.5-1.5 m, width 0.1-0.6 m, load 0.1-20 kN, slip -0.5 to 0.99.  Other
    terrains and Wong–Reece: see the README section "Every terrain law, two stress
    distributions".
    """
    model = _as_model(terrain)
    terrain, shear, distribution = model.terrain, model.shear, model.distribution
    lateral, terms = model.lateral, model.terms
    if not isinstance(throw, bool):
        raise TypeError(f"throw must be True or False, got {throw!r}")
    _check_model(wheel, model)
    _check_options(max_steps)
    load = _numeric_argument("load", load)
    slip = _numeric_argument("slip", slip)
    if initial_entry_angle is not None:
        initial_entry_angle = _numeric_argument("initial_entry_angle", initial_entry_angle)
    running: AbstractRunning = _STRAIGHT
    if slip_angle is not None:
        slip_angle = _numeric_argument("slip_angle", slip_angle)
        x64 = bool(jax.config.read("jax_enable_x64"))
        lateral = _default_lateral(x64) if lateral is None else lateral
        running = SlipAngle(slip_angle, lateral)
        if not _is_traced(slip_angle) and np.all(np.asarray(slip_angle) == 0):
            # Straight running: the solver paths without a slip angle, at the broadcast shape.
            shape = _broadcast_shape(
                wheel, terrain, distribution, load, slip, initial_entry_angle, running, terms
            )
            broadcast = np.broadcast_to if not _is_traced(load) else jnp.broadcast_to
            load = broadcast(load, shape)
            running = _STRAIGHT
    if not (running.straight or shear.lateral):
        raise ValueError(
            f"shear={shear.name!r} ({type(shear).__name__}) has no lateral counterpart: "
            "use ContactModel(terrain, shear='classic') (or 'none') with a slip_angle."
        )
    shape = _broadcast_shape(
        wheel, terrain, distribution, load, slip, initial_entry_angle, running, terms
    )
    if math.prod(shape) == 0:  # an empty batch: empty results, nothing to solve
        dtype = jnp.result_type(*jax.tree_util.tree_leaves((wheel, terrain, load, slip)), float)
        empty = jnp.zeros(shape, dtype)
        return WheelState(
            empty, empty, empty, empty, empty, empty, empty, empty, jnp.zeros(shape, jnp.int32)
        )
    dtype = _validate_eagerly(wheel, terrain, distribution, load, slip, shear)
    if isinstance(running, SlipAngle):  # the slip angle; its lateral law once per object
        angle = slip_angle if _is_traced(slip_angle) else np.asarray(slip_angle)
        _check_rules(_angle_rules(angle), dtype, *_magnitude_window(dtype))
    lateral = running.lateral if isinstance(running, SlipAngle) else None
    _check_lateral_and_terms(lateral, terms, dtype)
    rule = _contact_rule(terrain, distribution, wheel, running)
    # Unbound calls: an equinox bound method costs ~40 us to create, and this runs on
    # every eager call.  The rule travels as its class: a module among the arguments
    # costs the compiled function's dispatch ~5 us per call (flattened and hashed).
    nodes = type(rule).nodes(rule, shear, model.nodes_per_panel, model.accuracy)
    options = (shear, nodes, int(max_steps), type(rule), model.accuracy)
    layout = _layout(slip, warm_start=rule.warm_layout and initial_entry_angle is not None)
    state = _solve_jit(
        wheel,
        terrain,
        distribution,
        terms,
        load,
        slip,
        initial_entry_angle,
        running,
        options,
        layout,
    )
    return _throw_on_failure(state) if throw else state
