"""`ContactModel`: the terrain, stress distribution, shear law, lateral law, quadrature
settings and force terms of your own of the wheel–terrain contact, as one module.

The functions that solve or integrate the wheel's contact take a `ContactModel` in place
of the terrain (`solve_wheel`, `contact_forces`, `wheel_forces`, both simulations,
`snowjax.mjx`, `sweep`, `fit_wheel`, `tire_forces_on_snow`; not the per-point stresses
`normal_stress` / `shear_stress`, nor the plate fits); a bare terrain stands for
`ContactModel(terrain)`.  Those functions have no `shear=`, `distribution=`, `lateral=`
or `nodes_per_panel=` keywords of their own: given, they raise a `TypeError` naming the
model's spelling.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import numpy as np

from .._terrain.base import AbstractTerrain
from .distribution import AbstractStressDistribution, _as_distribution
from .inputs import _per_module
from .lateral import Lateral
from .shear_law import AbstractShearLaw, _shear_law
from .terms import AbstractForceTerm, _check_terms

__all__ = ["ContactModel"]


def _nodes_option(nodes_per_panel):
    if nodes_per_panel is None:
        return None
    if isinstance(nodes_per_panel, (bool, np.bool_)) or not isinstance(
        nodes_per_panel, (int, np.integer)
    ):
        raise TypeError(f"nodes_per_panel must be None or an int, got {nodes_per_panel!r}")
    if nodes_per_panel < 2:
        raise ValueError(f"nodes_per_panel must be >= 2, got {nodes_per_panel}")
    return int(nodes_per_panel)


ACCURACIES = ("reference", "simulator")


def _accuracy_option(accuracy):
    if not isinstance(accuracy, str):
        raise TypeError(f"accuracy must be one of {ACCURACIES}, got {accuracy!r}")
    if accuracy not in ACCURACIES:
        raise ValueError(f"accuracy must be one of {ACCURACIES}, got {accuracy!r}")
    return accuracy


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
    - `accuracy` (static): `"reference"` (default: every contact integral within 1e-7
      of adaptive quadrature) or `"simulator"`, for vehicle simulations and RL: fewer
      quadrature nodes (the shear law's `nodes_simulator`: 6 per panel of Wong snow's
      closed-form rule, 8 per half-panel of the any-terrain rule (14 on a contact that
      is one panel graded towards its entry), against 10 and 12-16 (20)),
      and a solver tolerance of 1e-6 on ln(W / F_z) instead of 1e-9 (a warm-started
      simulation step then ends after one Newton step), for errors up to ~3e-4 of the
      load and ~1e-8 typically (the worst and median over random cases of every law,
      and the speed it buys, are in the performance guide).
      `nodes_per_panel`, where given, sets the nodes instead.

    A module like the terrain: its array leaves (the terrain's and the distribution's
    parameters, `Lateral`'s moduli) broadcast, vmap and differentiate, e.g.
    `jax.grad(lambda m: solve_wheel(wheel, m, load, slip).drawbar_pull)(model)`.  The
    combination is checked when the model is built (a `ValueError` for a shear law that
    does not apply to the terrain or distribution, e.g. `ThesisSimplified()` on Bekker
    soil).  Pass it where a function takes a terrain (a bare terrain stands for
    `ContactModel(terrain)`), e.g. `solve_wheel(wheel, ContactModel(snow,
    shear="simplified"), load, slip)`.
    """

    terrain: AbstractTerrain
    distribution: AbstractStressDistribution = eqx.field(converter=_as_distribution, default=None)
    shear: AbstractShearLaw = eqx.field(converter=_shear_law, default="classic")
    lateral: Lateral | None = None
    nodes_per_panel: int | None = eqx.field(static=True, converter=_nodes_option, default=None)
    terms: tuple[AbstractForceTerm, ...] = eqx.field(converter=_check_terms, default=())
    accuracy: str = eqx.field(
        static=True, converter=_accuracy_option, default="reference",
        metadata=dict(choices=ACCURACIES),
    )  # fmt: skip

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


def _as_model(terrain: Any, name: str = "terrain") -> ContactModel:
    """The `ContactModel` given, or `ContactModel(terrain)` for a bare terrain (built once
    per terrain object whose leaves are concrete JAX arrays); a `TypeError` naming the
    argument `name` for anything else.  The model is passed down unchanged from here."""
    if isinstance(terrain, ContactModel):
        return terrain
    if not isinstance(terrain, AbstractTerrain):
        raise TypeError(
            f"{name} must be a snowjax terrain (WongSnow, BekkerSoil, ReeceSoil, "
            f"LayeredSnow, or a law of your own) or a snowjax.ContactModel, got "
            f"{type(terrain).__name__}"
        )
    with jax.ensure_compile_time_eval():  # no tracer in the cached model (inside jit)
        return _per_module(_MODELS, terrain, ContactModel, limit=16)


# The default model of a bare terrain (building one costs ~40 us).  The model holds its
# terrain: at most 16 are kept alive by this table.
_MODELS: dict = {}


def _with_terrain(model: ContactModel, terrain: AbstractTerrain) -> ContactModel:
    """`model` with its terrain replaced by `terrain` (e.g. a `Rut` of it): the model's
    other parts kept, unchecked (the solver checks the pair)."""
    return eqx.tree_at(lambda m: m.terrain, model, terrain)


_MODEL_PARTS = {
    name: f"ContactModel(terrain, {name}=...) in place of the terrain"
    for name in ("shear", "distribution", "lateral", "nodes_per_panel")
}


def _renamed(positional: int, hint: str, **spellings: str) -> Callable[[Callable], Callable]:
    """Decorate a public function whose keywords in `spellings` (name -> new spelling)
    were grouped into modules: given, they raise a `TypeError` naming the new spelling;
    more than `positional` positional arguments raise one that ends with `hint`."""

    def decorate(function: Callable) -> Callable:
        name = function.__name__

        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            for key in kwargs.keys() & spellings.keys():
                raise TypeError(f"{name}({key}=...) is now spelled {spellings[key]}")
            if len(args) > positional:
                raise TypeError(
                    f"{name} takes {positional} positional arguments, got {len(args)}: {hint}"
                )
            return function(*args, **kwargs)

        return wrapper

    return decorate


def _takes_model(positional: int, **moved: str) -> Callable[[Callable], Callable]:
    """`_renamed` for a function whose terrain argument may be a `ContactModel`: the
    model's parts (`shear=`, `distribution=`, `lateral=`, `nodes_per_panel=`), once
    keywords or trailing positional arguments of the function (the shear law and nodes
    per panel were once positional), and the keywords in `moved`."""
    hint = (
        "the shear law, stress distribution, lateral law and nodes per panel are set in "
        "the contact model, passed in place of the terrain: ContactModel(terrain, "
        "shear=..., distribution=...)"
    )
    return _renamed(positional, hint, **(_MODEL_PARTS | moved))
