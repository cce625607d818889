"""The wheel under a slip angle: lateral shear and sidewall bulldozing.

A wheel steered at slip angle beta to its direction of travel moves over the terrain with
the velocity (V cos beta, -V sin beta) in its own frame (x along the heading, y along the
axle, z up).  The longitudinal slip stays the driving slip of eq. (2.6) on the heading's
component, `i = 1 - V cos(beta) / (omega r)`.

**Shear displacements** over the contact, per unit width, of the rim point at angle theta:

- along the rim, eq. (4.10): `j_x = r [(theta0 - theta) - (1 - i)(sin theta0 - sin theta)]`;
- along the axle: `j_y = r (1 - i)(theta0 - theta) tan(beta)` (the side speed V sin beta
  times the time (theta0 - theta) / omega the point has spent in the contact; Ishigami,
  Miwa, Nagatani & Yoshida 2007, "Terramechanics-based model for steering maneuver of
  planetary exploration rovers on loose soil", *J. Field Robotics* 24(3):233-250, eq. 9).

**Combined shear stress.**  The stress is mobilised by the resultant of the two
displacements, each scaled by its own shear deformation modulus (K_x the terrain's, K_y
`Lateral.shear_modulus`), and points along it:

    u = sqrt((j_x / K_x)^2 + (j_y / K_y)^2)
    (tau_x, tau_y) = (c + sigma tan phi) (1 - exp(-u)) (j_x / K_x, j_y / K_y) / u

so the resultant never exceeds the Mohr–Coulomb strength (2.5), each direction starts with
its own modulus (`tau_y ~ tau_max j_y / K_y` for small displacements), and with beta = 0
it is Janosi–Hanamoto (4.11) along the rim.  This is the resultant-displacement
formulation of the 3-D wheel model of Pavlov & Johnson (robomechanics/3d-terramechanics,
`tau_t.m` / `tau_l.m`: magnitude from `sqrt(j_t^2 + j_l^2) / K`), and of the isotropic
Janosi–Hanamoto law used for combined slip in Chrono's SCM.  Ishigami et al. (2007)
instead apply Janosi–Hanamoto to each direction separately, whose resultant can reach
sqrt(2) times the Mohr–Coulomb strength; it is not used here.

**Sidewall bulldozing** (`Lateral(bulldozing=True)`).  The side face of the wheel that
moves into the terrain pushes a failure wedge (passive earth pressure; Bekker 1960,
Hegedus 1960).  Per unit length of side face at depth h, in the form of Wong (2008),
*Theory of Ground Vehicles*, 4th ed., used by the same 3-D model (`R_b.m`):

    q_b(h) = 1/2 gamma h^2 cot^2(X_c) (1 + cot(X_c) tan(phi) / 2) + 2 c h cot(X_c),
    X_c = 45 deg - phi / 2,

with h(theta) = r (cos theta - cos theta0) the depth of the side face below the surface
and dx = r cos theta d theta the face's length element, over the contact (theta_r ... theta0).
The resultant is scaled by sin(beta), the share of the wheel's travel that is normal to
its side face: it acts along +y for beta > 0, is odd in beta and vanishes smoothly with it
(Ishigami et al. 2007 apply it in full for any beta != 0, a jump at beta = 0; the 3-D
model scales it by |sin beta| sin beta).  c and phi are the terrain's at the surface; the
unit weight gamma [N/m^3] is `Lateral.unit_weight`.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._leaves import _as_float, _check_real_leaves, _parameter_rules, parameter

__all__ = ["Lateral"]


class Lateral(eqx.Module):
    """Lateral terrain response of a wheel under a slip angle (see `solve_wheel`).

    **Fields:**

    - `shear_modulus`: lateral shear deformation modulus K_y [m] of the Janosi–Hanamoto law
      along the axle; `None` (default) uses the terrain's longitudinal modulus K.
    - `unit_weight`: bulk unit weight gamma = rho g of the terrain [N/m^3], used by the
      sidewall bulldozing resistance only (default 0: cohesion term only).
    - `bulldozing`: whether the sidewall bulldozing resistance is added to the lateral
      force and the aligning torque (static; default False).

    **Valid range** (checked like every input: `ValueError` for concrete values,
    `Status.INVALID_INPUT` under jit): `shear_modulus > 0`, `unit_weight >= 0`.
    """

    __check_init__ = _check_real_leaves

    shear_modulus: Float[Array, "..."] | None = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "m",
            "lateral shear deformation modulus K_y (None: the terrain's K)",
            lower=0.0,
            open_lower=True,
            scale=0.01,
        ),
        default=None,
    )
    unit_weight: Float[Array, "..."] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "N/m^3", "unit weight gamma of the terrain (bulldozing)", lower=0.0, scale=1e4
        ),
        default=0.0,
    )
    bulldozing: bool = eqx.field(static=True, default=False)

    def constraints(self) -> list[tuple[str, Array, Array, str]]:
        """Validity per element: (name, value, ok mask, allowed range)."""
        return [
            (f"lateral.{name}", v, ok, allowed) for name, v, ok, allowed in _parameter_rules(self)
        ]


def _lateral_modulus(k_y, k):
    """K_y [m] along the axle: `Lateral.shear_modulus`, or without one (None) the
    terrain's longitudinal K [m] (`k`)."""
    return k if k_y is None else k_y


def combined_mobilisation(a: Array, b: Array) -> tuple[Array, Array]:
    """(a, b) (1 - exp(-u)) / u with u = sqrt(a^2 + b^2): the shares of the Mohr–Coulomb
    strength along x and y for modulus-scaled displacements a = j_x / K_x, b = j_y / K_y.

    Value and gradient are finite everywhere (at u = 0 the factor is 1); with b = 0 it is
    `sign(a) (1 - exp(-|a|))`, the mirrored Janosi–Hanamoto factor.
    """
    q = a * a + b * b
    positive = q > 0
    u = jnp.sqrt(jnp.where(positive, q, 1.0))
    factor = jnp.where(positive, -jnp.expm1(-u) / u, 1.0)
    return a * factor, b * factor


def bulldozing_pressure(depth: Array, cohesion: Array, tan_phi: Array, unit_weight: Array) -> Array:
    """Sidewall bulldozing resistance per unit length of side face q_b(h) [N/m] (Wong 2008).

    **Arguments:** `depth` h [m] (>= 0), `cohesion` c [Pa], `tan_phi` [-], `unit_weight`
    gamma [N/m^3].
    """
    phi = jnp.arctan(tan_phi)
    cot_x = 1 / jnp.tan(jnp.pi / 4 - phi / 2)
    h = jnp.maximum(depth, 0.0)
    return (
        0.5 * unit_weight * h**2 * cot_x**2 * (1 + cot_x * tan_phi / 2) + 2 * cohesion * h * cot_x
    )
