"""Generate notebooks/vehicle_simulation.ipynb (no stored outputs)."""

import sys

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

cells = [
    new_markdown_cell("""# Vehicle simulation on snow: calibration and control through a differentiable ODE

`snowjax.simulate_longitudinal` integrates a vehicle driving straight on shallow snow: the
vehicle speed v, the distance x and every wheel's spin ω, with each wheel's drawbar pull
(eq. 2.10) and resisted torque M_w (eq. 2.12) from the thesis's quasi-static rigid-wheel
equilibrium (Sankapalli 2004, eq. 4.14) at the wheel's current slip (eq. 2.6):

    m dv/dt = Σ_k drawbar pull_k,    I dω_k/dt = T_k(t) − M_w,k.

It runs implicit Euler steps inside `diffrax.diffeqsolve`, starts from rest (the slip is 0/0
there; a documented regularisation fades the contact forces in over `speed_eps` = 0.05 m/s),
and is differentiable end to end. Two uses:

* **(a) calibration**: recover Wong's pressure parameter p_w and tan φ from a noisy speed
  trace;
* **(b) control**: find the torque profile that reaches 5 m/s fastest without exceeding a
  slip limit.

SI units: kg, N, N m, m, s, Pa."""),
    new_code_cell("""import os

import jax

jax.config.update("jax_enable_x64", True)
import diffrax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np
import optimistix as optx

import snowjax as sj

SMALL = os.environ.get("SNOWJAX_NOTEBOOK_SMALL") == "1"  # the test suite runs a tiny version
T1 = 6.0  # [s]
DT = 0.1 if SMALL else 0.05  # [s]
MAX_FIT_STEPS = 40 if SMALL else 100"""),
    new_markdown_cell("""## The vehicle

Two driven thesis tyres (D = 0.736 m, b = 0.235 m) carrying 3.5 kN each (the thesis's
lightest FEA load) on the thesis's fresh snow (Table 4.1, p_w = 85.55 kPa). The torque is a
`TorqueProfile`: piecewise linear between knots, so the trajectory is differentiable with
respect to every knot value."""),
    new_code_cell("""wheel = sj.RigidWheel.thesis_tire()
true_snow = sj.WongSnow.thesis_fresh_snow()
vehicle = sj.Vehicle(mass=2 * 3500.0 / 9.80665, wheel_inertia=1.5, wheel=wheel, num_wheels=2)
knot_times = jnp.linspace(0.0, T1, 6)
print(f"wheel load {float(vehicle.wheel_load):.0f} N")

slips = np.array([0.0, 0.2, 1.0])
st = sj.solve_wheel(wheel, true_snow, vehicle.wheel_load, slips)
for slip, pull, torque in zip(slips, st.drawbar_pull, st.torque):
    print(f"slip {slip:.1f}: drawbar pull {float(pull):6.1f} N, M_w {float(torque):5.1f} N m")
torque_at_limit = float(st.torque[1])  # M_w at slip 0.2, used in (b)"""),
    new_markdown_cell("""## One differentiable program for both problems

Both tasks are least-squares problems over the same vector
u = (ln(p_w / 1 kPa), ln tan φ, six torque knots [N m]) (logarithms keep p_w and tan φ
positive, the range where the wheel model is defined); a `spec` of arrays says which
residual terms count:

* measured speed − simulated speed (weight 1/σ): calibration;
* the speed shortfall below 5 m/s, √dt (5 − v)₊: minimising its sum of squares, ∫(5 − v)₊² dt,
  reaches 5 m/s as early as it can: control;
* the slip above the limit, (i − i_max)₊ with a large weight: the slip limit;
* a prior (u − u₀) per component: stiff on what a task keeps fixed, weak elsewhere.

Keeping one residual function means JAX compiles the simulation and its sensitivities once
for both tasks (a compile of the implicit solver with nested wheel equilibria takes tens of
seconds on a CPU; a run of the 60-step trajectory with its 8 sensitivities a fraction of a
second).

The sensitivities come from forward-mode differentiation through the solver
(`Stepping(adjoint=diffrax.ForwardMode())`, the cheaper mode for 8 parameters). They are handed to
optimistix as a materialised Jacobian through a `jax.custom_jvp`: optimistix's
Levenberg–Marquardt evaluates its initial, zero-filled linearisation once, which a nested
implicit solve (the wheel equilibrium) cannot digest."""),
    new_code_cell("""def snow_of(u):
    # z_w, cohesion and K stay at the thesis values; p_w and tan(phi) come from u.
    return sj.WongSnow(1e3 * jnp.exp(u[0]), true_snow.z_w, true_snow.cohesion,
                       jnp.exp(u[1]), true_snow.shear_modulus)


def simulate(u, adjoint=None):
    torque = sj.TorqueProfile(knot_times, u[2:])
    return sj.simulate_longitudinal(
        vehicle, snow_of(u), torque, T1, DT, stepping=sj.Stepping(adjoint=adjoint)
    )


def speed_and_slip(u):
    traj = simulate(u, adjoint=diffrax.ForwardMode())
    return jnp.concatenate([traj.speed, traj.slip.ravel()])


@jax.custom_jvp
def speed_and_slip_fwd(u):
    return speed_and_slip(u)


@speed_and_slip_fwd.defjvp
def _(primals, tangents):
    (u,), (du,) = primals, tangents
    out, lin = jax.linearize(speed_and_slip, u)
    jacobian = jax.vmap(lin, out_axes=1)(jnp.eye(u.shape[0]))
    return out, jacobian @ du


n_saved = int(round(T1 / DT)) + 1


def residuals(u, spec):
    out = speed_and_slip_fwd(u)
    speed, slip = out[:n_saved], out[n_saved:]
    return jnp.concatenate([
        spec["w_data"] * (speed - spec["v_data"]),
        spec["w_short"] * jnp.sqrt(DT) * jax.nn.relu(spec["v_target"] - speed),
        spec["w_slip"] * jax.nn.relu(slip - spec["slip_max"]),
        spec["w_prior"] * (u - spec["u_prior"]),
    ])


def least_squares(u0, spec):
    # Levenberg–Marquardt; returns the optimum, the outcome, the step count and the
    # Jacobian of the residuals there (from the solver state: no extra compile).
    solver = optx.LevenbergMarquardt(rtol=1e-8, atol=1e-8)
    sol = optx.least_squares(residuals, solver, u0, args=spec, options=dict(jac="fwd"),
                             max_steps=MAX_FIT_STEPS, throw=False)
    jacobian = sol.state.f_info.jac.as_matrix()
    return sol.value, sol.result, int(sol.stats["num_steps"]), jacobian


def spec_of(**kw):
    spec = dict(v_data=jnp.zeros(n_saved), w_data=0.0, w_short=0.0, v_target=0.0,
                w_slip=0.0, slip_max=1.0, w_prior=jnp.zeros(8), u_prior=jnp.zeros(8))
    spec.update(kw)
    return {k: jnp.asarray(v, float) for k, v in spec.items()}"""),
    new_markdown_cell("""## (a) Recover p_w and tan φ from a noisy speed trace

The torque history drives, eases off to 300 N m (the wheels then run near the
self-propelled slip, where the drawbar pull changes fast with slip) and drives again: that
separates the effects of p_w (sinkage, motion resistance) and tan φ (thrust), which under a
steady drive are nearly interchangeable. The "measurement" is the simulated speed with
2 cm/s of Gaussian noise. The fit starts from p_w = 60 kPa, tan φ = 0.12 and holds the
torque knots at their known values (stiff prior)."""),
    new_code_cell("""u_true = jnp.concatenate([jnp.log(jnp.array([true_snow.p_w / 1e3, true_snow.tan_phi])),
                          jnp.array([545.0, 545.0, 300.0, 300.0, 545.0, 545.0])])
truth = simulate(u_true)
assert truth.result == diffrax.RESULTS.successful
sigma = 0.02  # [m/s]
rng = np.random.default_rng(1)
v_measured = truth.speed + sigma * rng.standard_normal(truth.speed.shape)

u_start = u_true.at[0].set(jnp.log(60.0)).at[1].set(jnp.log(0.12))
fixed_knots = jnp.concatenate([jnp.zeros(2), jnp.full(6, 1e3)])  # [1/(N m)]
spec_a = spec_of(v_data=v_measured, w_data=1 / sigma, w_prior=fixed_knots, u_prior=u_true)
u_fit, result, steps, jacobian = least_squares(u_start, spec_a)
print(f"Levenberg–Marquardt: {'converged' if result == optx.RESULTS.successful else result}"
      f" after {steps} steps")

# Gauss–Newton covariance at the optimum (residuals are already divided by sigma); the
# (ln p_w, ln tan phi) block, the knots being pinned by their prior.
J = np.asarray(jacobian)
cov = np.linalg.inv(J.T @ J)[:2, :2]
p_w_fit, tan_phi_fit = 1e3 * float(jnp.exp(u_fit[0])), float(jnp.exp(u_fit[1]))
print(f"recovered p_w = {p_w_fit / 1e3:.2f} ± {p_w_fit * np.sqrt(cov[0, 0]) / 1e3:.2f} kPa "
      f"(true {float(true_snow.p_w) / 1e3:.2f})")
print(f"recovered tan phi = {tan_phi_fit:.4f} ± {tan_phi_fit * np.sqrt(cov[1, 1]):.4f} "
      f"(true {float(true_snow.tan_phi):.4f})")
print(f"correlation {cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1]):+.2f}")
assert abs(p_w_fit / float(true_snow.p_w) - 1) < 0.05
assert abs(tan_phi_fit / float(true_snow.tan_phi) - 1) < 0.15"""),
    new_code_cell("""fitted = simulate(u_fit)
start = simulate(u_start)
fig, ax = plt.subplots(figsize=(6.5, 4))
ax.plot(truth.time, v_measured, ".", ms=4, label="measured (true snow + noise)")
ax.plot(start.time, start.speed, "--", label="start: p_w 60 kPa, tan φ 0.12")
ax.plot(fitted.time, fitted.speed, label="fitted")
ax.set_xlabel("time [s]")
ax.set_ylabel("speed [m/s]")
ax.legend();"""),
    new_markdown_cell("""## (b) Fastest to 5 m/s with slip ≤ 0.2

The baseline holds the torque at M_w(0.2), the torque the snow resists at the slip limit.
Starting from it, Levenberg–Marquardt shapes the six knots to minimise ∫(5 − v)₊² dt with a
stiff penalty on slip above 0.2 (and a weak pull towards the baseline, which keeps the
knots after the target is reached well defined). The snow is the true snow (stiff prior)."""),
    new_code_cell("""slip_max = 0.2
u_base = u_true.at[2:].set(torque_at_limit)
spec_b = spec_of(w_short=1.0, v_target=5.0, w_slip=100.0, slip_max=slip_max,
                 w_prior=jnp.concatenate([jnp.full(2, 1e3), jnp.full(6, 1e-3)]),
                 u_prior=u_base)
u_opt, result, steps, _ = least_squares(u_base, spec_b)
print(f"Levenberg–Marquardt: {'converged' if result == optx.RESULTS.successful else 'step limit'}"
      f" after {steps} steps")


def time_to(traj, v):
    speed, time = np.asarray(traj.speed), np.asarray(traj.time)
    k = int(np.argmax(speed >= v))
    if speed[k] < v:
        return np.inf
    return time[k - 1] + (v - speed[k - 1]) / (speed[k] - speed[k - 1]) * (time[k] - time[k - 1])


baseline, optimised = simulate(u_base), simulate(u_opt)
for name, traj in (("baseline", baseline), ("optimised", optimised)):
    print(f"{name:9s}: time to 5 m/s {time_to(traj, 5.0):.2f} s, "
          f"max slip {float(jnp.max(traj.slip)):.3f}, speed at {T1:g} s "
          f"{float(traj.speed[-1]):.2f} m/s")
print("knots [N m]:", np.round(np.asarray(u_opt[2:]), 1))
assert time_to(optimised, 5.0) <= time_to(baseline, 5.0)
assert float(jnp.max(optimised.slip)) < slip_max + 0.02"""),
    new_code_cell("""fig, axes = plt.subplots(3, 1, figsize=(6.5, 8), sharex=True)
for name, traj in (("baseline", baseline), ("optimised", optimised)):
    axes[0].plot(traj.time, traj.applied_torque[:, 0], label=name)
    axes[1].plot(traj.time, traj.slip[:, 0], label=name)
    axes[2].plot(traj.time, traj.speed, label=name)
axes[1].axhline(slip_max, color="k", lw=0.8, ls=":")
axes[2].axhline(5.0, color="k", lw=0.8, ls=":")
axes[0].set_ylabel("torque per wheel [N m]")
axes[1].set_ylabel("slip [-]")
axes[2].set_ylabel("speed [m/s]")
axes[2].set_xlabel("time [s]")
axes[0].legend()
fig.tight_layout()"""),
    new_markdown_cell("""## Notes

* **Reverse mode.** `jax.grad` through `simulate_longitudinal` uses
  `diffrax.RecursiveCheckpointAdjoint` (the default `Stepping.adjoint`); it gives the same gradients
  as forward mode, compiles about twice as long and is the right choice for many parameters.
* **The model is quasi-static.** Each wheel's forces are the thesis's steady-rolling
  equilibrium at the current slip. At speeds below `Stepping.speed_eps` the regularisation, not
  the thesis, sets the forces: a torque below the self-propelled torque (where the drawbar
  pull vanishes) leaves the vehicle creeping slower than `speed_eps`.
* **Other simulators.** `sj.wheel_forces(v, ω, load, wheel, snow)` is the same force
  function as a pure JAX call, for an MJX or Brax step (see its docstring)."""),
]
nb = new_notebook(
    cells=cells,
    metadata={
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python"},
    },
)
nbformat.write(nb, sys.argv[1])
