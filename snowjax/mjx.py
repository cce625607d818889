# pyright: reportAttributeAccessIssue=false
# (mujoco is a C extension without type stubs: pyright cannot see its attributes; and
# MJX's Data._impl is a union of backend types of which only the JAX one has efc_J.)
"""snowjax wheel forces inside MuJoCo MJX: `snowjax.mjx` (optional extra `snowjax[mjx]`).

Not imported by `import snowjax`; `import snowjax.mjx` needs `pip install 'snowjax[mjx]'`
(`mujoco`, `mujoco-mjx`).

**What it does.**  `step(m, d, wheels, snow, entry_angle)` advances an `mjx.Data` by one
time step like `mjx.step`, with the snow's forces on every wheel body of `wheels`
(`MjxWheels.from_model`): for each wheel it reads the axle's speed along the wheel's
heading, the wheel's spin about its axle and its vertical load from the MJX state,
evaluates `snowjax.wheel_forces` (slip of eq. 2.6, regularised at rest; the quasi-static
equilibrium 4.14 by `solve_wheel`, warm-started from the previous step's entry angles)
and writes the drawbar pull (2.10) along the heading and the resisting torque M_w (2.12)
about the axle into the wheel rows of `data.xfrc_applied`.  Pure JAX: `jax.jit`,
`jax.lax.scan`, `jax.vmap` (over snows, wheels, states) and `jax.grad`/`jax.jacfwd`
(through the whole rollout) all work.  `rollout` scans `step` over a control sequence.

**How the load and the sinkage are modelled (and why).**  The snow is soft: under the
thesis's model a wheel sinks z0 (4.15) into it, and the snow's vertical reaction W
equals the wheel load.  MJX has only rigid geometry, so the wheel's collision geom (a
sphere or cylinder of the wheel's radius) rests on a rigid floor that stands for the
*compacted bottom of the rut*; the undisturbed snow surface lies z0 above it.  The floor
contact must be frictionless (`condim="1"` on the wheel geoms and on everything they touch;
checked): MuJoCo's contact supplies only the normal force, which *is* the wheel load W,
and the snow supplies the tangential force and the resisting torque.  The load the snow
model sees is one of three (`load=` of `step`): by default each wheel's static load,
measured by `MjxWheels.from_model` at rest (the static share `m g / n` of
`snowjax.simulate_longitudinal` for a symmetric vehicle); an array to prescribe it; or
`"contact"`: MJX's own solution, the normal force of the wheel's floor contacts in the
previous step (`efc_force`, one step of lag), which includes the load transfer produced
by acceleration, pitch and the drive torques' reaction, as a real vehicle sees it.  The
forces are scaled by `min(load / min_load, 1)` (`MjxWheels.min_load`), so with
`"contact"` a wheel that leaves the floor gets no snow force and lift-off is continuous.
Why not a vertical spring on the sinkage: W(z0) of the snow is a plastic compaction
curve (it does not give the load back on unloading) and is stiff near the layer's base,
so a spring built from it would be neither the thesis's physics nor stable in an explicit
step, and the thesis's contact is quasi-static anyway: the rut depth follows the load and
slip instantly, exactly as in `simulate_longitudinal`.  What is neglected: the vertical
motion of the vehicle as the rut deepens or shallows with slip (`sinkage` is reported, not
applied to the geometry), and the few millimetres of MuJoCo's soft-contact penetration
are not sinkage.

**Stiff wheel spin.**  Near the self-propelled slip the wheel-spin equation is stiff
(time constant `I v / (r (1 - i)^2 dM_w/di)`, well below MJX's step at low speed), so an
explicit step would make the spin oscillate.  `step` therefore treats the snow torque
linearly implicitly: it computes c = dM_w/domega (forward mode through `wheel_forces`,
clipped at 0) and adds it to the wheel joints' damping *for the Euler update only*
(MuJoCo's Euler integrator treats damping implicitly), which turns
`I domega = dt (T - M_w(omega_n))` into `dt (T - M_w(omega_n) - c (omega_{n+1} - omega_n))`.
Only `integrator="Euler"` (MuJoCo's default) with implicit damping enabled is accepted.

**Gradients.**  Forward mode (`jax.jvp`, `jax.jacfwd`) works through `step` and `rollout`
with any MJX settings and is the cheap choice for a few parameters (snow, controls).
Reverse mode (`jax.grad`) works too, but MJX only allows it with `opt.iterations = 1` (its
constraint solver is a `while_loop` otherwise); the shipped model uses up to 20 Newton
iterations because with one the contact solve is too inexact for it (measured: from
rest the chassis jumps by 0.3 m), so differentiate it in forward mode. Measured against
central differences: the distance after 40 steps from rest with `load="contact"`, 2e-6
(d/dp_w) and 4e-5 (d/dtan phi) relative; from 1 m/s with `load="contact"`, 2e-7 and
1e-6; with the static loads (the default), 3e-8 and 5e-6 from rest, 3e-7 and 8e-7 from
1 m/s. (The derivative of the implicit spin update is a second derivative of the
equilibrium: its Leibniz term comes from the quadrature rule that moves with the entry
angle, `moving_rule`.) Reverse mode at `iterations = 1`: 1e-3.

**Load transfer, measured.**  With `load="contact"` the shipped vehicle driven by 540 N m
per wheel from 1 m/s carries, after 0.2 s, 2,995 N on each front and 4,004 N on each rear
wheel (the drive torques' reaction and the snow's resisting torques pitch it back), so the
front wheels slip more than the rear ones.  With the default (static load, no transfer)
all four run at the 18.3 % slip `simulate_longitudinal` gives.

**Lateral force.**  This bridge applies no lateral force: `solve_wheel`'s lateral force and
aligning torque (`slip_angle=`, `snowjax.Lateral`, used by `simulate_planar`) are not wired
in here.  `MjxWheelForces.slip_angle` is reported but nothing is applied sideways, so use
it on vehicles whose lateral motion is constrained (the shipped model is planar: x, z,
pitch) or add your own lateral force.
"""

from __future__ import annotations

import contextlib
import importlib.resources
import io
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

try:
    import mujoco

    # mujoco.mjx prints "Failed to import warp" when the optional GPU backend (NVIDIA
    # Warp) is absent; the JAX backend used here does not need it.
    with contextlib.redirect_stdout(io.StringIO()):
        from mujoco import mjx
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise ImportError(
        "snowjax.mjx needs MuJoCo MJX: pip install 'snowjax[mjx]' (mujoco, mujoco-mjx)"
    ) from exc

from ._leaves import _as_float
from ._sim.vehicle import (
    DEFAULT_SPEED_EPS,
    _check_concrete,
    _check_dynamic_shear,
    _check_parameters,
    wheel_forces,
)
from ._terrain.base import Terrain
from ._wheel.contact import ShearModel
from ._wheel.distribution import AbstractStressDistribution
from ._wheel.equilibrium import Status, _check_model
from ._wheel.geometry import AbstractWheel, RigidWheel
from ._wheel.model import ContactModel, _unpack_model
from ._wheel.passes import Ruts, _follower_overlap, _in_tracks, _levels, _resolved
from ._wheel.shear_law import AbstractShearLaw, _shear_name

__all__ = [
    "MjxWheels",
    "MjxWheelForces",
    "Rollout",
    "step",
    "rollout",
    "vehicle_model_path",
    "load_vehicle",
]


def vehicle_model_path() -> str:
    """Path of the shipped MJCF model `snowjax/data/mjx_vehicle.xml`: a planar 4-wheel
    vehicle (1,327.6 kg chassis and four 25 kg thesis tyres, D = 0.736 m, b = 0.235 m,
    I = 1.5 kg m^2; 3,500 N per wheel at rest; wheelbase 2.6 m, track 1.6 m; motors
    `motor_fl/fr/rl/rr`, ctrl = torque [N m]) on a flat floor, g = 9.80665 m/s^2."""
    return str(importlib.resources.files("snowjax") / "data" / "mjx_vehicle.xml")


WHEEL_BODIES = ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")


def load_vehicle() -> tuple[mujoco.MjModel, "MjxWheels"]:
    """The shipped vehicle: `(mujoco.MjModel, MjxWheels)` with the thesis tyre on its four
    wheels.  `mjx.put_model(model)` gives the MJX model."""
    model = mujoco.MjModel.from_xml_path(vehicle_model_path())
    return model, MjxWheels.from_model(model, WHEEL_BODIES, RigidWheel.thesis_tire())


# ---------------------------------------------------------------------------------------
# Which bodies are wheels
# ---------------------------------------------------------------------------------------


class MjxWheels(eqx.Module):
    """Which bodies of an MJX model are wheels on snow, and their geometry.

    Build it with `MjxWheels.from_model` (checks the model).  **Fields:**

    - `wheel`: `RigidWheel` (diameter D, width b [m]) or another `snowjax.AbstractWheel`
      (`DeflectingTire`); leaves scalar or of shape (n,).
    - `static_load`: each wheel's load at rest [N], the default load of `step`
      (measured by `from_model`: MuJoCo settles the model at rest, zero controls, and
      sums the floor's normal force on each wheel's geoms).
    - `min_load`: with `load="contact"`, the load below which the snow forces fade
      linearly to 0 (lift-off) [N].
    - `body_ids`: the n wheel bodies (static).
    - `dof_ids`: each wheel's spin dof (the hinge joint of the body; static).
    - `axes`: spin axis of each wheel in its body frame (unit vectors; static).  Positive
      spin about the axis rolls the wheel along `axis x up` (up = against gravity).
    - `geom_ids`: each wheel's collision geoms, whose floor contacts carry its load
      (static; condim 1).
    """

    wheel: AbstractWheel
    static_load: Float[Array, " n"] = eqx.field(converter=_as_float)
    min_load: Float[Array, ""] = eqx.field(converter=_as_float)
    body_ids: tuple[int, ...] = eqx.field(static=True)
    dof_ids: tuple[int, ...] = eqx.field(static=True)
    axes: tuple[tuple[float, float, float], ...] = eqx.field(static=True)
    geom_ids: tuple[tuple[int, ...], ...] = eqx.field(static=True)

    @property
    def num_wheels(self) -> int:
        return len(self.body_ids)

    @classmethod
    def from_model(
        cls,
        model: mujoco.MjModel,
        bodies: Sequence[str | int],
        wheel: AbstractWheel | None = None,
        *,
        axes: Sequence[Sequence[float]] | None = None,
        min_load: float = 100.0,
        radius_rtol: float = 1e-3,
        settle_time: float = 2.0,
    ) -> "MjxWheels":
        """Describe the wheels of `model` (a `mujoco.MjModel`, before `mjx.put_model`).

        **Arguments:**

        - `bodies`: wheel bodies, by name or id; each must have exactly one hinge joint
          (its spin) and at least one collision geom (`contype` or `conaffinity` != 0),
          all of them `condim="1"` and only able to touch geoms with `condim="1"`.
        - `wheel`: `RigidWheel` (D, b [m]) or `DeflectingTire`; default
          `RigidWheel.thesis_tire()`.  Sphere and cylinder collision geoms must have
          radius D/2 (within `radius_rtol`).
        - `axes`: spin axis per wheel in the body frame; default the hinge's axis.
        - `min_load`: lift-off threshold [N], > 0.
        - `settle_time`: how long MuJoCo (C, not MJX) lets the model settle at rest from
          `qpos0` with zero controls to measure `static_load` [s].

        **Raises:** `TypeError` for a model that is not a `mujoco.MjModel` or a wheel that
        is not a `snowjax.AbstractWheel`; `ValueError` naming the body or geom for an
        unknown body, a body without exactly one hinge, without collision geoms, with a frictional
        (condim > 1) contact or a radius that is not D/2.
        """
        if not isinstance(model, mujoco.MjModel):
            raise TypeError(f"model must be a mujoco.MjModel, got {type(model).__name__}")
        wheel = RigidWheel.thesis_tire() if wheel is None else wheel
        if not isinstance(wheel, AbstractWheel):
            raise TypeError(
                "wheel must be a snowjax.RigidWheel, snowjax.DeflectingTire or another "
                f"snowjax.AbstractWheel, got {type(wheel).__name__}"
            )
        if not (np.isfinite(min_load) and min_load > 0):
            raise ValueError(f"min_load must be finite and > 0 N; got {min_load!r}")
        if len(bodies) == 0:
            raise ValueError("bodies must name at least one wheel body")
        radius = np.broadcast_to(np.asarray(wheel.diameter, float) / 2, (len(bodies),))
        body_ids, dof_ids, axis_list, geom_lists = [], [], [], []
        for k, body in enumerate(bodies):
            if isinstance(body, str):
                b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
                if b < 0:
                    raise ValueError(f"no body named {body!r} in the model")
            else:
                b = int(body)
                if not 0 < b < model.nbody:
                    raise ValueError(f"body id {body!r} out of range 1..{model.nbody - 1}")
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body {b}"
            joints = [j for j in range(model.njnt) if model.jnt_bodyid[j] == b]
            hinges = [j for j in joints if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
            if len(joints) != 1 or len(hinges) != 1:
                raise ValueError(
                    f"wheel body {name!r} must have exactly one joint, a hinge (its spin);"
                    f" it has {len(joints)} joint(s), {len(hinges)} hinge(s)"
                )
            j = hinges[0]
            axis = np.asarray(model.jnt_axis[j] if axes is None else axes[k], float)
            if axis.shape != (3,) or not np.linalg.norm(axis) > 0:
                raise ValueError(f"axis of wheel {name!r} must be a non-zero 3-vector")
            axis = axis / np.linalg.norm(axis)
            geoms = [
                g
                for g in range(model.ngeom)
                if model.geom_bodyid[g] == b
                and (model.geom_contype[g] or model.geom_conaffinity[g])
            ]
            if not geoms:
                raise ValueError(f"wheel body {name!r} has no collision geom")
            for g in geoms:
                gname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}"
                _check_frictionless(model, g, gname)
                if int(model.geom_type[g]) in (
                    int(mujoco.mjtGeom.mjGEOM_SPHERE),
                    int(mujoco.mjtGeom.mjGEOM_CYLINDER),
                ):
                    r = float(model.geom_size[g, 0])
                    if abs(r - radius[k]) > radius_rtol * radius[k]:
                        raise ValueError(
                            f"collision geom {gname!r} of wheel {name!r} has radius {r} m,"
                            f" but the wheel's D/2 is {radius[k]} m"
                        )
            body_ids.append(b)
            dof_ids.append(int(model.jnt_dofadr[j]))
            axis_list.append(tuple(float(a) for a in axis))
            geom_lists.append(tuple(geoms))
        if len(set(body_ids)) != len(body_ids):
            raise ValueError("bodies lists a wheel body twice")
        return cls(
            wheel=wheel,
            static_load=_static_loads(model, geom_lists, settle_time),
            min_load=min_load,
            body_ids=tuple(body_ids),
            dof_ids=tuple(dof_ids),
            axes=tuple(axis_list),
            geom_ids=tuple(geom_lists),
        )


def _static_loads(model, geom_lists, settle_time):
    """Floor normal force on each wheel after settling at rest (MuJoCo C) [N]."""
    data = mujoco.MjData(model)
    for _ in range(max(1, int(round(settle_time / model.opt.timestep)))):
        mujoco.mj_step(model, data)
    mujoco.mj_forward(model, data)
    wrench = np.zeros(6)
    loads = np.zeros(len(geom_lists))
    for i in range(data.ncon):
        c = data.contact[i]
        for k, geoms in enumerate(geom_lists):
            if c.geom1 in geoms or c.geom2 in geoms:
                mujoco.mj_contactForce(model, data, i, wrench)
                loads[k] += wrench[0]
    if not np.all(loads > 0):
        raise ValueError(
            f"at rest the floor carries no load on some wheels (loads {loads} N): does"
            " every wheel rest on a geom it can touch?"
        )
    return loads


def _check_frictionless(model, g, gname):
    """Every contact a wheel geom can make must have condim 1 (normal force only)."""
    if model.geom_condim[g] != 1:
        raise ValueError(
            f"wheel collision geom {gname!r} has condim={model.geom_condim[g]}; it must be 1"
            " (frictionless): the snow supplies the tangential force, the floor only the load"
        )
    for h in range(model.ngeom):
        touch = (model.geom_contype[g] & model.geom_conaffinity[h]) or (
            model.geom_contype[h] & model.geom_conaffinity[g]
        )
        if (
            touch
            and h != g
            and model.geom_bodyid[h] != model.geom_bodyid[g]
            and model.geom_condim[h] != 1
        ):
            hname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, h) or f"geom {h}"
            raise ValueError(
                f"geom {hname!r} can touch wheel geom {gname!r} but has condim="
                f"{model.geom_condim[h]}; MuJoCo uses the larger condim, so it must be 1"
                " (or exclude the pair with contype/conaffinity)"
            )
    for p in range(model.npair):
        if g in (model.pair_geom1[p], model.pair_geom2[p]) and model.pair_dim[p] != 1:
            raise ValueError(f"contact pair {p} with wheel geom {gname!r} must have condim 1")


# ---------------------------------------------------------------------------------------
# Forces
# ---------------------------------------------------------------------------------------


class MjxWheelForces(eqx.Module):
    """What `step` computed for each wheel (leading axis: wheels, in `MjxWheels` order).

    - `load`: vertical load used [N] (floor normal force of the previous step, or `load=`).
    - `speed`: axle speed along the wheel's heading [m/s]; `lateral_speed`: along the
      axle (horizontal) [m/s]; `slip_angle`: atan2(lateral, |speed|) [rad] (reported only).
    - `wheel_speed`: spin about the axle, world frame [rad/s].
    - `slip`: slip i [-]; `sinkage`: z0 [m]; `entry_angle`: theta0 [rad] (pass it back).
    - `longitudinal_force`: drawbar pull applied along the heading [N];
      `resisting_torque`: M_w applied against the spin [N m] (both after the lift-off
      and rest regularisations).
    - `spin_damping`: c = dM_w/domega >= 0 used implicitly [N m s/rad].
    - `status`: `Status` of each equilibrium (int32).
    """

    load: Float[Array, "... n"]
    speed: Float[Array, "... n"]
    lateral_speed: Float[Array, "... n"]
    slip_angle: Float[Array, "... n"]
    wheel_speed: Float[Array, "... n"]
    slip: Float[Array, "... n"]
    sinkage: Float[Array, "... n"]
    entry_angle: Float[Array, "... n"]
    longitudinal_force: Float[Array, "... n"]
    resisting_torque: Float[Array, "... n"]
    spin_damping: Float[Array, "... n"]
    status: Int[Array, "... n"]


def _safe_atan2(y, x):
    ok = (jnp.abs(x) + jnp.abs(y)) > 0
    return jnp.where(ok, jnp.arctan2(y, jnp.where(ok, x, 1.0)), 0.0)


def _contact_loads(d, wheels):
    """Floor normal force on each wheel from the last constraint solve [N]."""
    contact = d._impl.contact
    efc_address = np.asarray(contact.efc_address)
    dim = np.asarray(contact.dim)
    rows = np.where(dim == 1)[0]
    if rows.size == 0:
        return jnp.zeros((wheels.num_wheels,), d.qpos.dtype)
    force = d._impl.efc_force[efc_address[rows]] * (efc_address[rows] >= 0)
    geom = contact.geom[rows]  # (ncon1, 2)
    loads = []
    for ids in wheels.geom_ids:
        mine = jnp.isin(geom, jnp.asarray(ids)).any(axis=-1)
        loads.append(jnp.sum(jnp.where(mine, force, 0.0)))
    return jnp.stack(loads)


def _wheel_kinematics(m, d, wheels):
    b = np.asarray(wheels.body_ids)
    root = np.asarray(m.body_rootid)[b]
    rot = d.xmat[b]  # (n, 3, 3) body frame -> world
    axle = jnp.einsum("nij,nj->ni", rot, jnp.asarray(wheels.axes, d.qpos.dtype))
    gravity = jnp.asarray(m.opt.gravity, d.qpos.dtype)
    up = -gravity / jnp.linalg.norm(gravity)
    heading = jnp.cross(axle, up)
    heading = heading / jnp.linalg.norm(heading, axis=-1, keepdims=True)
    lateral_dir = jnp.cross(up, heading)  # horizontal, along the axle
    cvel = d.cvel[b]
    offset = d.xipos[b] - d.subtree_com[root]
    velocity = cvel[:, 3:] + jnp.cross(cvel[:, :3], offset)
    speed = jnp.sum(velocity * heading, -1)
    lateral = jnp.sum(velocity * lateral_dir, -1)
    spin = jnp.sum(cvel[:, :3] * axle, -1)
    return speed, lateral, spin, heading, axle, velocity


def _rut_overlap(d, wheels, follows, velocity, spin, axle):
    """Each wheel's overlap with its leader's rut (`Ruts`; 1 for a leader): positions and
    velocities projected on the world's (x, y) plane (z up), the yaw rate the leader
    body's angular velocity about z less its spin's share."""
    b = np.asarray(wheels.body_ids)
    yaw_rate = (d.cvel[b][:, 2] - spin * axle[:, 2])[np.maximum(np.asarray(follows), 0)]
    return _follower_overlap(
        d.xipos[b][:, :2], velocity[:, :2], yaw_rate, wheels.wheel.width, follows
    )


def _snow_forces(m, d, wheels, snow, entry_angle, load, shear, speed_eps, distribution, ruts):
    speed, lateral, spin, heading, axle, velocity = _wheel_kinematics(m, d, wheels)
    dtype = speed.dtype
    load = jnp.broadcast_to(jnp.asarray(load, dtype), speed.shape)
    min_load = wheels.min_load.astype(dtype)
    # A traced prescribed load that is negative or not finite: no force, INVALID_INPUT.
    valid_load = jnp.isfinite(load) & (load >= 0)
    load = jnp.where(valid_load, load, 0.0)
    airborne = jnp.clip(load / min_load, 0.0, 1.0)  # lift-off: forces fade to 0
    solve_load = jnp.maximum(load, min_load)

    n = wheels.num_wheels
    follows = (-1,) * n if ruts is None else ruts.follows
    overlap = None if ruts is None else _rut_overlap(d, wheels, follows, velocity, spin, axle)

    def forces(v, omega):
        contact = ContactModel(snow, distribution, shear)

        def solve(c, idx=slice(None)):
            part = jax.tree.map(lambda x: x[idx] if jnp.ndim(x) == 1 else x, wheels.wheel)
            hint = None if entry_angle is None else entry_angle[idx]
            f = wheel_forces(
                v[idx], omega[idx], solve_load[idx], part, c,
                speed_eps=speed_eps, initial_entry_angle=hint,
            )  # fmt: skip
            return f, f.sinkage

        if ruts is None:
            f, _ = solve(contact)
        else:
            f = _in_tracks(ruts, follows, contact, wheels.wheel.width, overlap, solve)
        return (f.longitudinal_force, f.resisting_torque), f

    # Each wheel's (F, M_w) depends on its own (v, omega) and, in a rut, on its leaders':
    # two forward-mode tangents per level of wheels (leaders, their followers, ...) give
    # the 2 x 2 diagonal block of every wheel at once.  Vmapping the jvp over the
    # tangents traces (and runs) the equilibrium solves once.
    level = _levels(follows)
    masks = (level[None, :] == np.arange(level.max() + 1)[:, None]).astype(float)
    basis = np.concatenate(
        [np.kron(masks, np.ones((2, 1))), np.tile(np.eye(2), (len(masks), 1))], 1
    )

    def tangent(row):
        mask, direction = row[:n], row[n:]
        return jax.jvp(
            forces, (speed, spin), (mask * direction[0], mask * direction[1]), has_aux=True
        )

    _, jac, f = jax.vmap(tangent, out_axes=(None, 0, None))(jnp.asarray(basis, speed.dtype))
    pick = lambda rows, axis: rows[2 * level + axis, np.arange(n)]  # noqa: E731
    (dF_dv, dF_dw), (dM_dv, dM_dw) = ((pick(x, 0), pick(x, 1)) for x in jac)
    force = airborne * f.longitudinal_force
    torque = airborne * f.resisting_torque
    # Damping of the generalised snow force Q = J_v^T F - J_w^T M_w w.r.t. (v, omega):
    # D = -dQ/d(v, omega) = [[-dF/dv, -dF/dw], [dM/dv, dM/dw]] (diagonal clipped at 0).
    damp = airborne[:, None, None] * jnp.stack(
        [
            jnp.stack([jnp.maximum(-dF_dv, 0.0), -dF_dw], -1),
            jnp.stack([dM_dv, jnp.maximum(dM_dw, 0.0)], -1),
        ],
        -2,
    )
    wrench = jnp.concatenate([force[:, None] * heading, -torque[:, None] * axle], axis=-1)
    out = MjxWheelForces(
        load=load,
        speed=speed,
        lateral_speed=lateral,
        slip_angle=_safe_atan2(lateral, jnp.abs(speed)),
        wheel_speed=spin,
        slip=f.slip,
        sinkage=f.sinkage,
        entry_angle=f.entry_angle,
        longitudinal_force=force,
        resisting_torque=torque,
        spin_damping=damp[:, 1, 1],
        status=jnp.where(valid_load, f.status, Status.INVALID_INPUT).astype(jnp.int32),
    )
    return wrench, damp, heading, axle, out


def _snow_damping_matrix(m, d, wheels, damp, heading, axle):
    """K = sum_k G_k^T D_k G_k [N s/m ...], G_k = (heading^T J_p, axle^T J_r) (2 x nv)."""
    b = jnp.asarray(wheels.body_ids)

    def rows(body, point, h, a):
        jacp, jacr = mjx.jac(m, d, point, body)  # (nv, 3) each
        return jnp.stack([jacp @ h, jacr @ a])  # (2, nv)

    g = jax.vmap(rows)(b, d.xipos[np.asarray(wheels.body_ids)], heading, axle)  # (n, 2, nv)
    return jnp.einsum("kiv,kij,kjw->vw", g, damp, g)


def _check_step_args(m, d, wheels, snow, shear, speed_eps, distribution):
    if not isinstance(m, mjx.Model):
        raise TypeError(f"m must be an mjx.Model (mjx.put_model), got {type(m).__name__}")
    if not isinstance(d, mjx.Data):
        raise TypeError(f"d must be an mjx.Data (mjx.make_data), got {type(d).__name__}")
    if not isinstance(wheels, MjxWheels):
        raise TypeError(f"wheels must be a snowjax.mjx.MjxWheels, got {type(wheels).__name__}")
    _check_dynamic_shear(shear, "snowjax.mjx")
    _check_model(wheels.wheel, snow, distribution, shear)
    _check_parameters(wheels.wheel, snow, distribution, shear)
    if not (np.isfinite(speed_eps) and speed_eps > 0):
        raise ValueError(f"speed_eps must be finite and > 0 m/s; got {speed_eps!r}")
    if m.opt.integrator != mjx.IntegratorType.EULER:
        raise ValueError(
            "snowjax.mjx.step needs integrator='Euler' (it adds the snow torque's slope to"
            f" the implicit wheel damping); the model has {m.opt.integrator!r}"
        )
    if m.opt.disableflags & mjx.DisableBit.EULERDAMP:
        raise ValueError("snowjax.mjx.step needs Euler's implicit damping (eulerdamp enabled)")
    if max(wheels.body_ids) >= m.nbody:
        raise ValueError("wheels do not belong to this model (body id out of range)")


def step(
    m: mjx.Model,
    d: mjx.Data,
    wheels: MjxWheels,
    snow: Terrain | ContactModel,
    entry_angle: Float[ArrayLike, " n"] | None = None,
    *,
    load: Float[ArrayLike, " n"] | str | None = None,
    shear: ShearModel | AbstractShearLaw = "classic",
    speed_eps: float = DEFAULT_SPEED_EPS,
    distribution: AbstractStressDistribution | None = None,
    ruts: Ruts | None = None,
) -> tuple[mjx.Data, MjxWheelForces]:
    """One MJX time step with the snow's forces on the wheels; pure and differentiable.

    The same pipeline as `mjx.step` (`fwd_position`, sensors, `fwd_velocity`,
    `fwd_actuation`, `fwd_acceleration`, constraint `solve`, Euler), with the wheel
    forces computed after the velocity stage (so from the current positions and
    velocities) and written into the wheel rows of `xfrc_applied` (those rows are
    overwritten; other rows are kept): force `longitudinal_force * heading` [N] and
    torque `-resisting_torque * axle` [N m], world frame, at each wheel's centre of mass
    (its axle).  The snow torque's slope is added to the wheels' damping for the Euler
    update (module docs).  See the module documentation for the load and sinkage model.

    **Arguments:**

    - `m`, `d`: `mjx.Model` (Euler integrator) and `mjx.Data`.
    - `wheels`: `MjxWheels` of this model.
    - `snow`: the terrain, any `snowjax.Terrain` (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
      `LayeredSnow`; SI), or a `ContactModel` (its shear law and distribution; then
      leave those keywords out).  Vmapping over its leaves runs one rollout per terrain.
    - `entry_angle`: warm start theta0 [rad] per wheel, the `entry_angle` output of the
      previous step (None: cold start); changes only the iteration count.
    - `load`: vertical load per wheel [N]: None (default) `wheels.static_load`, the
      quasi-static load at rest; an array (shape () or (n,)) to prescribe it; or
      `"contact"`: the floor's normal force on the wheel in the previous step (module
      documentation; includes load transfer, but see its caveat).
    - `shear`, `speed_eps`, `distribution`: as in `snowjax.wheel_forces` (shear model;
      regularisation speed [m/s]; `None`, `FrontRegion()`, `WongReece` or another
      stress distribution).
    - `ruts`: None (default: every wheel on virgin snow), or `snowjax.Ruts(k_0, a_u,
      follows)`: the wheels run in the ruts of the wheels ahead, `follows` in
      `MjxWheels` order (default: the last half behind the first half, as the shipped
      vehicle's rear wheels behind its front wheels), each seeing the rut's depth times
      its overlap with its leader's path (`snowjax.track_offset`, in the world's x-y
      plane); a following wheel's `sinkage` is below its rut's floor.

    **Returns:** `(next mjx.Data, MjxWheelForces)`; its `xfrc_applied` holds the snow
    wrenches that were applied.

    **Errors:** `TypeError` for arguments of the wrong type, `ValueError` for a model
    that is not Euler-integrated, a bad `speed_eps` or `shear`, a shear model the terrain
    does not support, a concrete terrain or wheel parameter out of `solve_wheel`'s range
    (NaN included) or a concrete prescribed `load` that is negative or not finite.  Under
    `jit`, a wheel whose prescribed load is negative or not finite gets no snow force and
    `Status.INVALID_INPUT`.
    """
    snow, shear, distribution, *_ = _unpack_model(snow, shear, distribution)
    shear = _shear_name(shear)
    _check_step_args(m, d, wheels, snow, shear, speed_eps, distribution)
    if isinstance(load, str) and load != "contact":
        raise ValueError(f"load must be None, 'contact' or an array of loads [N]; got {load!r}")
    if not isinstance(load, str):
        _check_concrete("load", load, lambda x: x >= 0, ">= 0 N (0: the wheel is airborne)")
    if isinstance(load, str):
        # The floor's normal forces of the last solve, before fwd_position rebuilds them.
        load = _contact_loads(d, wheels)
    elif load is None:
        load = wheels.static_load
    n = wheels.num_wheels
    if entry_angle is not None:
        entry_angle = jnp.broadcast_to(jnp.asarray(entry_angle, d.qpos.dtype), (n,))
    ruts = _resolved(ruts, n)

    d = mjx.fwd_position(m, d)
    d = mjx.sensor_pos(m, d)
    d = mjx.fwd_velocity(m, d)
    d = mjx.sensor_vel(m, d)
    wrench, damp, heading, axle, out = _snow_forces(
        m,
        d,
        wheels,
        snow,
        entry_angle,
        load,
        shear,
        float(speed_eps),
        distribution,
        ruts,
    )
    b = np.asarray(wheels.body_ids)
    d = d.replace(xfrc_applied=d.xfrc_applied.at[b].set(wrench.astype(d.xfrc_applied.dtype)))
    d = mjx.fwd_actuation(m, d)
    d = mjx.fwd_acceleration(m, d)
    if d._impl.efc_J.size == 0:
        d = d.replace(qacc=d.qacc_smooth)
    else:
        d = mjx.solve(m, d)
        d = mjx.sensor_acc(m, d)
    # Linearly implicit Euler in the snow forces: (M + dt (D_joint + K)) qacc = f, then
    # MJX's own update of the state with that qacc (implicit damping switched off there).
    dt = m.opt.timestep
    mass = mjx.full_m(m, d) + dt * jnp.diag(m.dof_damping)
    mass = mass + dt * _snow_damping_matrix(m, d, wheels, damp, heading, axle)
    qacc = jnp.linalg.solve(mass, d.qfrc_smooth + d.qfrc_constraint)
    explicit = m.replace(
        opt=m.opt.replace(disableflags=m.opt.disableflags | mjx.DisableBit.EULERDAMP)
    )
    d = mjx.euler(explicit, d.replace(qacc=qacc))
    return d, out


# ---------------------------------------------------------------------------------------
# Rollout
# ---------------------------------------------------------------------------------------


class Rollout(eqx.Module):
    """States and wheel outputs of `rollout`, one row per step (after the step).

    `time` [s], `qpos`, `qvel` (MJX's generalised coordinates and velocities, SI),
    `wheels`: `MjxWheelForces` with a leading step axis (forces of the step that
    produced the row), `data`: the final `mjx.Data`.
    """

    time: Float[Array, " steps"]
    qpos: Float[Array, "steps nq"]
    qvel: Float[Array, "steps nv"]
    wheels: MjxWheelForces
    data: mjx.Data


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
    shear: ShearModel | AbstractShearLaw = "classic",
    speed_eps: float = DEFAULT_SPEED_EPS,
    distribution: AbstractStressDistribution | None = None,
    ruts: Ruts | None = None,
) -> Rollout:
    """`num_steps` calls of `step` in one `jax.lax.scan`, the entry angles carried along.

    **Arguments:** as `step`, plus `ctrl`: actuator controls (for the shipped vehicle,
    motor torques [N m]), shape (nu,) held constant or (num_steps, nu) per step;
    `num_steps`: number of steps (static int >= 1); `entry_angle`: initial warm start
    [rad].  Jit it yourself (e.g. `jax.jit(rollout, static_argnums=5)` or inside your own
    jitted function); vmap it over snows; differentiate it.

    **Returns:** `Rollout`.
    """
    snow, shear, distribution, *_ = _unpack_model(snow, shear, distribution)
    shear = _shear_name(shear)
    _check_step_args(m, d, wheels, snow, shear, speed_eps, distribution)
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
        data, theta = carry
        data, out = step(
            m,
            data.replace(ctrl=u),
            wheels,
            snow,
            theta,
            load=load,
            shear=shear,
            speed_eps=speed_eps,
            distribution=distribution,
            ruts=ruts,
        )
        theta = jax.lax.stop_gradient(
            jnp.where(jnp.isfinite(out.entry_angle), out.entry_angle, theta)
        )
        return (data, theta), (data.time, data.qpos, data.qvel, out)

    (data, _), (time, qpos, qvel, outs) = jax.lax.scan(body, (d, entry_angle), ctrl)
    return Rollout(time=time, qpos=qpos, qvel=qvel, wheels=outs, data=data)
