"""Several wheels in one track: each pass runs on the rut the earlier ones left (`Rut`).

The rut's state is the deepest sinkage below the original surface any earlier wheel
reached, z_max (0 before the first pass).  Pass k runs on `Rut(terrain, z_max, b, k_0,
A_u)`; its lowest point lies `sinkage + floor_depth` below the original surface, and
z_max grows to it where the wheel went deeper (a wheel that stays within the rut's
elastic rebound leaves the state as it was: the next identical wheel repeats it).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, Int

from .._leaves import _as_float, _is_traced, parameter
from .._terrain.base import AbstractTerrain
from .._terrain.rut import Rut
from .._terrain.rut_map import RutMap, _check_modulus
from .equilibrium import solve_wheel
from .geometry import AbstractWheel
from .model import ContactModel, _as_model, _takes_model, _with_terrain

__all__ = ["PassResult", "PathResult", "Ruts", "drive_path", "multi_pass", "track_offset"]


class PassResult(eqx.Module):
    """Each pass of `multi_pass`, along the last axis (pass 1 first).

    - `sinkage`: the wheel's lowest point below the original surface [m].
    - `rut_depth`: the rut's state after the pass, z_max [m].
    - `motion_resistance`, `drawbar_pull` [N], `torque` [N m]: as `WheelState`'s.
    - `status`: `Status` of each pass's equilibrium.
    """

    sinkage: Float[Array, "... n"]
    rut_depth: Float[Array, "... n"]
    motion_resistance: Float[Array, "... n"]
    drawbar_pull: Float[Array, "... n"]
    torque: Float[Array, "... n"]
    status: Int[Array, "... n"]


@_takes_model(positional=6)
def multi_pass(
    wheel: AbstractWheel,
    terrain: AbstractTerrain | ContactModel,
    loads: Float[ArrayLike, "... n"],
    slip: Float[ArrayLike, "..."],
    k_0: Float[ArrayLike, "..."],
    a_u: Float[ArrayLike, "..."],
) -> PassResult:
    """n wheels in one track, one after the other (a convoy, a tandem axle).

    **Arguments:**

    - `wheel`: every pass's wheel (`RigidWheel`, `DeflectingTire`, ...).
    - `terrain`: the virgin terrain (any law), or a `ContactModel` of it (its shear
      law, stress distribution, nodes per panel and force terms act in every pass, the
      later passes on a `Rut` of its terrain).
    - `loads`: F_z of each pass [N], the passes along the last axis (leading axes batch).
    - `slip`: driving slip of every pass [-] (broadcast against `loads`).
    - `k_0` [Pa/m], `a_u` [Pa/m^2]: the unloading modulus k_u = k_0 + A_u z_u of the
      terrain (`Rut`).

    **Returns:** a `PassResult`.  Differentiable in every input (the rut's state is a
    running maximum: its derivative follows the pass that set it).
    """
    model = _as_model(terrain)
    virgin = model.terrain
    loads = jnp.asarray(loads, float)
    slips = jnp.broadcast_to(jnp.asarray(slip, loads.dtype), loads.shape)
    z_max = jnp.zeros(loads.shape[:-1], loads.dtype)
    rows = []
    for k in range(loads.shape[-1]):
        # The first pass on the virgin terrain itself (a rut of zero depth is the same
        # law, but the virgin law may offer closed forms: Wong snow's front region).
        ground, floor = model, 0.0
        if k > 0:
            rut = Rut(virgin, z_max, wheel.width, k_0, a_u)
            ground, floor = _with_terrain(model, rut), rut.floor_depth
        st = solve_wheel(wheel, ground, loads[..., k], slips[..., k])
        total = _below_surface(st.sinkage, floor, virgin)
        z_max = jnp.maximum(z_max, total)
        rows.append((total, z_max, st.motion_resistance, st.drawbar_pull, st.torque, st.status))
    return PassResult(*(jnp.stack(column, axis=-1) for column in zip(*rows)))


def _below_surface(sinkage, floor, terrain):
    """The depth [m] below the original surface of a wheel that sank `sinkage` [m] below
    a rut's floor at `floor` [m]: their sum, kept on the virgin `terrain`'s base (a
    wheel resting on it: the sum can round past it, which no `Rut` accepts)."""
    return jnp.minimum(sinkage + floor, terrain.depth)


def _left_behind(sinkage, rut, seen):
    """The rut's state [m] a wheel leaves behind that sank `sinkage` [m] below the floor
    of `rut` (a `Rut` of depth `seen` [m] of its virgin terrain): its lowest point below
    the original surface, or the rut it ran in where that is deeper (a wheel within the
    rut's elastic rebound leaves the rut as it was)."""
    return jnp.maximum(_below_surface(sinkage, rut.floor_depth, rut.virgin), seen)


class Ruts(eqx.Module):
    """Wheels of a vehicle running in the ruts of the wheels ahead of them (the
    `ruts=` option of `simulate_longitudinal`, `simulate_planar` and `snowjax.mjx`).

    The model is `multi_pass`'s, inside the vehicle and quasi-static: at every instant
    a following wheel runs on the `Rut` whose depth is the deepest point below the
    original surface its leader reaches now (the leader's own sinkage below its rut's
    floor plus that floor, or the rut it runs in, whichever is deeper), i.e. the rut of
    a leader in steady state (the time the snow takes from the leader to the follower,
    wheelbase / speed, is not modelled).  Where the follower is offset sideways from its
    leader's path (a turning vehicle; `track_offset`), or narrower or wider than it, it
    sees the rut's depth times the share of its width over the rut (`_overlap`: for
    equal widths b, `clip(1 - |e| / b, 0, 1)`, e the offset): the contact is split by the
    width-weighted mean depth of the snow under the follower, not into a rut part and a
    virgin part (a documented simplification).

    **Fields:**

    - `k_0`: unloading modulus at zero sinkage [Pa/m], > 0 (`Rut`).
    - `a_u`: its growth with the rut's depth [Pa/m^2], >= 0.
    - `follows`: for each wheel, the index of the wheel whose rut it runs in, or -1 for
      virgin snow (static; leaders before followers).  None (default): the simulation's
      own layout (`simulate_planar`: rear left behind front left, rear right behind
      front right; `simulate_longitudinal` with n = 2 m wheels: the last m behind the
      first m, as two axles of m tracks; one wheel: virgin snow).
    """

    k_0: Float[Array, ""] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "Pa/m", "unloading modulus at zero sinkage k_0", lower=0.0, open_lower=True, scale=1e6
        ),
    )
    a_u: Float[Array, ""] = eqx.field(
        converter=_as_float,
        metadata=parameter("Pa/m^2", "growth A_u of the unloading modulus", lower=0.0, scale=1e7),
    )
    follows: tuple[int, ...] | None = eqx.field(static=True, default=None)

    def layout(self, num_wheels: int) -> tuple[int, ...]:
        """`follows`, or the default two-axle layout for `num_wheels` wheels; checked."""
        follows = self.follows
        if follows is None:
            if num_wheels == 1:
                follows = (-1,)
            elif num_wheels % 2:
                raise ValueError(
                    f"Ruts(follows=None) needs an even number of wheels (two axles); got "
                    f"{num_wheels}: give follows, one leader index (or -1) per wheel"
                )
            else:
                m = num_wheels // 2
                follows = (-1,) * m + tuple(range(m))
        follows = tuple(int(j) for j in follows)
        if len(follows) != num_wheels or any(not -1 <= j < k for k, j in enumerate(follows)):
            raise ValueError(
                f"Ruts.follows must give, for each of the {num_wheels} wheels, -1 or the index "
                f"of a wheel before it; got {follows!r}"
            )
        _check_modulus(self.k_0, self.a_u)
        return follows

    def _overlap(self, overlap: Callable) -> Any:
        """Each wheel's overlap with its leader's rut: `overlap(follows)`."""
        return overlap(self.follows)

    def _solving(self) -> Ruts:
        """What `_solve` needs: all of it."""
        return self

    def _solve(self, contact, width, overlap, solve):
        """The wheels solved level by level in the ruts of their leaders (`_in_tracks`;
        the layout resolved)."""
        return _in_tracks(self, contact, width, overlap, solve)

    def _depths(self, terrain, width, overlap, sinkage):
        """(the rut depth each wheel saw, the rut's state it leaves behind) [m] of wheels
        that `_solve` put at `sinkage` [m] below their ruts' floors (the wheel axis last;
        the layout resolved): `_in_tracks`'s depths again, from its results."""
        follows = np.asarray(self.follows)
        n = follows.size
        width = jnp.broadcast_to(jnp.asarray(width), (n,))
        seen: list = [None] * n
        left: list = [None] * n
        for k, j in enumerate(follows.tolist()):  # leaders before followers
            z = sinkage[..., k]
            if j < 0:
                seen[k], left[k] = jnp.zeros_like(z), z
            else:
                seen[k] = _take(overlap, n, np.array([k]))[..., 0] * left[j]
                rut = Rut(terrain, seen[k], width[j], self.k_0, self.a_u)
                left[k] = _left_behind(z, rut, seen[k])
        return jnp.stack(seen, -1), jnp.stack(left, -1)


class _VirginGround(eqx.Module):
    """The ground of a vehicle without `Ruts`: every wheel on the virgin terrain.  With
    `Ruts` (its layout resolved, `_resolved`) the two are the terrain state a vehicle's
    wheels run on: `layout(n)`, `_overlap(overlap)` and `_solve(contact, width,
    overlap, solve)`, where `solve(contact, take)` solves the wheels that `take`
    selects from arrays with the wheel axis last and returns (results, sinkage), and
    `_depths(terrain, width, overlap, sinkage)`: the rut depth each wheel saw and the
    rut's state it leaves behind, from the solved sinkages."""

    def layout(self, num_wheels: int) -> tuple[int, ...]:
        """Every wheel a leader on virgin snow."""
        return (-1,) * num_wheels

    def _overlap(self, overlap: Callable) -> Any:
        del overlap
        return 1.0

    def _solving(self) -> _VirginGround:
        """What `_solve` needs: all of it."""
        return self

    def _solve(self, contact, width, overlap, solve):
        del width, overlap
        return solve(contact, lambda x: x)[0]

    def _depths(self, terrain, width, overlap, sinkage):
        """No rut (0) and the wheels' own sinkage [m] (`Ruts._depths`)."""
        del terrain, width, overlap
        return jnp.zeros_like(sinkage), sinkage


def track_offset(
    leader: Float[ArrayLike, "... 2"],
    follower: Float[ArrayLike, "... 2"],
    velocity: Float[ArrayLike, "... 2"],
    yaw_rate: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """|e| [m]: how far sideways a follower's path runs from its leader's, for a rigid
    body moving in the plane (both points fixed on it).

    Both paths are circles about the instantaneous centre of rotation c (straight lines
    when the yaw rate is 0), and |e| = | |p_f - c| - |p_l - c| |, written so that it is
    exact and finite as the yaw rate goes to 0, where it becomes the follower's distance
    from the line through the leader along its velocity:

        |e| = |r |d|^2 - 2 w.d| / (|r d - w| + |w|),   d = p_f - p_l,  w = z x v_l,

    (r the yaw rate, v_l the leader's velocity).  0 at rest.

    **Arguments:** `leader`, `follower`: positions (x, y) [m] in any frame fixed to the
    body or the ground; `velocity`: the leader's velocity (v_x, v_y) [m/s] in the same
    frame; `yaw_rate` r [rad/s], counter-clockwise positive.
    """
    d = jnp.asarray(follower) - jnp.asarray(leader)
    v = jnp.asarray(velocity)
    r = jnp.asarray(yaw_rate)
    w = jnp.stack([-v[..., 1], v[..., 0]], -1)
    numerator = r * jnp.sum(d * d, -1) - 2 * jnp.sum(w * d, -1)
    denominator = jnp.linalg.norm(r[..., None] * d - w, axis=-1) + jnp.linalg.norm(w, axis=-1)
    moving = denominator > 0
    return jnp.where(moving, jnp.abs(numerator) / jnp.where(moving, denominator, 1.0), 0.0)


def _overlap(offset, width, leader_width):
    """The share [-] of a wheel of width b_f [m] whose centre line runs |e| = `offset`
    [m] beside a rut of width b_l [m] that lies over the rut:
    |[e - b_f/2, e + b_f/2] and [-b_l/2, b_l/2]| / b_f, in [0, 1]."""
    inner = jnp.minimum(offset + width / 2, leader_width / 2)
    outer = jnp.maximum(offset - width / 2, -leader_width / 2)
    return jnp.clip((inner - outer) / width, 0.0, 1.0)


def _follower_overlap(position, velocity, yaw_rate, width, follows):
    """Each wheel's overlap with its leader's rut (`_overlap` of its `track_offset`), 1
    for a leader: `position`, `velocity` (n, 2) / (..., n, 2) of every wheel in one
    plane frame [m, m/s], `yaw_rate` [rad/s] broadcastable to (..., n) (each follower's
    leader's), `width` [m] broadcastable to (n,)."""
    follows = np.asarray(follows)
    lead = np.maximum(follows, 0)
    position = jnp.asarray(position)
    offset = track_offset(
        position[..., lead, :], position, velocity[..., lead, :], jnp.asarray(yaw_rate)
    )
    width = jnp.broadcast_to(jnp.asarray(width), (follows.size,))
    return jnp.where(follows >= 0, _overlap(offset, width, width[lead]), 1.0)


def _resolved(ruts, num_wheels: int) -> Ruts | _VirginGround:
    """The ground of the simulations' `ruts=`: `_VirginGround()` for None, or the `Ruts`
    with its layout for `num_wheels` wheels resolved and checked."""
    if ruts is None:
        return _VirginGround()
    if not isinstance(ruts, Ruts):
        raise TypeError(
            f"ruts must be None or a snowjax.Ruts (or, in snowjax.mjx, a RutMap), got "
            f"{type(ruts).__name__}"
        )
    return Ruts(ruts.k_0, ruts.a_u, ruts.layout(num_wheels))


def _levels(follows) -> np.ndarray:
    """Each wheel's place in its track (0: a leader on virgin snow, 1: behind it, ...)."""
    level = np.zeros(len(follows), int)
    for k, j in enumerate(follows):
        level[k] = 0 if j < 0 else level[j] + 1
    return level


def _in_tracks(ruts, contact, width, overlap, solve):
    """Solve the wheels of a vehicle level by level (leaders before followers), each
    follower on the `Rut` its leader leaves (`Ruts`, its layout resolved).

    `solve(contact, take)` solves on `contact` the wheels that `take` selects (it takes
    an array whose last axis, the wheel axis, broadcasts to n, and returns the level's
    wheels) and returns (a pytree of results with the wheel axis last, their sinkage
    below the contact's surface).  `width` [m]: the wheels' widths, broadcastable to
    (n,) (a rut's b_1 is its leader's); `overlap` [-]: each wheel's overlap with its
    leader's rut, (..., n).  Returns the results of all wheels in wheel order.
    """
    follows = np.asarray(ruts.follows)
    n = follows.size
    level = _levels(follows)
    width = jnp.broadcast_to(jnp.asarray(width), (n,))
    depth: list = [None] * n  # the deepest point below the original surface per wheel
    parts, order = [], []
    for lv in range(level.max() + 1):
        idx = np.flatnonzero(level == lv)
        take = partial(_take, n=n, idx=idx)
        if lv == 0:
            result, sinkage = solve(contact, take)
            total = sinkage
        else:
            seen = take(overlap) * jnp.stack([depth[j] for j in follows[idx]], -1)
            rut = Rut(contact.terrain, seen, width[follows[idx]], ruts.k_0, ruts.a_u)
            result, sinkage = solve(eqx.tree_at(lambda c: c.terrain, contact, rut), take)
            total = _left_behind(sinkage, rut, seen)
        for i, k in enumerate(idx):
            depth[k] = total[..., i]
        parts.append(result)
        order.extend(idx)
    inverse = np.argsort(np.asarray(order))
    return jax.tree.map(lambda *xs: jnp.concatenate(xs, -1)[..., inverse], *parts)


def _take(x, n: int, idx: np.ndarray):
    """The wheels `idx` of `x`, whose last axis (the wheel axis) broadcasts to n."""
    x = jnp.asarray(x)
    return jnp.broadcast_to(x, jnp.broadcast_shapes(x.shape, (n,)))[..., idx]


class PathResult(eqx.Module):
    """Each step of `drive_path` (leading axis: steps; then wheels), and the final map.

    - `sinkage`: the wheel's lowest point below the original surface [m].
    - `rut_depth`: the rut depth the wheel saw (`RutMap.read`) [m].
    - `motion_resistance`, `drawbar_pull` [N], `torque` [N m]: as `WheelState`'s.
    - `status`: `Status` of each equilibrium.
    - `rut_map`: the `RutMap` after the last step.
    """

    sinkage: Float[Array, "steps n"]
    rut_depth: Float[Array, "steps n"]
    motion_resistance: Float[Array, "steps n"]
    drawbar_pull: Float[Array, "steps n"]
    torque: Float[Array, "steps n"]
    status: Int[Array, "steps n"]
    rut_map: RutMap


@_takes_model(positional=7)
def drive_path(
    wheel: AbstractWheel,
    terrain: AbstractTerrain | ContactModel,
    rut_map: RutMap,
    positions: Float[ArrayLike, "steps n 2"],
    headings: Float[ArrayLike, "steps n"],
    loads: Float[ArrayLike, "*steps n"],
    slip: Float[ArrayLike, "*steps n"],
    *,
    lookahead: Float[ArrayLike, ""] | None = None,
) -> PathResult:
    """n wheels driven along prescribed paths over a `RutMap` (a test rig, a kinematic
    vehicle, a convoy), each step: read the rut ahead of every wheel, solve its
    equilibrium on that `Rut` (quasi-static, `solve_wheel`, warm-started from the last
    step), mark the map with the depth it reached.  One `jax.lax.scan`; jitted;
    differentiable (forward and reverse mode) in the terrain, the wheel, the loads, the
    slips, the map and the positions; vmap it over environments.

    **Arguments:**

    - `wheel`, `terrain`: every wheel's (`RigidWheel`, `DeflectingTire`, ...) and the
      virgin terrain (any law), or a `ContactModel` of it (its shear law, distribution,
      nodes per panel and force terms act on every `Rut` read from the map).
    - `rut_map`: the map before the first step (`RutMap.empty`, or an earlier result's).
    - `positions`: each wheel's centre (x, y) [m] at every step, (steps, n, 2); the
      first row only places the wheels (nothing is marked before it).
    - `headings`: each wheel's heading [rad] at every step, (steps, n).
    - `loads`: F_z [N] and `slip`: driving slip [-], (n,) or (steps, n).
    - `lookahead`: how far ahead of the axle the rut is read [m] (default the wheel's
      radius, the farthest the contact can reach).

    **Returns:** `PathResult`.

    **Errors:** `ValueError` for `positions` not of shape (steps, n, 2) and for a
    concrete `lookahead` (or wheel radius) not above sqrt(2) times the map's cell size
    (a wheel would read its own marks); at run time, a step longer than the map's
    reach raises (`RutMap.mark`).
    """
    if np.ndim(positions) != 3 or np.shape(positions)[-1] != 2:
        raise ValueError(f"positions must have shape (steps, n, 2); got {np.shape(positions)}")
    lookahead = _lookahead(wheel, rut_map, lookahead)
    model = _as_model(terrain)
    return _drive_path(wheel, model, rut_map, positions, headings, loads, slip, lookahead)


def _lookahead(wheel: AbstractWheel, rut_map: RutMap, lookahead) -> Any:
    """How far ahead of its axle a wheel reads `rut_map` [m]: `lookahead`, or (None) the
    wheel's radius (the largest, for wheels of several sizes), checked to exceed sqrt(2)
    times the map's cell size where it is concrete (`RutMap.check_lookahead`)."""
    if lookahead is None:
        diameter = wheel.diameter
        traced = _is_traced(diameter)
        lookahead = jnp.max(diameter) / 2 if traced else float(np.max(np.asarray(diameter))) / 2
    rut_map.check_lookahead(lookahead)
    return lookahead


@eqx.filter_jit
def _drive_path(wheel, model, rut_map, positions, headings, loads, slip, lookahead):
    terrain = model.terrain
    positions = jnp.asarray(positions, float)
    steps, n = positions.shape[:2]
    headings = jnp.broadcast_to(jnp.asarray(headings, positions.dtype), (steps, n))
    loads = jnp.broadcast_to(jnp.asarray(loads, positions.dtype), (steps, n))
    slips = jnp.broadcast_to(jnp.asarray(slip, positions.dtype), (steps, n))
    width = jnp.broadcast_to(wheel.width, (n,))

    def step(carry, row):
        grid, previous, hint = carry
        position, heading, load, s = row
        seen = grid.read(position, heading, width, lookahead)
        rut = Rut(terrain, seen, width, grid.k_0, grid.a_u)
        st = solve_wheel(wheel, _with_terrain(model, rut), load, s, initial_entry_angle=hint)
        total = _left_behind(st.sinkage, rut, seen)
        grid = grid.mark(previous, position, width, total)
        hint = jax.lax.stop_gradient(jnp.where(jnp.isfinite(st.entry_angle), st.entry_angle, hint))
        out = (total, seen, st.motion_resistance, st.drawbar_pull, st.torque, st.status)
        return (grid, position, hint), out

    start = (rut_map, positions[0], jnp.full((n,), jnp.nan, positions.dtype))
    (final, *_), out = jax.lax.scan(step, start, (positions, headings, loads, slips))
    return PathResult(*out, rut_map=final)
