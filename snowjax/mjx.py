"""snowjax wheel forces inside MuJoCo MJX: `snowjax.mjx` (optional extra `snowjax[mjx]`).

Not imported by `import snowjax`; `import snowjax.mjx` needs `pip install 'snowjax[mjx]'`
(`mujoco`, `mujoco-mjx`).  Public MuJoCo API only (no private attributes), tested with
mujoco 4.0 and mujoco-mjx 3.17.

**What it does.**  `step(m, d, wheels, snow, entry_angle)` advances an `mjx.Data` by one
time step like `mjx.step`, with the snow's forces on every wheel body of `wheels`
(`MjxWheels.from_model`), for any MuJoCo model whose wheels are bodies with a spin hinge
(steering and suspension joints on their parent bodies, a free-floating chassis or not).
For each wheel it reads from the MJX state the ground's normal under it (its contact
sensor), the wheel's frame (heading = axle x normal, lateral = normal x heading), the
centre's velocity along both, the spin about the axle and the load; evaluates the same
force function as `snowjax.simulate_planar` (slip of eq. 2.6 and slip angle, regularised
at rest; the quasi-static equilibrium 4.14 with the lateral law by `solve_wheel`,
warm-started from the previous step's entry angles); and writes the drawbar pull (2.10)
along the heading, the lateral force along the lateral direction, the resisting torque
M_w (2.12) about the axle and the aligning torque about the normal into the wheel rows
of `data.xfrc_applied` (at the axle).  Pure JAX: `jax.jit`, `jax.lax.scan`, `jax.vmap`
(over snows, states, controls) and `jax.jvp`/`jax.jacfwd` (through the whole rollout)
all work.  `rollout` scans `step` over a control sequence; `SnowRoverEnv` is a
reinforcement-learning environment on top of it.

**The ground and the load.**  The snow is soft: under the thesis's model a wheel sinks
z0 (4.15) into it, and the snow's vertical reaction equals the wheel load.  MJX has only
rigid geometry, so the wheel's collision geom (a sphere or cylinder of the wheel's radius)
rests on a rigid ground (a plane, an inclined plane or a height field) that stands for the
*compacted bottom of the rut*; the undisturbed snow surface lies z0 above it.  The ground
contact must be frictionless (`condim="1"` on the wheel geoms and on everything they
touch; checked): MuJoCo's contact supplies only the normal force, and the snow supplies
the tangential forces and torques.  Each wheel geom carries a MuJoCo contact sensor
(`data="force normal"`) through which `step` reads, from the previous step (one step of
lag), the ground's normal (the frame of the snow forces follows slopes and bumps) and,
with `load="contact"`, the load.  The load the snow model sees is one of three (`load=`):
by default each wheel's static load, measured by `MjxWheels.from_model` at rest (the
share `simulate_planar` uses); an array to prescribe it; or `"contact"`: the normal force
of the wheel's ground contacts in the previous step, which includes the load transfer of
acceleration, cornering, slopes and bumps.  The forces are scaled by `min(load /
min_load, 1)`, so with `"contact"` a wheel that leaves the ground gets no snow force and
lift-off is continuous; with the static loads a wheel in the air keeps its forces (use
`"contact"` on uneven ground).  Why not a vertical spring on the sinkage: W(z0) is a
plastic compaction curve (it does not give the load back on unloading) and is stiff near
the layer's base, so a spring built from it would be neither the thesis's physics nor
stable in an explicit step.  Neglected: the vertical motion of the vehicle as the rut
deepens or shallows with slip (`sinkage` is reported, not applied to the geometry); the
lateral force acts at the axle, not at the contact patch (no roll moment from it, as in
`simulate_planar`, which has no roll).

**Ruts** (the guide's ruts page).  `ruts=snowjax.Ruts(k_0, a_u, follows)`: quasi-static,
a following wheel runs at every instant on the `Rut` (Gawwad & Crolla's reloading, thesis
eq. 2.21) of the depth its leader leaves now, times the overlap of their paths.
`ruts=snowjax.RutMap.empty(...)`: the ruts' depth on a grid over the
world's x-y plane (z up), carried through `step` (returned third) and `rollout`
(`Rollout.rut_map`), one map per environment under `jax.vmap`.  In every step each wheel
reads the rut its radius ahead of its centre along its direction
of travel (behind it when reversing), runs on that `Rut`, and marks the segment its
centre swept in the step, `p - v dt` to `p`, with the depth it leaves
(`MjxWheelForces.depth`): a follower meets its leader's rut once the leader has been
there, and a vehicle meets its own ruts on a second lap.  Memory: `RutMap.nbytes` per
environment (one number per cell); the cost per step does not grow with the map.  The
map is read from the positions once per step, so the implicit slopes below leave out how
the rut seen changes with the wheel's velocity; the rigid ground stays where it is (the
rut changes the snow's forces and `sinkage`, not MuJoCo's geometry); a map on an
inclined floor or a height field is its projection on the x-y plane.

**Stiff wheel forces.**  Near the self-propelled slip the wheel-spin equation is stiff
(time constant `I v / (r (1 - i)^2 dM_w/di)`, well below MJX's step at low speed), and
at low speed so is the lateral force (cornering stiffness / speed).  `step` therefore
treats the snow forces linearly implicitly: forward-mode derivatives of every wheel's
(drawbar pull, lateral force, -M_w, M_z) w.r.t. its (v_x, v_y, omega) form a damping
matrix `K = sum_k G_k^T D_k G_k` with the wheels' Jacobians (`mjx.jac`; rows along the
heading, the lateral direction, the axle and the normal), and the step solves
`(M + dt (D_joint + K)) qacc = f` before MJX's Euler update (MuJoCo's Euler treats joint
damping implicitly in the same way).  Near rest the slopes are large and far from
symmetric, and M + dt K could turn indefinite (the rover was thrown at 25 m/s under
random controls); each block D_k therefore gets the least added diagonal damping for
which the symmetric part of D_k + W_k / (2 dt) is diagonally dominant (W_k: the wheel
body's own mass and least moment of inertia, part of M), so the symmetric part of the
step's matrix stays >= M / 2.  In steady driving no block needs it.  Only
`integrator="Euler"` (MuJoCo's default) with implicit damping enabled is accepted.

**Gradients.**  Forward mode (`jax.jvp`, `jax.jacfwd`) works through `step` and `rollout`
with any MJX settings and is the cheap choice for a few parameters (snow, controls).
Reverse mode (`jax.grad`) needs `solver_unroll=k` (`step`, `rollout`): MJX's
constraint solver is a `while_loop`, which reverse mode cannot differentiate; k unrolled
Newton iterations can (k = 2 on the shipped rover: a 100-step return's gradient within
5e-8 of central differences, `tests/test_rl_gradients.py`; k = 1 bounced and diverged).

**Many environments on a CPU.**  MJX's own `mjx.step` on the shipped rover (which has
joint damping) hung when vmapped over 256 or more environments on a 2-core CPU (jaxlib
0.10.2: no CPU use, never returned; 128 ran; with `eulerdamp` disabled it ran): its
implicit-damping Euler update factors M + dt D with a batched Cholesky.  `step` does its
own implicit solve (an LU of M + dt (D + K)) and runs 1,024 and 4,096 environments.

**MuJoCo versions.**  `mujoco` 4.0 ships without MJX (`mujoco-mjx` 3.17, the newest on
the package index, runs on it: `from mujoco import mjx`); MuJoCo Warp's JAX interface is
a GPU backend of the same `mjx` API (`impl="warp"`), which this bridge does not use: it
calls the JAX pipeline stage by stage.
"""

from __future__ import annotations

from ._mjx.env import SnowRanges, SnowRoverEnv, State
from ._mjx.rover import (
    load_rover,
    rover_controls,
    rover_model_path,
    rover_spec,
)
from ._mjx.step import MjxWheelForces, Rollout, rollout, step
from ._mjx.wheels import MjxWheels

__all__ = [
    "MjxWheels",
    "MjxWheelForces",
    "Rollout",
    "step",
    "rollout",
    "rover_model_path",
    "rover_spec",
    "load_rover",
    "rover_controls",
    "SnowRoverEnv",
    "SnowRanges",
    "State",
]
