"""The contact rule: how the contact integrals are computed and where the solver starts.

One integrator, `general.py`'s any-terrain rule (`AnyTerrainRule`), takes every wheel,
terrain, stress distribution, shear law, slip angle and force term.  A terrain law may
offer closed forms of its rim integrals (`AbstractTerrain.front_rim_integrals`: Wong's
law, a `Rut` on it, layered snow); on the front region of a rigid rim, running straight
or at a slip angle, the solver then takes the accelerations they allow, which live in
one module, `front_rim.py` (`FrontRimRule`: the log singularity at a bottomed axle
subtracted in closed form, panels placed by the shear law, a closed-form start; at a
slip angle `SteeredRimRule`, the same with one node layout in a warm-started solve; on
a law that can fall, `FallingFrontRimRule`, driven batches only).
`front_rim._contact_rule` makes that choice, in one place; the solver
(`equilibrium.py`) and the quadrature's entry (`contact._contact_batch`) take the rule
it returns and never ask which it is.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx

__all__: list[str] = []


class AbstractContactRule(eqx.Module):
    """A contact rule (no fields; static in the compiled programs).

    - `nodes(law, nodes_per_panel, accuracy)`: the quadrature nodes per panel,
      `(driving, braking)`: the law's own table for the rule (`law_nodes`), at the
      simulator accuracy the law's `nodes_simulator` on every panel (`simulator_nodes`),
      or, given `nodes_per_panel`, that many on every panel (`uniform_nodes`).
    - `prepare_slip(slip)`: the slips as the rule's layout needs them.
    - `start(vertical, theta_cap, load, slip, wheel, terrain, distribution, shear,
      braking)`: (over, target, lower, upper, s0, secant) of the solver (`start.py`;
      `braking`: whether the layout has braked elements; `secant`: None for Newton
      steps, or the options of `BracketedSecant`, whose steps then solve);
      `warm_start(vertical, theta_cap, load, slip, guess, wheel, terrain)` the same
      from a previous entry angle `guess`.
    - `contact(contact, slip, terrain, distribution, law, n, running, braking,
      vertical_only, terms, bottomed, moving_rule)`: (W, R, T, M, F_y, M_z) of one
      element (scalar inputs; `running` from `running.py`), or W alone with
      `vertical_only`.
    - `warm_layout`: whether a warm-started solve (a simulation step) compiles both node
      layouts and picks one per step (`contact._layout`).
    """

    warm_layout: ClassVar[bool] = False

    def nodes(self, law, nodes_per_panel: int | None, accuracy: str = "reference") -> tuple:
        # Unbound calls: an equinox bound method costs ~40 us to create (every eager call).
        if nodes_per_panel is not None:
            return type(self).uniform_nodes(self, nodes_per_panel)
        if accuracy == "simulator":
            return type(self).simulator_nodes(self, law)
        return type(self).law_nodes(self, law)

    @abc.abstractmethod
    def law_nodes(self, law) -> tuple:
        raise NotImplementedError

    @abc.abstractmethod
    def uniform_nodes(self, n: int) -> tuple:
        raise NotImplementedError

    @abc.abstractmethod
    def simulator_nodes(self, law) -> tuple:
        raise NotImplementedError

    def prepare_slip(self, slip):
        return slip

    @abc.abstractmethod
    def start(
        self, vertical, theta_cap, load, slip, wheel, terrain, distribution, shear, braking
    ):  # fmt: skip
        raise NotImplementedError

    @abc.abstractmethod
    def warm_start(self, vertical, theta_cap, load, slip, guess, wheel, terrain):
        raise NotImplementedError

    @abc.abstractmethod
    def contact(
        self, contact, slip, terrain, distribution, law, n, running, braking, vertical_only,
        terms, bottomed, moving_rule,
    ):  # fmt: skip
        raise NotImplementedError
