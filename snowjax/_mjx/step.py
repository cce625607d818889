# pyright: reportAttributeAccessIssue=false
# (mujoco is a C extension without type stubs: pyright cannot see its attributes.)
"""`snowjax.mjx.step` and `rollout`: one MJX time step with the snow's forces on the
wheels, and a scan of it (the module documentation of `snowjax.mjx` explains the model)."""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

from .._sim.planar import _steered_model
from .._sim.vehicle import (
    DEFAULT_SPEED_EPS,
    _check_concrete,
    _check_dynamic_shear,
    _check_parameters,
    _frame_forces,
)
from .._terrain.base import Terrain
from .._terrain.rut import Rut
from .._terrain.rut_map import RutMap
from .._wheel.batchwide import _vmapped_in_chunks
from .._wheel.equilibrium import Status, _check_model
from .._wheel.model import ContactModel, _takes_model, _with_terrain
from .._wheel.passes import (
    Ruts,
    _follower_overlap,
    _left_behind,
    _levels,
    _lookahead,
    _resolved,
)
from .wheels import MjxWheels, _ground, mjx

__all__ = ["MjxWheelForces", "Rollout", "step", "rollout"]

# The wheel equilibrium's Newton iteration limit (`solve_wheel`'s `max_steps`), as in
# `snowjax.wheel_forces`: warm-started from the last step it takes two or three.
_WHEEL_MAX_STEPS = 64


class MjxWheelForces(eqx.Module):
    """What `step` computed for each wheel (leading axis: wheels, in `MjxWheels` order).

    - `load`: vertical load used [N] (ground normal force of the previous step, or
      `load=`).
    - `speed`: the wheel centre's speed along its heading (axle x ground normal) [m/s];
      `lateral_speed`: along the axle's projection on the ground (positive to the
      wheel's left) [m/s]; `slip_angle`: beta of `snowjax.planar_wheel_kinematics` [rad].
    - `wheel_speed`: spin about the axle, world frame [rad/s].
    - `slip`: slip i (eq. 2.6) [-]; `sinkage`: z0 (4.15) [m], below the surface the
      wheel runs on (in a rut: below the rut's floor); `entry_angle`: theta0 [rad] (pass
      it back).
    - `rut_depth`: the depth z_u of the rut the wheel runs in [m] (its `Rut`'s
      `rut_sinkage`: `Ruts`' overlap times the leader's `depth`, or `RutMap.read`), 0 on
      virgin snow.
    - `depth`: the rut's state the wheel leaves behind [m]: its lowest point below the
      original surface (`sinkage` plus its rut's floor depth), or `rut_depth` where that
      is deeper; what it marks on a rut map (`drive_path`'s and `multi_pass`'s
      `sinkage`).  `sinkage` on virgin snow.
    - `longitudinal_force`: drawbar pull (2.10) applied along the heading [N];
      `lateral_force`: applied along the axle's ground projection [N];
      `resisting_torque`: M_w (2.12) applied against the spin [N m]; `aligning_torque`:
      M_z applied about the ground normal [N m] (all after the lift-off and rest
      regularisations).
    - `spin_damping`: c, the spin's damping used implicitly: dM_w/domega, plus near rest
      the damping added to keep the step well posed (`snowjax.mjx`'s stiff wheel forces);
      never below -I / (2 dt) (I: the wheel's least moment of inertia) [N m s/rad].
    - `normal`: the ground's unit normal under the wheel (world frame) [-], shape (n, 3).
    - `status`: `Status` of each equilibrium (int32).
    """

    load: Float[Array, "... n"]
    speed: Float[Array, "... n"]
    lateral_speed: Float[Array, "... n"]
    slip_angle: Float[Array, "... n"]
    wheel_speed: Float[Array, "... n"]
    slip: Float[Array, "... n"]
    sinkage: Float[Array, "... n"]
    rut_depth: Float[Array, "... n"]
    depth: Float[Array, "... n"]
    entry_angle: Float[Array, "... n"]
    longitudinal_force: Float[Array, "... n"]
    lateral_force: Float[Array, "... n"]
    resisting_torque: Float[Array, "... n"]
    aligning_torque: Float[Array, "... n"]
    spin_damping: Float[Array, "... n"]
    normal: Float[Array, "... n 3"]
    status: Int[Array, "... n"]


def _wheel_frames(m, d, wheels, normal):
    """Each wheel's frame and velocities: (v_x, v_y, omega, heading, lateral, axle,
    centre velocity), from MJX's positions and velocities (public `mjx.Data` fields)."""
    b = np.asarray(wheels.body_ids)
    root = np.asarray(m.body_rootid)[b]
    axle = jnp.einsum("nij,nj->ni", d.xmat[b], jnp.asarray(wheels.axes, d.qpos.dtype))
    heading = jnp.cross(axle, normal)
    heading = heading / jnp.linalg.norm(heading, axis=-1, keepdims=True)
    lateral = jnp.cross(normal, heading)  # on the ground, towards the wheel's left
    cvel = d.cvel[b]  # (angular, linear at the root's subtree centre of mass)
    velocity = cvel[:, 3:] + jnp.cross(cvel[:, :3], d.xipos[b] - d.subtree_com[root])
    vx = jnp.sum(velocity * heading, -1)
    vy = jnp.sum(velocity * lateral, -1)
    spin = jnp.sum(cvel[:, :3] * axle, -1)
    return vx, vy, spin, heading, lateral, axle, velocity


class _WheelPlane(eqx.Module):
    """The wheels seen from above: what the rut models need of them, on the world's
    (x, y) plane (z up).  Called with `Ruts.follows` it gives each wheel's overlap with
    its leader's rut (`Ruts._overlap`); `read` gives the rut ahead of it on a map.

    `position` [m] and `velocity` [m/s] of the wheel centres (n, 2); `yaw_rate` [rad/s]:
    each wheel body's angular velocity about z less its spin's share; `travel` [rad]:
    the angle (from x towards y) of the heading's projection, turned by pi where the
    wheel moves backwards (v_x < 0); `width` b [m] (n,)."""

    position: Float[Array, "n 2"]
    velocity: Float[Array, "n 2"]
    yaw_rate: Float[Array, " n"]
    travel: Float[Array, " n"]
    width: Float[Array, " n"]

    def __call__(self, follows) -> Array:
        lead = np.maximum(np.asarray(follows), 0)
        return _follower_overlap(
            self.position, self.velocity, self.yaw_rate[lead], self.width, follows
        )

    def read(self, rut_map: RutMap, lookahead) -> Array:
        """The rut depth [m] each wheel is about to enter (`RutMap.read`, `lookahead`
        [m] ahead of its centre along its direction of travel)."""
        return rut_map.read(self.position, self.travel, self.width, lookahead)


def _wheel_plane(d, wheels, vx, spin, heading, axle, velocity):
    b = np.asarray(wheels.body_ids)
    ahead = jnp.arctan2(heading[:, 1], heading[:, 0])
    return _WheelPlane(
        position=d.xipos[b][:, :2],
        velocity=velocity[:, :2],
        yaw_rate=d.cvel[b][:, 2] - spin * axle[:, 2],
        travel=jnp.where(vx < 0, ahead + jnp.pi, ahead),
        width=jnp.broadcast_to(jnp.asarray(wheels.wheel.width, vx.dtype), vx.shape),
    )


class _ReadRuts(eqx.Module):
    """The wheels on the ruts read from a `RutMap` (`_MapGround`): each on the `Rut` of
    the depth it `seen` [m], with the map's k_0 [Pa/m] and a_u [Pa/m^2]."""

    k_0: Float[ArrayLike, ""]
    a_u: Float[ArrayLike, ""]

    def _rut(self, terrain, width, seen) -> Rut:
        return Rut(terrain, seen, width, self.k_0, self.a_u)

    def _solve(self, contact, width, seen, solve):
        rut = self._rut(contact.terrain, width, seen)
        return solve(_with_terrain(contact, rut), lambda x: x)[0]


class _MapGround(eqx.Module):
    """The ground of `step(ruts=RutMap)`: every wheel on the `Rut` its `RutMap` holds
    ahead of it (the `_VirginGround` / `Ruts` interface of `snowjax._wheel.passes`, with
    the overlap slot carrying the depth read, `rut_depth`).  Nothing depends on another
    wheel within a step, so every wheel is a leader for the slopes (`layout`)."""

    rut_map: RutMap
    lookahead: Float[ArrayLike, ""]

    def layout(self, num_wheels: int) -> tuple[int, ...]:
        return (-1,) * num_wheels

    def _overlap(self, plane: _WheelPlane) -> Array:
        return plane.read(self.rut_map, self.lookahead)

    def _solving(self) -> _ReadRuts:
        """What `_solve` needs (not the map, which chunks of a vmapped batch would copy)."""
        return _ReadRuts(self.rut_map.k_0, self.rut_map.a_u)

    def _solve(self, contact, width, seen, solve):
        return self._solving()._solve(contact, width, seen, solve)

    def _depths(self, terrain, width, seen, sinkage):
        rut = self._solving()._rut(terrain, width, seen)
        return seen, _left_behind(sinkage, rut, seen)

    def mark(self, plane: _WheelPlane, dt, depth) -> RutMap:
        """The map after each wheel swept from `position - velocity dt` to `position`
        at `depth` [m] (`RutMap.mark`)."""
        start = plane.position - plane.velocity * dt
        return self.rut_map.mark(start, plane.position, plane.width, depth)


def _forces_and_slopes(wheel, contact, load, u0, guess, ground, overlap, basis, *, speed_eps):
    """(jac, `_FrameForces`) of wheels at u0 = (v_x, v_y, omega) (3, n): their forces
    (drawbar pull, lateral force, -M_w, M_z) and those forces' tangents (jac, one per
    row of `basis`, (rows, 4, n)); `ground` with what its `_solve` needs
    (`_solving`)."""

    def forces(u):
        f = _frame_forces(
            wheel, contact, load, u[0], u[1], u[2], speed_eps, guess, _WHEEL_MAX_STEPS,
            ground, overlap,
        )  # fmt: skip
        out = (f.drawbar_pull, f.lateral_force, -f.resisting_torque, f.aligning_torque)
        return jnp.stack(out), f

    # One linearisation (the equilibrium solves run once), its tangents one after the
    # other: a vmap of the JVP over the tangents ran them at once, on arrays of
    # (tangents, wheels, nodes) (the rover in MJX, 1,024 environments, 2 cores, two
    # interleaved runs: the step with snow 37.9-40.5 -> 35.9-36.3 ms, at the simulator
    # accuracy 33.3-37.6 -> 33.1-33.9 ms, the same rollouts; compile 34-36 -> 29-31 s).
    _, linear, f = jax.linearize(forces, u0, has_aux=True)
    return jax.lax.map(linear, basis), f


def _snow_forces(m, d, wheels, contact, entry_angle, load, speed_eps, ground):
    """(world wrenches (n, 6), damping blocks D (n, 4, 3), frame rows (n, 4, 3), the
    wheels from above (`_WheelPlane`), MjxWheelForces) of the snow on every wheel at
    MJX's current state, on `ground` (`_VirginGround`, `Ruts` or `_MapGround`)."""
    dtype = d.qpos.dtype
    gravity = jnp.asarray(m.opt.gravity, dtype)
    up = -gravity / jnp.linalg.norm(gravity)
    contact_load, normal = _ground(d, wheels, up)
    if isinstance(load, str):  # "contact": the ground's normal force of the last step
        load = contact_load
    vx, vy, spin, heading, lateral, axle, velocity = _wheel_frames(m, d, wheels, normal)
    plane = _wheel_plane(d, wheels, vx, spin, heading, axle, velocity)
    load = jnp.broadcast_to(jnp.asarray(load, dtype), vx.shape)
    min_load = wheels.min_load.astype(dtype)
    # A traced prescribed load that is negative or not finite: no force, INVALID_INPUT.
    valid_load = jnp.isfinite(load) & (load >= 0)
    load = jnp.where(valid_load, load, 0.0)
    airborne = jnp.clip(load / min_load, 0.0, 1.0)  # lift-off: forces fade to 0
    solve_load = jnp.maximum(load, min_load)
    n = wheels.num_wheels
    follows = ground.layout(n)
    overlap = ground._overlap(plane)  # (the rut each wheel sees: fixed in the slopes)

    # Each wheel's forces depend on its own (v_x, v_y, omega) and, in a rut, on its
    # leaders': three forward-mode tangents per level of wheels (leaders, their
    # followers, ...) give the 4 x 3 block of every wheel at once.  Vmapped over
    # environments, in chunks of environments (`_vmapped_in_chunks`).
    level = _levels(follows)
    masks = (level[None, :] == np.arange(level.max() + 1)[:, None]).astype(float)
    basis = np.einsum("ln,ij->lijn", masks, np.eye(3)).reshape(-1, 3, n)
    u0 = jnp.stack([vx, vy, spin])
    slopes = _vmapped_in_chunks(functools.partial(_forces_and_slopes, speed_eps=speed_eps), n)
    jac, f = slopes(
        wheels.wheel, contact, solve_load, u0, entry_angle, ground._solving(), overlap,
        jnp.asarray(basis, dtype),
    )  # fmt: skip
    # jac[3 level + j, i, k]: d(output i of wheel k) / d(input j of wheel k's level).
    jac = jac.reshape(-1, 3, 4, n)[level, :, :, np.arange(n)]  # (n, 3 inputs, 4 outputs)
    damp = -jnp.swapaxes(jac, 1, 2)  # D = -d(F_x, F_y, -M_w, M_z)/d(v_x, v_y, omega)
    b = np.asarray(wheels.body_ids)
    mass, moment = m.body_mass[b], jnp.min(m.body_inertia[b], axis=-1)
    inertia = jnp.stack([mass, mass, moment, moment], -1).astype(dtype)
    dt = jnp.asarray(m.opt.timestep, dtype)
    damp = airborne[:, None, None] * _dissipative(damp, wheels.wheel.diameter / 2, inertia, dt)
    fx, fy = airborne * f.drawbar_pull, airborne * f.lateral_force
    mw, mz = airborne * f.resisting_torque, airborne * f.aligning_torque
    force = fx[:, None] * heading + fy[:, None] * lateral
    torque = -mw[:, None] * axle + mz[:, None] * normal
    rows_out = jnp.stack([heading, lateral, axle, normal], 1)  # (n, 4, 3)
    rut_depth, depth = ground._depths(contact.terrain, wheels.wheel.width, overlap, f.sinkage)
    out = MjxWheelForces(
        load=load,
        speed=vx,
        lateral_speed=vy,
        slip_angle=f.slip_angle,
        wheel_speed=spin,
        slip=f.slip,
        sinkage=f.sinkage,
        rut_depth=rut_depth,
        depth=depth,
        entry_angle=f.entry_angle,
        longitudinal_force=fx,
        lateral_force=fy,
        resisting_torque=mw,
        aligning_torque=mz,
        spin_damping=damp[:, 2, 2],
        normal=normal,
        status=jnp.where(valid_load, f.status, Status.INVALID_INPUT).astype(jnp.int32),
    )
    return jnp.concatenate([force, torque], -1), damp, rows_out, plane, out


def _dissipative(damp, radius, inertia, dt):
    """Each wheel's 4 x 3 block D of slopes as the square 4 x 4 block (a zero column for
    the wheel's rotation about the normal, on which its forces do not depend), plus the
    least diagonal damping, per row, for which the symmetric part of D + W / (2 dt) is
    diagonally dominant (Gershgorin), so positive semi-definite.  W = `inertia` (n, 4):
    the wheel body's own (mass, mass, least principal moment, least principal moment)
    [kg, kg, kg m^2, kg m^2].  Rows and columns are measured in (v_x, v_y, r omega,
    r omega_n) [m/s] and (F_x, F_y, -M_w / r, M_z / r) [N] (`radius` r [m]), where a
    wheel's slip block is near balance (F depends on r omega - v_x).

    Why: near rest (slip jumping between -1 and 1) the slopes are large and far from
    symmetric, and the symmetric part of M + dt K went indefinite (least eigenvalue
    down to -1.3e4, from +1.5 for M alone, in random driving): MJX's implicit solve
    then amplified the forces and threw the rover at 25 m/s.  The wheels' own inertia
    is part of M (sum_k G_k^T W_k G_k <= M), so with the blocks above the symmetric part
    of M + dt (D_joint + K) is >= M / 2 and the step's accelerations stay bounded by the
    forces.  In steady driving no block needs it (unchanged there); near rest the step
    damps more, as an implicit Euler step with a stiffer slope would."""
    n = damp.shape[0]
    square = jnp.concatenate([damp, jnp.zeros((n, 4, 1), damp.dtype)], axis=2)
    one = jnp.ones((), damp.dtype)
    scale = jnp.stack([one, one, one / radius, one / radius])
    scaled = scale[None, :, None] * square * scale[None, None, :]
    sym = 0.5 * (scaled + jnp.swapaxes(scaled, 1, 2))
    diag = jnp.diagonal(sym, axis1=1, axis2=2) + inertia * scale**2 / (2 * dt)
    off = jnp.sum(jnp.abs(sym), axis=2) - jnp.abs(jnp.diagonal(sym, axis1=1, axis2=2))
    shift = jnp.maximum(off - diag, 0.0) / scale**2  # back to the wheel's units
    return square.at[:, np.arange(4), np.arange(4)].add(shift)


def _snow_damping_matrix(m, d, wheels, damp, rows):
    """K = sum_k G_k^T D_k G_k [N s/m ...], G = (heading^T J_p, lateral^T J_p, axle^T
    J_r, normal^T J_r) (4 x nv), D_k the wheel's 4 x 4 block (`_dissipative`)."""
    b = jnp.asarray(wheels.body_ids)

    def wheel_rows(body, point, r):
        jacp, jacr = mjx.jac(m, d, point, body)  # (nv, 3) each
        g = jnp.stack([jacp @ r[0], jacp @ r[1], jacr @ r[2], jacr @ r[3]])
        return g  # (4, nv)

    g = jax.vmap(wheel_rows)(b, d.xipos[np.asarray(wheels.body_ids)], rows)  # (n, 4, nv)
    return jnp.einsum("kiv,kij,kjw->vw", g, damp, g)


def _check_step_args(m, d, wheels, model, speed_eps):
    if not isinstance(m, mjx.Model):
        raise TypeError(f"m must be an mjx.Model (mjx.put_model), got {type(m).__name__}")
    if not isinstance(d, mjx.Data):
        raise TypeError(f"d must be an mjx.Data (mjx.make_data), got {type(d).__name__}")
    if not isinstance(wheels, MjxWheels):
        raise TypeError(f"wheels must be a snowjax.mjx.MjxWheels, got {type(wheels).__name__}")
    _check_dynamic_shear(model.shear, "snowjax.mjx")
    _check_model(wheels.wheel, model)
    _check_parameters(wheels.wheel, model)
    if not (np.isfinite(speed_eps) and speed_eps > 0):
        raise ValueError(f"speed_eps must be finite and > 0 m/s; got {speed_eps!r}")
    if m.opt.integrator != mjx.IntegratorType.EULER:
        raise ValueError(
            "snowjax.mjx.step needs integrator='Euler' (it adds the snow forces' slopes to"
            f" the implicit damping); the model has {m.opt.integrator!r}"
        )
    if m.opt.disableflags & mjx.DisableBit.EULERDAMP:
        raise ValueError("snowjax.mjx.step needs Euler's implicit damping (eulerdamp enabled)")
    if max(wheels.body_ids) >= m.nbody or max(a for s in wheels.sensors for a, _ in s) >= int(
        m.nsensordata
    ):
        raise ValueError("wheels do not belong to this model (body or sensor out of range)")


@_takes_model(positional=5)
def step(
    m: mjx.Model,
    d: mjx.Data,
    wheels: MjxWheels,
    snow: Terrain | ContactModel,
    entry_angle: Float[ArrayLike, " n"] | None = None,
    *,
    load: Float[ArrayLike, " n"] | str | None = None,
    speed_eps: float = DEFAULT_SPEED_EPS,
    ruts: Ruts | RutMap | None = None,
    solver_unroll: int | None = None,
) -> tuple[mjx.Data, MjxWheelForces] | tuple[mjx.Data, MjxWheelForces, RutMap]:
    """One MJX time step with the snow's forces on the wheels; pure and differentiable.

    The same pipeline as `mjx.step` (`fwd_position`, sensors, `fwd_velocity`,
    `fwd_actuation`, `fwd_acceleration`, constraint `solve`, Euler), with the wheel
    forces computed after the velocity stage (so from the current positions and
    velocities) and written into the wheel rows of `xfrc_applied` (those rows are
    overwritten; other rows are kept): in the world frame at each wheel's centre of mass
    (its axle), force `longitudinal_force * heading + lateral_force * lateral` [N] and
    torque `-resisting_torque * axle + aligning_torque * normal` [N m].  The forces'
    slopes w.r.t. the wheels' velocities enter the Euler update implicitly (module
    documentation).  Public MuJoCo API only.

    **Arguments:**

    - `m`, `d`: `mjx.Model` (Euler integrator) and `mjx.Data`.
    - `wheels`: `MjxWheels` of this model.
    - `snow`: the terrain, any `snowjax.Terrain` (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
      `LayeredSnow`; SI), or a `ContactModel`: its shear law, lateral law, stress
      distribution, nodes per panel and force terms as in `snowjax.simulate_planar`.
      Vmapping over its leaves runs one rollout per terrain.
    - `entry_angle`: warm start theta0 [rad] per wheel, the `entry_angle` output of the
      previous step (None: cold start); changes only the iteration count.
    - `load`: vertical load per wheel [N]: None (default) `wheels.static_load`, the
      quasi-static load at rest; an array (shape () or (n,)) to prescribe it; or
      `"contact"`: the ground's normal force on the wheel in the previous step (includes
      load transfer and lift-off).
    - `speed_eps`: regularisation speed at rest [m/s], > 0 (see
      `snowjax.planar_wheel_kinematics`).
    - `ruts`: None (default: every wheel on virgin snow); `snowjax.Ruts(k_0, a_u,
      follows)`: the wheels run in the ruts of the wheels ahead, `follows` in
      `MjxWheels` order (default: the last half behind the first half, as the shipped
      rover's rear wheels behind its front wheels), each seeing the rut's depth times
      its overlap with its leader's path (`snowjax.track_offset`, in the world's x-y
      plane), at the same instant (quasi-static); or a `snowjax.RutMap` over the world's
      x-y plane (z up): each wheel reads the rut a wheel radius ahead of its centre along
      its direction of travel (`RutMap.read`; behind it when it reverses), runs on that
      `Rut`, and marks the segment it swept in the step, from `p - v dt` to `p` (p, v
      its centre's horizontal position and velocity, dt the time step), with its
      `depth` (`RutMap.mark`): a following wheel meets its leader's rut after the
      leader has passed, and a vehicle its own ruts where it drives again.  The map's
      cells must be smaller than the wheel radius / sqrt(2) (a wheel would read its own
      mark).  A following wheel's `sinkage` is below its rut's floor.
    - `solver_unroll`: None (default) runs MJX's constraint solver as the model sets it
      (`opt.iterations`, a `while_loop` to `opt.tolerance`: jit, vmap and forward mode,
      not reverse mode); an int k >= 1 runs exactly k Newton (or CG) iterations of it,
      unrolled (k calls of `mjx.solve` with `opt.iterations = 1`, each warm-started from
      the last), which `jax.grad` differentiates.  On the shipped rover over 120 steps
      of 5 ms, k = 2 gave a return's derivative within 3e-7 of the converged solver's
      (and its reverse-mode gradient within 1e-8 of central differences); k = 1 let the
      chassis bounce by 4 cm and the derivatives diverge.

    **Returns:** `(next mjx.Data, MjxWheelForces)`, and with a `RutMap` for `ruts`
    `(next mjx.Data, MjxWheelForces, RutMap after the step)`; `xfrc_applied` holds the
    snow wrenches that were applied.

    **Errors:** `TypeError` for arguments of the wrong type, `ValueError` for a model
    that is not Euler-integrated, a bad `speed_eps` or `shear`, a shear model the terrain
    does not support, a concrete terrain or wheel parameter out of `solve_wheel`'s range
    (NaN included), a concrete prescribed `load` that is negative or not finite, or a
    rut map whose cells are too large for the wheel (above), or a bad `solver_unroll`.
    Under `jit`, a wheel whose prescribed load is negative or not finite gets no snow
    force and `Status.INVALID_INPUT`; a wheel whose width plus travel in a step exceeds
    the map's `reach` raises (`RutMap.mark`).
    """
    contact = _steered_model(snow, "snowjax.mjx")
    _check_step_args(m, d, wheels, contact, speed_eps)
    ground = _ground_of(wheels, ruts)
    solver_unroll = _solver_unroll(solver_unroll)
    if isinstance(load, str) and load != "contact":
        raise ValueError(f"load must be None, 'contact' or an array of loads [N]; got {load!r}")
    if not isinstance(load, str):
        _check_concrete("load", load, lambda x: x >= 0, ">= 0 N (0: the wheel is airborne)")
    if load is None:
        load = wheels.static_load
    n = wheels.num_wheels
    if entry_angle is not None:
        entry_angle = jnp.broadcast_to(jnp.asarray(entry_angle, d.qpos.dtype), (n,))

    d = mjx.fwd_position(m, d)
    d = mjx.sensor_pos(m, d)
    d = mjx.fwd_velocity(m, d)
    d = mjx.sensor_vel(m, d)
    wrench, damp, rows, plane, out = _snow_forces(
        m, d, wheels, contact, entry_angle, load, float(speed_eps), ground
    )
    b = np.asarray(wheels.body_ids)
    d = d.replace(xfrc_applied=d.xfrc_applied.at[b].set(wrench.astype(d.xfrc_applied.dtype)))
    d = mjx.fwd_actuation(m, d)
    d = mjx.fwd_acceleration(m, d)
    if solver_unroll is None:
        d = mjx.solve(m, d)
    else:  # k single iterations: no while_loop, so reverse mode works
        single = m.replace(opt=m.opt.replace(iterations=1))
        for _ in range(solver_unroll):
            d = mjx.solve(single, d)
            d = d.replace(qacc_warmstart=d.qacc)
    d = mjx.sensor_acc(m, d)
    # Linearly implicit Euler in the snow forces: (M + dt (D_joint + K)) qacc = f, then
    # MJX's own update of the state with that qacc (implicit damping switched off there).
    dt = m.opt.timestep
    mass = mjx.full_m(m, d) + dt * jnp.diag(m.dof_damping)
    mass = mass + dt * _snow_damping_matrix(m, d, wheels, damp, rows)
    qacc = _solve_dense(mass, d.qfrc_smooth + d.qfrc_constraint)
    explicit = m.replace(
        opt=m.opt.replace(disableflags=m.opt.disableflags | mjx.DisableBit.EULERDAMP)
    )
    d = mjx.euler(explicit, d.replace(qacc=qacc))
    if isinstance(ground, _MapGround):
        return d, out, ground.mark(plane, m.opt.timestep, out.depth)
    return d, out


def _solve_dense(a: Float[Array, "n n"], b: Float[Array, " n"]) -> Float[Array, " n"]:
    """x with a x = b, by Gaussian elimination with partial pivoting written in jnp
    (unrolled over the n = nv rows: 16 on the rover), not `jnp.linalg.solve`.

    Why not LAPACK: vmapped over environments, `jnp.linalg.solve` is jaxlib's batched
    LU and triangular-solve kernels, which on the CPU split a large batch over XLA's
    intra-op thread pool and block a pool thread until the pieces are done
    (`ParallelBatchMap` in jaxlib's `lapack_kernels.cc`, jaxlib 0.10.2).  The mass
    matrix is ready before MJX's constraint solver runs, so XLA may start its LU while
    the solver's batched Cholesky runs on the other thread; with both of a 2-core
    machine's pool threads blocked in such a wait, nothing runs the pieces and the step
    deadlocks (seen in the test suite: the 1,024-environment episode at 0 % CPU, `gdb`
    showing the two pool threads in `LuDecomposition` and `TriMatrixEquationSolver`).
    Elimination in jnp has no such call. Measured (`benchmarks/mjx.py --quick`, one run
    each, 2 cores): the wheel forces' share of the step at 1,024 environments 56.9 ms
    against 56.4 with LAPACK, but the first-call compile 55.9 s against 39.5 (the
    unrolled 16 x 16 elimination; a `fori_loop` over masked rows was not tried).
    """
    n = a.shape[-1]
    m = jnp.concatenate([a, b[:, None]], axis=1)  # the augmented matrix, (n, n + 1)
    rows = jnp.arange(n)
    for k in range(n):
        p = k + jnp.argmax(jnp.abs(m[k:, k]))  # the pivot row (k <= p < n)
        at_p = (rows == p).astype(m.dtype)
        row_p, row_k = at_p @ m, m[k]
        # swap rows k and p (nothing where p == k)
        m = m + jnp.outer((rows == k).astype(m.dtype) - at_p, row_p - row_k)
        m = m.at[k + 1 :].add(-jnp.outer(m[k + 1 :, k] / m[k, k], m[k]))
    x = jnp.zeros(n, m.dtype)
    for k in reversed(range(n)):
        x = x.at[k].set((m[k, n] - m[k, k + 1 : n] @ x[k + 1 :]) / m[k, k])
    return x


def _solver_unroll(solver_unroll) -> int | None:
    """`step`'s `solver_unroll`, checked: None or an int >= 1."""
    if solver_unroll is None:
        return None
    if isinstance(solver_unroll, bool) or int(solver_unroll) != solver_unroll or solver_unroll < 1:
        raise ValueError(f"solver_unroll must be None or an integer >= 1; got {solver_unroll!r}")
    return int(solver_unroll)


def _ground_of(wheels, ruts):
    """The wheels' ground (`_VirginGround`, `Ruts` or `_MapGround`) of `step`'s `ruts=`,
    checked."""
    if isinstance(ruts, RutMap):
        return _MapGround(ruts, _lookahead(wheels.wheel, ruts, None))
    return _resolved(ruts, wheels.num_wheels)


class Rollout(eqx.Module):
    """States and wheel outputs of `rollout`, one row per step (after the step).

    `time` [s], `qpos`, `qvel` (MJX's generalised coordinates and velocities, SI),
    `wheels`: `MjxWheelForces` with a leading step axis (forces of the step that
    produced the row), `data`: the final `mjx.Data`, `rut_map`: the `RutMap` after the
    last step (None unless `ruts` is a `RutMap`).
    """

    time: Float[Array, " steps"]
    qpos: Float[Array, "steps nq"]
    qvel: Float[Array, "steps nv"]
    wheels: MjxWheelForces
    data: mjx.Data
    rut_map: RutMap | None = None


@_takes_model(positional=6)
def rollout(
    m: mjx.Model,
    d: mjx.Data,
    wheels: MjxWheels,
    snow: Terrain | ContactModel,
    ctrl: Float[ArrayLike, "... nu"],
    num_steps: int,
    *,
    entry_angle: Float[ArrayLike, " n"] | None = None,
    load: Float[ArrayLike, " n"] | str | None = None,
    speed_eps: float = DEFAULT_SPEED_EPS,
    ruts: Ruts | RutMap | None = None,
) -> Rollout:
    """`num_steps` calls of `step` in one `jax.lax.scan`, the entry angles (and the rut
    map) carried along.

    **Arguments:** as `step`, plus `ctrl`: actuator controls (for the shipped rover,
    `rover_controls(steering, torque)`: steer angles [rad] and motor torques [N m]),
    shape (nu,) held constant or (num_steps, nu) per step; `num_steps`: number of steps
    (static int >= 1); `entry_angle`: initial warm start [rad]; `ruts`: as `step`'s, a
    `RutMap` being the map before the first step (`RutMap.empty`, or an earlier
    rollout's `rut_map`).  For reverse mode, scan `step(..., solver_unroll=2)`
    yourself (as `snowjax.playground.SnowRover` does).  Jit it
    yourself (e.g. `jax.jit(rollout, static_argnums=5)` or inside your own jitted
    function); vmap it over snows, states and maps (one map per environment);
    differentiate it.

    **Returns:** `Rollout`.
    """
    contact = _steered_model(snow, "snowjax.mjx")
    _check_step_args(m, d, wheels, contact, speed_eps)
    _ground_of(wheels, ruts)  # (its errors before the scan's trace)
    num_steps = int(num_steps)
    if num_steps < 1:
        raise ValueError(f"num_steps must be >= 1; got {num_steps!r}")
    ctrl = jnp.asarray(ctrl, d.qpos.dtype)
    if ctrl.shape == (m.nu,):
        ctrl = jnp.broadcast_to(ctrl, (num_steps, m.nu))
    if ctrl.shape != (num_steps, m.nu):
        raise ValueError(
            f"ctrl must have shape ({m.nu},) or ({num_steps}, {m.nu}); got {ctrl.shape}"
        )
    n = wheels.num_wheels
    if entry_angle is None:  # NaN: solve_wheel's cold start (closed-form guess)
        entry_angle = jnp.full((n,), jnp.nan, d.qpos.dtype)
    entry_angle = jnp.broadcast_to(jnp.asarray(entry_angle, d.qpos.dtype), (n,))

    def body(carry, u):
        data, theta, grid = carry
        data, out, *grid = step(
            m, data.replace(ctrl=u), wheels, contact, theta, load=load, speed_eps=speed_eps,
            ruts=ruts if grid is None else grid,
        )  # fmt: skip
        theta = jax.lax.stop_gradient(
            jnp.where(jnp.isfinite(out.entry_angle), out.entry_angle, theta)
        )
        return (data, theta, grid[0] if grid else None), (data.time, data.qpos, data.qvel, out)

    start = (d, entry_angle, ruts if isinstance(ruts, RutMap) else None)
    (data, _, grid), (time, qpos, qvel, outs) = jax.lax.scan(body, start, ctrl)
    return Rollout(time=time, qpos=qpos, qvel=qvel, wheels=outs, data=data, rut_map=grid)
