"""The contact rule: how the contact integrals are computed and where the solver starts.

One integrator, `general.py`'s any-terrain rule (`AnyTerrainRule`), takes every wheel,
terrain, stress distribution, shear law, slip angle and force term.  A terrain law may
offer closed forms of its rim integrals (`AbstractTerrain.front_rim_integrals`: Wong's
law); on the front region of a rigid rim running straight the solver then takes the
accelerations they allow, which live in one module, `front_rim.py` (`FrontRimRule`: the
log singularity at a bottomed axle subtracted in closed form, panels placed by the shear
law, a closed-form start).  `front_rim._contact_rule` makes that choice, in one place;
the solver (`equilibrium.py`) and the quadrature's entry (`contact._contact_batch`) take
the rule it returns and never ask which it is.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx

__all__: list[str] = []


class AbstractContactRule(eqx.Module):
    """A contact rule (no fields; static in the compiled programs).

    - `nodes(law, nodes_per_panel)`: the quadrature nodes per panel, `(driving,
      braking)` (`AbstractShearLaw.nodes`).
    - `prepare_slip(slip)`: the slips as the rule's layout needs them.
    - `start(vertical, theta_cap, load, slip, guess, wheel, terrain, shear)`: (over,
      target, lower, upper, s0) of the solver (`start.py`).
    - `contact(contact, slip, terrain, distribution, law, n, braking, vertical_only,
      side, bulldozing, terms, bottomed, moving_rule)`: (W, R, T, M, F_y, M_z) of one
      element (scalar inputs), or W alone with `vertical_only`.
    - `warm_layout`: whether a warm-started solve (a simulation step) compiles both node
      layouts and picks one per step (`contact._layout`).
    """

    warm_layout: ClassVar[bool] = False

    @abc.abstractmethod
    def nodes(self, law, nodes_per_panel) -> tuple:
        raise NotImplementedError

    def prepare_slip(self, slip):
        return slip

    @abc.abstractmethod
    def start(self, vertical, theta_cap, load, slip, guess, wheel, terrain, shear):
        raise NotImplementedError

    @abc.abstractmethod
    def contact(
        self, contact, slip, terrain, distribution, law, n, braking, vertical_only, side,
        bulldozing, terms, bottomed, moving_rule,
    ):  # fmt: skip
        raise NotImplementedError
