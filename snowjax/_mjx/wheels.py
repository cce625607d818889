# pyright: reportAttributeAccessIssue=false
# (mujoco is a C extension without type stubs: pyright cannot see its attributes.)
"""Which bodies of a MuJoCo model are wheels on snow: `MjxWheels`, and its checks."""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

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

from .._leaves import _as_float
from .._wheel.geometry import AbstractWheel, RigidWheel

__all__ = ["MjxWheels", "mjx", "mujoco"]

# Contact sensor data (mjtConDataField order) and each field's size per slot.
_CONDATA_SIZES = (1, 3, 3, 1, 3, 3, 3, 3, 3)  # found force torque dist pos normal tangent ...
_FORCE, _NORMAL = 1, 5


class MjxWheels(eqx.Module):
    """Which bodies of a MuJoCo model are wheels on snow, and their geometry.

    Build it with `MjxWheels.from_model` (checks the model).  **Fields:**

    - `wheel`: `RigidWheel` (diameter D, width b [m]) or another `snowjax.AbstractWheel`
      (`DeflectingTire`); leaves scalar or of shape (n,).
    - `static_load`: each wheel's load at rest [N], the default load of `step`
      (measured by `from_model`: MuJoCo settles the model at rest, zero controls, and
      reads the normal force of each wheel's ground contacts).
    - `min_load`: with `load="contact"`, the load below which the snow forces fade
      linearly to 0 (lift-off) [N].
    - `body_ids`: the n wheel bodies (static).
    - `dof_ids`: each wheel's spin dof (the hinge joint of the body; static).
    - `axes`: spin axis of each wheel in its body frame (unit vectors; static).  Positive
      spin about the axis rolls the wheel along `axis x normal` (normal: the ground's,
      pointing out of it).
    - `sensors`: per wheel, `(force, normal)` addresses in `sensordata` of every contact
      slot of its contact sensors (static): the normal force [N] and the unit normal of
      each ground contact, the public channel through which `step` reads the ground.
    """

    wheel: AbstractWheel
    static_load: Float[Array, " n"] = eqx.field(converter=_as_float)
    min_load: Float[Array, ""] = eqx.field(converter=_as_float)
    body_ids: tuple[int, ...] = eqx.field(static=True)
    dof_ids: tuple[int, ...] = eqx.field(static=True)
    axes: tuple[tuple[float, float, float], ...] = eqx.field(static=True)
    sensors: tuple[tuple[tuple[int, int], ...], ...] = eqx.field(static=True)

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
    ) -> MjxWheels:
        """Describe the wheels of `model` (a `mujoco.MjModel`, before `mjx.put_model`).

        **Arguments:**

        - `bodies`: wheel bodies, by name or id; each must have exactly one joint, a
          hinge (its spin; steering and suspension joints belong to parent bodies), at
          least one collision geom (`contype` or `conaffinity` != 0), all of them
          `condim="1"` and only able to touch geoms with `condim="1"`, and a MuJoCo
          contact sensor on each collision geom reporting `force` and `normal`, e.g.
          `<contact geom1="tyre_fl" num="4" data="force normal" reduce="mindist"/>`
          (MuJoCo >= 3.3; MJX computes it; the shipped rover has them).
        - `wheel`: `RigidWheel` (D, b [m]) or `DeflectingTire`; default
          `RigidWheel.thesis_tire()`.  Sphere and cylinder collision geoms must have
          radius D/2 (within `radius_rtol`).
        - `axes`: spin axis per wheel in the body frame; default the hinge's axis.
        - `min_load`: lift-off threshold [N], > 0.
        - `settle_time`: how long MuJoCo (C, not MJX) lets the model settle at rest from
          `qpos0` with zero controls to measure `static_load` [s].

        **Raises:** `TypeError` for a model that is not a `mujoco.MjModel` or a wheel that
        is not a `snowjax.AbstractWheel`; `ValueError` naming the body or geom for an
        unknown body, a body without exactly one hinge, without collision geoms, with a
        frictional (condim > 1) contact, a radius that is not D/2 or a collision geom
        without a contact sensor (the message gives the MJCF line to add).
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
        body_ids, dof_ids, axis_list, sensor_lists = [], [], [], []
        for k, body in enumerate(bodies):
            b, name = _body_id(model, body)
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
            slots = []
            for g in geoms:
                gname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}"
                _check_frictionless(model, g, gname)
                _check_radius(model, g, gname, name, radius[k], radius_rtol)
                slots.extend(_sensor_slots(model, g, gname))
            body_ids.append(b)
            dof_ids.append(int(model.jnt_dofadr[j]))
            axis_list.append(tuple(float(a) for a in axis))
            sensor_lists.append(tuple(slots))
        if len(set(body_ids)) != len(body_ids):
            raise ValueError("bodies lists a wheel body twice")
        return cls(
            wheel=wheel,
            static_load=_static_loads(model, sensor_lists, settle_time),
            min_load=min_load,
            body_ids=tuple(body_ids),
            dof_ids=tuple(dof_ids),
            axes=tuple(axis_list),
            sensors=tuple(sensor_lists),
        )


def _body_id(model, body):
    if isinstance(body, str):
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
        if b < 0:
            raise ValueError(f"no body named {body!r} in the model")
    else:
        b = int(body)
        if not 0 < b < model.nbody:
            raise ValueError(f"body id {body!r} out of range 1..{model.nbody - 1}")
    return b, mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body {b}"


def _check_radius(model, g, gname, name, radius, rtol):
    if int(model.geom_type[g]) in (
        int(mujoco.mjtGeom.mjGEOM_SPHERE),
        int(mujoco.mjtGeom.mjGEOM_CYLINDER),
    ):
        r = float(model.geom_size[g, 0])
        if abs(r - radius) > rtol * radius:
            raise ValueError(
                f"collision geom {gname!r} of wheel {name!r} has radius {r} m,"
                f" but the wheel's D/2 is {radius} m"
            )


def _sensor_slots(model, g, gname):
    """(force address, normal address) in sensordata of every slot of the contact
    sensors on geom g (geom1 = g, any second geom)."""
    slots = []
    for s in range(model.nsensor):
        if (
            model.sensor_type[s] != mujoco.mjtSensor.mjSENS_CONTACT
            or model.sensor_objtype[s] != mujoco.mjtObj.mjOBJ_GEOM
            or model.sensor_objid[s] != g
            or model.sensor_reftype[s] != mujoco.mjtObj.mjOBJ_UNKNOWN
        ):
            continue
        dataspec = int(model.sensor_intprm[s, 0])
        if not (dataspec >> _FORCE) & 1 or not (dataspec >> _NORMAL) & 1:
            continue
        used = [i for i in range(len(_CONDATA_SIZES)) if (dataspec >> i) & 1]
        size = sum(_CONDATA_SIZES[i] for i in used)
        within = {i: sum(_CONDATA_SIZES[u] for u in used if u < i) for i in used}
        for slot in range(int(model.sensor_dim[s]) // size):
            base = int(model.sensor_adr[s]) + slot * size
            slots.append((base + within[_FORCE], base + within[_NORMAL]))
    if not slots:
        raise ValueError(
            f"wheel collision geom {gname!r} has no contact sensor reporting force and "
            "normal; add one to the model, e.g. in MJCF: <sensor><contact "
            f'geom1="{gname}" num="4" data="force normal" reduce="mindist"/></sensor>'
            " (the geom needs a name)"
        )
    return slots


def _static_loads(model, sensor_lists, settle_time):
    """Normal force of each wheel's ground contacts after settling at rest (MuJoCo C) [N]."""
    data = mujoco.MjData(model)
    for _ in range(max(1, int(round(settle_time / model.opt.timestep)))):
        mujoco.mj_step(model, data)
    mujoco.mj_forward(model, data)
    loads = np.array([sum(data.sensordata[f] for f, _ in slots) for slots in sensor_lists])
    if not np.all(loads > 0):
        raise ValueError(
            f"at rest the ground carries no load on some wheels (loads {loads} N): does"
            " every wheel rest on a geom it can touch?"
        )
    return loads


def _check_frictionless(model, g, gname):
    """Every contact a wheel geom can make must have condim 1 (normal force only)."""
    if model.geom_condim[g] != 1:
        raise ValueError(
            f"wheel collision geom {gname!r} has condim={model.geom_condim[g]}; it must be 1"
            " (frictionless): the snow supplies the tangential force, the ground only the load"
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


def _ground(d, wheels, up):
    """Each wheel's ground contacts from the contact sensors of the last step: (load [N],
    unit normal out of the ground), shapes (n,) and (n, 3).  The normal is the
    load-weighted mean of the contacts' normals, blended with `up` by 1e-6 of the static
    load (so it is `up` for a wheel in the air, and smooth)."""
    loads, normals = [], []
    for k, slots in enumerate(wheels.sensors):
        f = np.asarray([a for a, _ in slots])
        nrm = np.asarray([b for _, b in slots])[:, None] + np.arange(3)
        force = d.sensordata[f]  # (slots,) normal forces, >= 0
        normal = d.sensordata[nrm]  # (slots, 3), either sign
        normal = normal * jnp.sign(jnp.sum(normal * up, -1, keepdims=True) + 1e-30)
        blend = 1e-6 * wheels.static_load[k].astype(up.dtype)
        total = jnp.sum(force[:, None] * normal, 0) + blend * up
        loads.append(jnp.sum(force))
        normals.append(total / jnp.linalg.norm(total))
    return jnp.stack(loads), jnp.stack(normals)
