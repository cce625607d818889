"""How the wheel runs through the terrain: straight, or under a slip angle.

The solver and the contact integrator take the wheel's running as one module and never
ask which it is: `Straight()` (the thesis's wheel, `solve_wheel`'s default) or
`SlipAngle(angle, lateral)` (`solve_wheel(slip_angle=...)`: the combined lateral shear
of `lateral.py`, optionally the sidewall bulldozing).  Each says

- which built-in force terms act on its contact (`terms`, `terms.py`),
- where the shear stress rises behind the entry angle, the width of the layer the
  quadrature grades its nodes to (`entry_scale`),
- tan(beta) of its slip angle for the force terms (`ContactNodes.tan_slip_angle`),
- its validity rules and the stand-in for invalid elements (`rules`, `safe`),
- and whether it runs straight (`straight`: any shear law applies; at a slip angle only
  one with a lateral counterpart, `AbstractShearLaw.lateral`).
"""

from __future__ import annotations

import abc
import functools
from typing import Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from .geometry import _shear_displacement_slope
from .lateral import Lateral, _lateral_modulus
from .terms import FlexingResistance, SidewallBulldozing, TerrainStresses

__all__: list[str] = []

# Slip angles are accepted up to (not including) 90 degrees, where the side-slip of a
# wheel that keeps its driving slip i < 1 would need an infinite travel speed.
MAX_SLIP_ANGLE = float(np.pi / 2)


class AbstractRunning(eqx.Module):
    """How the wheel runs (module documentation); per-element fields broadcast with the
    batch."""

    straight: ClassVar[bool]

    @abc.abstractmethod
    def terms(self, law) -> tuple:
        """The built-in force terms of the contact (`terms.py`), for the shear `law`."""

    @abc.abstractmethod
    def entry_scale(self, law, theta0, slip, diameter, terrain, k_surface) -> Array:
        """Width [rad] of the layer behind the entry angle theta0 [rad] over which the
        shear stress rises (`inf` without shear stress); `k_surface` K [m] at the
        surface."""

    @abc.abstractmethod
    def lateral_rate(self, slip, diameter, k_surface) -> ArrayLike:
        """|d(j_y / K_y) / d theta| [1/rad]: how fast the lateral displacement over its
        modulus grows behind the entry angle (0 running straight), which smooths a
        braked wheel's kink where j changes sign over a width of about that rate times
        the distance to the entry (`AbstractShearLaw.braking_panels`)."""

    @abc.abstractmethod
    def tan_slip_angle(self) -> ArrayLike:
        """tan(beta) [-] of the slip angle beta (0 running straight)."""

    def rules(self) -> list[tuple[str, Any, Any, str]]:
        """Validity of the fields, as `solve_wheel`'s input rules (none by default)."""
        return []

    def safe(self, valid) -> AbstractRunning:
        """This running with the elements not `valid` replaced by valid values."""
        del valid
        return self


class Straight(AbstractRunning):
    """Running straight (beta = 0): the normal and shear stresses of the shear law and a
    deflecting tyre's flexing resistance; no lateral force."""

    straight: ClassVar[bool] = True

    def terms(self, law) -> tuple:
        return (TerrainStresses(law), FlexingResistance())

    def entry_scale(self, law, theta0, slip, diameter, terrain, k_surface) -> Array:
        return law.entry_layer(theta0, slip, diameter, terrain, k_surface)

    def lateral_rate(self, slip, diameter, k_surface) -> ArrayLike:
        return 0.0

    def tan_slip_angle(self) -> ArrayLike:
        return 0.0


class SlipAngle(AbstractRunning):
    """Running at slip angle `angle` beta [rad], |beta| < pi/2, with the lateral law
    `lateral` (`Lateral`: K_y [m] or None for the terrain's K, gamma [N/m^3], sidewall
    bulldozing): the combined shear of the rim's and the axle's shear displacements
    (`lateral.py`), and the sidewall bulldozing if `lateral.bulldozing`."""

    angle: ArrayLike
    lateral: Lateral

    straight: ClassVar[bool] = False

    def terms(self, law) -> tuple:
        stresses = TerrainStresses(law, self.lateral.shear_modulus, combined=True)
        bulldozing = (SidewallBulldozing(self.lateral.unit_weight),)
        return (stresses, FlexingResistance()) + (bulldozing if self.lateral.bulldozing else ())

    def entry_scale(self, law, theta0, slip, diameter, terrain, k_surface) -> Array:
        if not law.mobilises:
            return jnp.full_like(theta0, jnp.inf)
        # Width of the layer where the resultant displacement u rises to ~1.
        entry_slope = _shear_displacement_slope(jnp.cos(theta0), slip)
        rate = jnp.hypot(
            diameter / 2 * entry_slope / k_surface, self.lateral_rate(slip, diameter, k_surface)
        )
        return 1 / jnp.maximum(rate, 1e-12 * diameter / 2 / k_surface)

    def lateral_rate(self, slip, diameter, k_surface) -> ArrayLike:
        # j_y = r (1 - i) tan(beta) (theta0 - theta) (`lateral.py`).
        k_y = _lateral_modulus(self.lateral.shear_modulus, k_surface)
        return diameter / 2 * (1 - slip) * jnp.abs(self.tan_slip_angle()) / k_y

    def tan_slip_angle(self) -> ArrayLike:
        return jnp.tan(self.angle)

    def rules(self) -> list[tuple[str, Any, Any, str]]:
        return _angle_rules(self.angle) + Lateral.constraints(self.lateral)

    def safe(self, valid) -> SlipAngle:
        pick = lambda x, ref: jnp.where(valid, x, jnp.asarray(ref, x.dtype))  # noqa: E731
        lateral = self.lateral
        reference = Lateral(
            shear_modulus=jax.tree_util.tree_map(lambda _: 0.02, lateral.shear_modulus),
            unit_weight=0.0,
            bulldozing=lateral.bulldozing,
        )
        lateral = jax.tree_util.tree_map(pick, lateral, reference)
        return SlipAngle(pick(self.angle, 0.0), lateral)


def _angle_rules(angle) -> list[tuple[str, Any, Any, str]]:
    """The slip angle's validity rule (NumPy or JAX values)."""
    return [("slip_angle", angle, abs(angle) < MAX_SLIP_ANGLE, "in (-pi/2, pi/2) rad")]


# One instance (no fields) for the straight-running callers.
_STRAIGHT = Straight()


@functools.lru_cache(maxsize=2)
def _default_lateral(x64: bool) -> Lateral:
    """`Lateral()`, built once per precision mode (building it costs ~30 us per call).
    Its leaves are concrete even when first asked for inside `jax.jit` (a tracer kept in
    the cache would leak into every later call)."""
    del x64  # the cache key: the fields' dtype follows jax_enable_x64
    with jax.ensure_compile_time_eval():
        return Lateral()
