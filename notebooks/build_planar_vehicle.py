"""Generate notebooks/planar_vehicle.ipynb (no stored outputs)."""

import sys

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

cells = [
    new_markdown_cell("""# A four-wheel vehicle that steers on snow: lane change and steering optimisation

`simulate_planar` integrates a four-wheel vehicle in the plane: CG position (X, Y), yaw ψ,
body-frame velocities (u, v), yaw rate r and the four wheel spins. Each wheel's forces come
from the thesis's quasi-static rigid-wheel equilibrium (Sankapalli 2004, eq. 4.14) at the
wheel's driving slip (eq. 2.6) **and slip angle** β: `solve_wheel(..., slip_angle=β)` adds
the lateral force (combined Janosi–Hanamoto shear along the rim and the axle) and the
aligning torque. The front wheels steer with Ackermann geometry; the forces are rotated by
each wheel's steer angle into the body frame. Implicit Euler steps in `diffrax`, start from
rest regularised, differentiable end to end.

Two uses on two snows (the thesis's fresh snow, p_w = 85.55 kPa, and a softer one with the
same ratios, p_w = 50 kPa):

* **a lane change** with the same steering on both snows;
* **steering optimisation**: three steering knots per snow, found by Gauss–Newton steps on
  the forward-mode sensitivities, so that the vehicle ends 2 m to the left, heading
  straight again.

SI units: kg, N, N m, m, s, rad, Pa."""),
    new_code_cell("""import os

import jax

jax.config.update("jax_enable_x64", True)
import diffrax
import jax.numpy as jnp
import numpy as np

import snowjax as sj

SMALL = os.environ.get("SNOWJAX_NOTEBOOK_SMALL") == "1"  # the test suite runs a tiny version
T1 = 4.0  # [s]
DT = 0.1 if SMALL else 0.05  # [s]"""),
    new_markdown_cell("""## The vehicle and one differentiable program

A light vehicle (612 kg, 1.5 kN per wheel) on four thesis tyres (D = 0.736 m, b = 0.235 m),
wheelbase 2 m, track 1.4 m. Steering and torque are piecewise linear between five knots.
`drive` runs one simulation and returns the forward-mode derivatives of the end state
(X, Y, ψ, u) with respect to p_w, tan φ, the five steering knots, the torque and the initial
speed and yaw rate (`Stepping(adjoint=diffrax.ForwardMode())`, the cheap mode for ten
parameters);
`jax.vmap` runs both snows at once, and JAX compiles the program once for everything below."""),
    new_code_cell("""wheel = sj.RigidWheel.thesis_tire()
LOAD = 1500.0  # [N] static load per wheel
WHEELBASE, TRACK = 2.0, 1.4  # [m]
mass = 4 * LOAD / 9.80665  # [kg]
vehicle = sj.PlanarVehicle(
    mass=mass,
    yaw_inertia=mass * (WHEELBASE**2 + TRACK**2) / 12,  # [kg m^2]
    wheel_inertia=1.5,  # [kg m^2]
    wheel=wheel,
    wheelbase=WHEELBASE,
    track_width=TRACK,
)
fresh = sj.WongSnow.thesis_fresh_snow()  # p_w = 85.55 kPa
soft = sj.WongSnow.thesis_fresh_snow(p_w=50e3)  # same ratios, p_w = 50 kPa
snows = jax.tree.map(lambda a, b: jnp.stack([a, b]), fresh, soft)  # leaves of shape (2,)
KNOTS = jnp.linspace(0.0, T1, 5)  # steering and torque knot times [s]


def drive(snow, x):
    \"\"\"One run and the forward-mode derivatives of its end state.

    x = (steering knots delta_0..4 [rad], torque per wheel [N m], u(0) [m/s], r(0) [rad/s]).
    Returns the trajectory and d(X, Y, yaw, u at T1) / d(p_w, tan phi, x), shape (4, 10).
    \"\"\"

    def end_state(z):
        trial = sj.WongSnow(z[0], snow.z_w, snow.cohesion, z[1], snow.shear_modulus)
        traj = sj.simulate_planar(
            vehicle,
            trial,
            sj.SteeringProfile(KNOTS, z[2:7]),
            sj.TorqueProfile(KNOTS, jnp.full(5, z[7])),
            T1,
            DT,
            initial=sj.InitialState(speed=z[8], yaw_rate=z[9]),
            stepping=sj.Stepping(adjoint=diffrax.ForwardMode()),
        )
        return jnp.stack([traj.x[-1], traj.y[-1], traj.yaw[-1], traj.speed[-1]]), traj

    z = jnp.concatenate([jnp.stack([snow.p_w, snow.tan_phi]), x])
    jacobian, traj = jax.jacfwd(end_state, has_aux=True)(z)
    return traj, jacobian


drive_batch = jax.jit(jax.vmap(drive))  # one snow and one x per row


def self_propelled_torque(snow):
    # M_w at the slip where a straight-running wheel's drawbar pull vanishes: the torque
    # that holds a straight vehicle's speed.  One solve over a slip grid, interpolated.
    slips = np.linspace(-0.3, 0.1, 81)
    st = sj.solve_wheel(wheel, snow, LOAD, slips)
    pull, torque = np.asarray(st.drawbar_pull), np.asarray(st.torque)
    k = int(np.flatnonzero(np.diff(np.sign(pull)) > 0)[0])
    w = pull[k] / (pull[k] - pull[k + 1])
    return float(torque[k] + w * (torque[k + 1] - torque[k]))"""),
    new_markdown_cell("""## A lane change on two snows

Both vehicles start at 5 m/s driving straight, with each snow's self-propelled torque
(the torque at which a straight-running wheel's drawbar pull vanishes), and get the same
steering: left, back through zero, right, back to zero."""),
    new_code_cell("""u0 = 5.0  # [m/s]
torques = [self_propelled_torque(fresh), self_propelled_torque(soft)]
lane_change = jnp.array([0.0, 0.06, 0.0, -0.06, 0.0])  # [rad] at the knots
X0 = jnp.stack([jnp.concatenate([lane_change, jnp.array([t, u0, 0.0])]) for t in torques])
traj, jac = drive_batch(snows, X0)
assert np.all(traj.result == diffrax.RESULTS.successful)
for k, name in enumerate(["fresh (85.55 kPa)", "soft (50 kPa)"]):
    print(f"{name}: torque {torques[k]:.1f} N m, end: X {float(traj.x[k, -1]):.2f} m, "
          f"Y {float(traj.y[k, -1]):.3f} m, heading {np.degrees(float(traj.yaw[k, -1])):.2f} deg, "
          f"max |slip angle| {np.degrees(float(jnp.max(jnp.abs(traj.slip_angle[k])))):.2f} deg")"""),
    new_code_cell("""import matplotlib.pyplot as plt

fig, axes = plt.subplots(1, 3, figsize=(12, 3.5))
for k, name in enumerate(["fresh", "soft"]):
    axes[0].plot(traj.x[k], traj.y[k], label=name)
    axes[1].plot(traj.time[k], np.degrees(traj.yaw_rate[k]), label=name)
    axes[2].plot(traj.time[k], np.degrees(traj.slip_angle[k, :, 2]), label=f"{name}, rear left")
axes[0].set(xlabel="X [m]", ylabel="Y [m]", title="CG path")
axes[1].set(xlabel="time [s]", ylabel="yaw rate [deg/s]")
axes[2].set(xlabel="time [s]", ylabel="slip angle [deg]")
axes[0].legend()
axes[2].legend()
fig.tight_layout()"""),
    new_markdown_cell("""## Steering to a 2 m lane offset

Unknowns: the three inner steering knots of each snow (the first and last stay 0).
Residuals: the end offset Y(T1) − 2 m and the end heading ψ(T1) (weighted by 5 m/rad).
Each Gauss–Newton step takes the minimum-norm solution of the linearised residuals, using
the sensitivities `drive_batch` already returns: one batched run per step for both snows."""),
    new_code_cell("""TARGET = 2.0  # [m]
HEADING_WEIGHT = 5.0  # [m/rad]
STEERED = slice(3, 6)  # columns of the Jacobian for delta_1..3 (after p_w, tan phi, delta_0)
steps = 3 if SMALL else 8

X = X0
history = []
for step in range(steps + 1):
    traj, jac = drive_batch(snows, X)
    residual = jnp.stack([traj.y[:, -1] - TARGET, HEADING_WEIGHT * traj.yaw[:, -1]], axis=1)
    history.append(np.asarray(jnp.linalg.norm(residual, axis=1)))
    if step == steps:
        break
    J = jnp.stack([jac[:, 1, STEERED], HEADING_WEIGHT * jac[:, 2, STEERED]], axis=1)  # (2, 2, 3)
    delta = jax.vmap(lambda a, b: jnp.linalg.lstsq(a, -b)[0])(J, residual)
    X = X.at[:, 1:4].add(delta)
history = np.array(history)
for k, name in enumerate(["fresh", "soft"]):
    knots = ", ".join(f"{v:.2f}" for v in np.degrees(np.asarray(X[k, :5])))
    print(f"{name}: knots ({knots}) deg, "
          f"end offset {float(traj.y[k, -1]):.4f} m, heading {np.degrees(float(traj.yaw[k, -1])):.3f} deg")
print("residual norm per step [m]:", np.round(history, 4).tolist())
assert np.all(history[-1] < 0.05 * history[0])"""),
    new_code_cell("""fig, axes = plt.subplots(1, 3, figsize=(12, 3.5))
for k, name in enumerate(["fresh", "soft"]):
    line, = axes[0].plot(traj.x[k], traj.y[k], label=f"{name}, optimised")
    axes[1].plot(traj.time[k], np.degrees(traj.steer_angle[k, :, 0]), color=line.get_color(),
                 label=f"{name}, front left")
    axes[2].semilogy(history[:, k], "o-", color=line.get_color(), label=name)
axes[0].axhline(TARGET, color="k", lw=0.8, ls=":")
axes[0].set(xlabel="X [m]", ylabel="Y [m]", title="CG path")
axes[1].set(xlabel="time [s]", ylabel="steer angle [deg]")
axes[2].set(xlabel="Gauss–Newton step", ylabel="residual norm [m]")
for ax in axes:
    ax.legend()
fig.tight_layout()"""),
    new_markdown_cell("""## Notes

* **Model limits.** Static wheel loads (no load transfer), no aerodynamic drag, a
  quasi-static contact. Below `speed_eps` (0.05 m/s) the regularisation, not the thesis,
  sets the forces (see `snowjax.planar_wheel_kinematics`).
* **Slip angle in the wheel model.** With a slip angle `solve_wheel` uses its any-terrain
  quadrature, which at β = 0 agrees with the straight-running results within 1e-7: driving
  straight, `simulate_planar` reproduces `simulate_longitudinal` (tested).
* **Reverse mode.** `jax.grad` through `simulate_planar` works with the default
  `diffrax.RecursiveCheckpointAdjoint`; for a handful of parameters forward mode, as here,
  compiles and runs faster."""),
]

nb = new_notebook(
    cells=cells,
    metadata={
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python"},
    },
)
nbformat.write(nb, sys.argv[1])
