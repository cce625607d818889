"""`ContactModel`: the terrain, stress distribution, shear law, lateral law, quadrature
settings and force terms of your own of the wheel–terrain contact, as one module.

The functions that solve or integrate the wheel's contact take a `ContactModel` in place
of the terrain (`solve_wheel`, `contact_forces`, `wheel_forces`, both simulations,
`snowjax.mjx`, `sweep`, `fit_wheel`, `tire_forces_on_snow`; not the per-point stresses
`normal_stress` / `shear_stress`, nor the plate fits); the separate keywords (`shear=`,
`distribution=`, `lateral=`, `nodes_per_panel=`) keep working for a bare terrain.
"""

from __future__ import annotations

from typing import Any

import equinox as eqx

from .._terrain.base import AbstractTerrain
from .distribution import AbstractStressDistribution, _as_distribution, _is_front
from .lateral import Lateral
from .shear_law import AbstractShearLaw, _shear_law
from .terms import AbstractForceTerm, _check_terms

__all__ = ["ContactModel"]


def _nodes_option(nodes_per_panel):
    if nodes_per_panel is None:
        return None
    if isinstance(nodes_per_panel, bool) or not isinstance(nodes_per_panel, int):
        raise TypeError(f"nodes_per_panel must be None or an int, got {nodes_per_panel!r}")
    if nodes_per_panel < 2:
        raise ValueError(f"nodes_per_panel must be >= 2, got {nodes_per_panel}")
    return nodes_per_panel


class ContactModel(eqx.Module):
    """The wheel–terrain contact: what the wheel runs on and how its stresses are modelled.

    **Fields:**

    - `terrain`: any `snowjax.Terrain` (`WongSnow`, `BekkerSoil`, `ReeceSoil`,
      `LayeredSnow` or a law of your own); its parameters in SI units.
    - `distribution`: the normal-stress distribution around the rim, an
      `AbstractStressDistribution` (default `FrontRegion()`, the thesis's; `None` is
      accepted and means the same), e.g. `WongReece(c1, c2, c3)`.
    - `shear`: the shear law, `JanosiHanamoto()` (default, eq. 4.11), `ThesisSimplified()`
      (4.13) or `NoShear()`, or its name (`"classic"`, `"simplified"`, `"none"`).
    - `lateral`: `Lateral(shear_modulus [m], unit_weight [N/m^3], bulldozing)`, the law
      under a slip angle (default None: `Lateral()` where a slip angle is given; unused
      by the functions that have none).
    - `nodes_per_panel`: Gauss–Legendre nodes per quadrature panel (static int >= 2;
      default None: the accurate defaults of `solve_wheel`); used by the functions that
      have the setting.
    - `terms`: force terms of your own (`AbstractForceTerm`s, one method each: their
      part of W, R, T, M, F_y, M_z at the contact's nodes), added to the built-in ones
      (normal stress, shear, lateral shear, bulldozing, a tyre's flexing); default none.

    A module like the terrain: its array leaves (the terrain's and the distribution's
    parameters, `Lateral`'s moduli) broadcast, vmap and differentiate, e.g.
    `jax.grad(lambda m: solve_wheel(wheel, m, load, slip).drawbar_pull)(model)`.  The
    combination is checked when the model is built (a `ValueError` for a shear law that
    does not apply to the terrain or distribution, e.g. `ThesisSimplified()` on Bekker
    soil).  Pass it where a function takes a terrain and leave that function's
    `shear`, `distribution`, `lateral` and `nodes_per_panel` keywords at their defaults
    (giving both raises `TypeError`).
    """

    terrain: AbstractTerrain
    distribution: AbstractStressDistribution = eqx.field(converter=_as_distribution, default=None)
    shear: AbstractShearLaw = eqx.field(converter=_shear_law, default="classic")
    lateral: Lateral | None = None
    nodes_per_panel: int | None = eqx.field(static=True, converter=_nodes_option, default=None)
    terms: tuple[AbstractForceTerm, ...] = eqx.field(converter=_check_terms, default=())

    def __check_init__(self):
        if not isinstance(self.terrain, AbstractTerrain):
            raise TypeError(
                f"ContactModel.terrain must be a snowjax.Terrain, got {type(self.terrain).__name__}"
            )
        if not isinstance(self.distribution, AbstractStressDistribution):
            raise TypeError(
                "ContactModel.distribution must be None or a snowjax stress distribution, got "
                f"{type(self.distribution).__name__}"
            )
        if self.lateral is not None and not isinstance(self.lateral, Lateral):
            raise TypeError(
                f"ContactModel.lateral must be None or a snowjax.Lateral, got "
                f"{type(self.lateral).__name__}"
            )
        type(self.shear).check(self.shear, self.terrain, self.distribution)


def _unpack_model(
    terrain: Any,
    shear: Any = "classic",
    distribution: Any = None,
    lateral: Any = None,
    nodes_per_panel: Any = None,
) -> tuple[Any, Any, Any, Any, Any, tuple]:
    """(terrain, shear, distribution, lateral, nodes_per_panel, terms) of a
    `ContactModel`, or the arguments unchanged (and no terms) for a bare terrain.
    `TypeError` if a model comes with any of the keywords set (other than to their
    defaults)."""
    if not isinstance(terrain, ContactModel):
        return terrain, shear, distribution, lateral, nodes_per_panel, ()
    given = [
        name
        for name, value, default in (
            ("shear", shear, "classic"),
            ("distribution", distribution, None),
            ("lateral", lateral, None),
            ("nodes_per_panel", nodes_per_panel, None),
        )
        if not (value is default or (isinstance(value, str) and value == default))
    ]
    if given:
        raise TypeError(
            f"{', '.join(given)} given both by the ContactModel and as keyword: set "
            "them in the model (eqx.tree_at or a new ContactModel) and leave the keywords out"
        )
    model = terrain
    # The front region as None, the spelling the functions' defaults use (one compiled
    # program for both spellings).
    distribution = None if _is_front(model.distribution) else model.distribution
    return (
        model.terrain,
        model.shear,
        distribution,
        model.lateral,
        model.nodes_per_panel,
        model.terms,
    )
