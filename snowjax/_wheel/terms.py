"""Force terms: the parts of the contact's stresses and forces that the contact integrator
sums, as diffrax's `MultiTerm` sums the terms of a differential equation.

The integrator (`general.general_contact`) places the quadrature's nodes on the contact,
asks the wheel for the geometry there and the terrain for its normal stress and strength,
and hands all of it to every term as one `ContactNodes`; each term returns its part of the
six contact resultants (`Resultants`: W, R, T, M, F_y, M_z) and the integrator adds them.
The built-in terms are the terrain's stresses (the normal stress and the shear law's shear
stress, straight or combined with the lateral shear under a slip angle: one term, since
they share the normal stress), the sidewall bulldozing of `Lateral(bulldozing=True)` and a
deflecting tyre's flexing resistance.  A term of your own
(`AbstractForceTerm`, one method) goes in `ContactModel(terrain, terms=(...))` and runs
wherever the model does: `solve_wheel`, `wheel_forces`, both simulations, `snowjax.mjx`,
`sweep`, `fit_wheel`.

Sign conventions (the thesis's, section 4.1): W [N] supports the wheel (upwards), R [N]
resists its travel, T [N] pushes it forwards (drawbar pull = T - R), M [N m] is the torque
the ground's stresses take from the axle, F_y [N] acts along +y (the axle, left of the
heading), M_z [N m] turns the wheel about the vertical through its centre.
"""

from __future__ import annotations

import abc
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._leaves import _module_leaves, _parameter_infos
from .._terrain.base import AbstractTerrain
from .geometry import AbstractContact, ContactPoints
from .lateral import _lateral_modulus, bulldozing_pressure
from .shear_law import AbstractShearLaw

__all__ = ["AbstractForceTerm", "ContactNodes", "Resultants"]


class Resultants(eqx.Module):
    """A term's part of the contact resultants (each 0 unless given).

    - `vertical_load`: W [N], upwards on the wheel.
    - `motion_resistance`: R [N], against the travel.
    - `thrust`: T [N], forwards (drawbar pull = T - R).
    - `torque`: M [N m], the torque the stresses take from the axle.
    - `lateral_force`: F_y [N], along the axle (+y, left of the heading).
    - `aligning_torque`: M_z [N m], about the vertical through the wheel centre.
    """

    vertical_load: ArrayLike = 0.0
    motion_resistance: ArrayLike = 0.0
    thrust: ArrayLike = 0.0
    torque: ArrayLike = 0.0
    lateral_force: ArrayLike = 0.0
    aligning_torque: ArrayLike = 0.0

    def __add__(self, other: "Resultants") -> "Resultants":
        return Resultants(*(a + b for a, b in zip(self.astuple(), other.astuple(), strict=True)))

    def astuple(self) -> tuple:
        """(W, R, T, M, F_y, M_z)."""
        return (
            self.vertical_load,
            self.motion_resistance,
            self.thrust,
            self.torque,
            self.lateral_force,
            self.aligning_torque,
        )


class ContactNodes(eqx.Module):
    """What a force term sees: the contact's quadrature nodes (one wheel, one entry angle),
    the wheel's geometry there and the terrain's stresses and strength there.

    - `contact`: the wheel's `AbstractContact` (`contact.wheel`, `contact.entry_angle`
      theta0 [rad], `contact.lowest_sinkage()` [m], ...).
    - `terrain`: the terrain law (`AbstractTerrain`).
    - `slip`: the driving slip i [-]; `tan_slip_angle`: tan(beta) [-] (0 running straight).
    - `theta` [rad], `weight` [rad]: the nodes' rim angles and quadrature weights (the
      integral of f over the contact is `sum(f(theta) * weight)`), with `sin`, `cos` of
      theta.
    - `points`: `ContactPoints` at the nodes: the normal's direction (`normal_cos`,
      `normal_sin`), the length element per r d theta (`element`), the depth [m] and the
      contact's width [m] there, the shortening of the shear displacement.
    - `sigma` [Pa]: the normal stress (the terrain's law through the stress
      distribution); `cohesion` [Pa], `tan_phi` [-], `modulus` K [m]: the terrain's
      strength at the nodes; `shear_displacement` j [m]: eq. (4.10) less the contact's
      shortening.
    """

    contact: AbstractContact
    terrain: AbstractTerrain
    slip: Array
    tan_slip_angle: ArrayLike
    theta: Array
    weight: Array
    sin: Array
    cos: Array
    points: ContactPoints
    sigma: Array
    cohesion: Array
    tan_phi: Array
    modulus: Array
    shear_displacement: Array

    @property
    def radius(self) -> Array:
        """The wheel's undeflected radius r [m]."""
        return self.contact.wheel.diameter / 2

    def area(self) -> Array:
        """The contact area [m^2] each node stands for: weight x element x width x r."""
        return self.weight * self.points.element * self.points.width * self.radius

    def integrate(
        self, normal: ArrayLike = 0.0, shear: ArrayLike = 0.0, lateral: ArrayLike = 0.0
    ) -> Resultants:
        """The resultants of stresses [Pa] at the nodes: `normal` along the contact's
        normal (pressing on the wheel), `shear` along the contact forwards (the shear
        law's sense: thrust), `lateral` along the axle (+y).  A stress left at its
        default 0 costs nothing; W is one sum of the normal and shear stresses' shares
        (one integrand, evaluated once)."""
        area = self.area()
        at = self.points
        zero = jnp.zeros_like(self.contact.entry_angle)

        def total(stress: ArrayLike, share: ArrayLike = 1.0) -> Array:
            given = not (isinstance(stress, (int, float)) and stress == 0)
            return jnp.sum(stress * share * area) if given else zero

        moment = self.contact.moment(normal, shear, self.theta, self.sin)
        return Resultants(
            vertical_load=total(normal * at.normal_cos + shear * at.normal_sin),
            motion_resistance=total(normal, at.normal_sin),
            thrust=total(shear, at.normal_cos),
            torque=total(moment) * self.radius,
            lateral_force=total(lateral),
            aligning_torque=total(lateral, self.sin) * self.radius,
        )


class AbstractForceTerm(eqx.Module):
    """A part of the contact's stresses or forces (abstract): one method, `forces`.

    `forces(nodes: ContactNodes) -> Resultants` returns the term's part of (W, R, T, M,
    F_y, M_z) for one wheel at one entry angle (scalar fields; the integrator vmaps).  A
    stress distributed over the contact is `nodes.integrate(normal=..., shear=...,
    lateral=...)`; a lumped force is a `Resultants` of its own.  Array fields are
    parameters: they broadcast with the batch and carry gradients (`jax.grad` w.r.t. the
    `ContactModel` that holds the term), and are checked like the terrain's (finite, and
    in the range of their `snowjax.parameter` metadata where they have some: a
    `ValueError` naming `terms[k].field` for concrete values, `Status.INVALID_INPUT` under
    `jax.jit`).  SI units.
    """

    @abc.abstractmethod
    def forces(self, nodes: ContactNodes) -> Resultants:
        """This term's part of the contact resultants at `nodes`."""

    def reference(self) -> "AbstractForceTerm":
        """A valid term of this kind, which stands in for invalid batch elements under
        `jax.jit` (their results are NaN either way; a NaN parameter left in would upset
        the batch's shared Newton iteration): every parameter 0 by default; override
        where 0 is not valid."""
        return jax.tree_util.tree_map(jnp.zeros_like, self)


class TerrainStresses(AbstractForceTerm):
    """The terrain's stresses on the contact: the normal stress `nodes.sigma` (its
    pressure–sinkage law through the stress distribution, eqs. 4.5 / 4.14) and the shear
    law's shear stress, `(c + sigma tan phi) g(j)` (eq. 4.11) running straight, or under
    a slip angle (`combined`) the law's combined mobilisation of the rim's and the axle's
    shear displacements (`lateral.py`; `lateral_modulus` K_y [m], None: the terrain's K)
    along the rim and the axle.

    One term for both: they share the normal stress at every node, and summed in one
    integrand XLA evaluates it once (as two terms, measured 10-24 % slower on a
    deflecting tyre and under a slip angle at batch 1,000: each term's sum recomputed it).
    """

    law: AbstractShearLaw
    lateral_modulus: Array | None = None
    combined: bool = eqx.field(static=True, default=False)

    def shares(self, j, j_y, modulus, sigma, theta0, slip, diameter, terrain):
        """(g_x, g_y) [-]: the shares of the strength c + sigma tan phi mobilised along the
        contact and along the axle at shear displacements j [m] along the rim (4.10) and
        j_y [m] along the axle (`lateral.py`; unused running straight, where g_y = 0),
        modulus K [m] and normal stress sigma [Pa], of a wheel of diameter D [m] at
        entry angle theta0 [rad] and slip i [-] on `terrain`."""
        if not self.combined:
            g = self.law.mobilisation(j, modulus, sigma, theta0, slip, diameter, terrain)
            return g, jnp.zeros_like(g)
        k_y = _lateral_modulus(self.lateral_modulus, modulus)
        return self.law.combined_mobilisation(
            j / modulus, j_y / k_y, sigma, theta0, slip, diameter, terrain
        )

    def stresses(self, nodes) -> tuple[Array, ArrayLike, ArrayLike]:
        """(normal, shear along the contact forwards, lateral along the axle) stresses
        [Pa] at the nodes; the shear and lateral stresses are the number 0 where there
        are none (`ContactNodes.integrate` skips them)."""
        if not self.law.mobilises:
            return nodes.sigma, 0.0, 0.0
        travel = nodes.contact.entry_angle - nodes.theta - nodes.points.shortening
        j_y = nodes.radius * (1 - nodes.slip) * travel * nodes.tan_slip_angle
        g_x, g_y = self.shares(
            nodes.shear_displacement, j_y, nodes.modulus, nodes.sigma,
            nodes.contact.entry_angle, nodes.slip, nodes.contact.wheel.diameter, nodes.terrain,
        )  # fmt: skip
        strength = nodes.cohesion + nodes.sigma * nodes.tan_phi
        return nodes.sigma, strength * g_x, strength * g_y if self.combined else 0.0

    def forces(self, nodes):
        normal, shear, lateral = self.stresses(nodes)
        return nodes.integrate(normal=normal, shear=shear, lateral=lateral)


class SidewallBulldozing(AbstractForceTerm):
    """The passive pressure on the side face that moves into the terrain under a slip
    angle (`lateral.py`): side faces below the surface, of the contact's depth, length
    element r cos(theta) d theta, scaled by sin(beta); `unit_weight` gamma [N/m^3]."""

    unit_weight: Array

    def forces(self, nodes):
        wheel = nodes.contact.wheel
        surface = jnp.zeros_like(nodes.contact.entry_angle)
        _, c, tan_phi, _ = nodes.terrain.rim_properties(
            surface, type(wheel).contact_width(wheel, surface)
        )
        q = bulldozing_pressure(nodes.points.depth, c, tan_phi, self.unit_weight)
        tan_beta = nodes.tan_slip_angle
        sin_beta = tan_beta / jnp.sqrt(1 + tan_beta**2)
        r = nodes.radius
        f_b = q * r * nodes.cos * nodes.weight * sin_beta
        return Resultants(lateral_force=jnp.sum(f_b), aligning_torque=jnp.sum(f_b * r * nodes.sin))


class FlexingResistance(AbstractForceTerm):
    """The wheel's own deformation (a deflecting tyre's hysteresis,
    `contact.flexing_resistance()`), part of the motion resistance; 0 on a rim."""

    def forces(self, nodes):
        return Resultants(motion_resistance=nodes.contact.flexing_resistance())


def _total(terms, nodes) -> Resultants:
    """The sum of the terms' resultants at `nodes`."""
    total = Resultants()
    for term in terms:
        total = total + term.forces(nodes)
    return total


def _term_rules(terms) -> list[tuple[str, Any, Any, str]]:
    """Validity of the terms' parameters, as `solve_wheel`'s input rules: (name, value, ok
    mask, allowed range) of every array leaf, from its `snowjax.parameter` metadata where
    it has some, else finite (every rule's value is checked finite)."""
    return [rule for k, term in enumerate(terms) for rule in _one_term_rules(k, term)]


def _one_term_rules(k: int, term) -> list[tuple[str, Any, Any, str]]:
    """`_term_rules` of `terms[k]`."""
    infos = _parameter_infos(term)
    rules = []
    for path, leaf in _module_leaves(term).items():
        info = infos.get(path)
        ok, allowed = (info.ok(leaf), info.allowed()) if info is not None else (True, "real")
        rules.append((f"terms[{k}].{path}", leaf, ok, allowed))
    return rules


def _check_terms(terms) -> tuple:
    """`terms` as a tuple of `AbstractForceTerm`s (`TypeError` otherwise)."""
    if isinstance(terms, AbstractForceTerm):
        terms = (terms,)
    if not isinstance(terms, (tuple, list)) or not all(
        isinstance(t, AbstractForceTerm) for t in terms
    ):
        raise TypeError(
            "terms must be a tuple of snowjax.AbstractForceTerm modules, got "
            f"{type(terms).__name__}"
        )
    return tuple(terms)
