"""The rigid wheel (the thesis's model of a tyre on soft snow, section 4.1)."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._constants import THESIS_DIAMETER, THESIS_TIRE_WIDTH
from .._leaves import _as_float, _check_real_leaves, parameter


class RigidWheel(eqx.Module):
    """A rigid wheel (the thesis's model of a tyre on soft snow, section 4.1).

    **Fields:**

    - `diameter`: D [m].
    - `width`: b [m].
    """

    __check_init__ = _check_real_leaves

    diameter: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("m", "wheel diameter D", lower=0.0, open_lower=True)
    )
    width: Float[Array, "..."] = eqx.field(
        converter=_as_float, metadata=parameter("m", "wheel width b", lower=0.0, open_lower=True)
    )

    @property
    def radius(self) -> Array:
        """r = D / 2 [m]."""
        return self.diameter / 2

    @classmethod
    def thesis_tire(cls) -> "RigidWheel":
        """The 0.736 m tyre of the thesis's FEA studies (section 3.2 and Table 4.1).

        The thesis gives D = 0.736 m but not the width; 0.235 m is the section width of a
        P235/75R15 tyre, whose nominal diameter (0.734 m) matches D.
        """
        return cls(diameter=THESIS_DIAMETER, width=THESIS_TIRE_WIDTH)


# Taylor coefficients of sin(x) / x and cos(x) in powers of x^2, to x^20: on half-angles
# |x| <= pi / 2 the truncation error is below 1e-17 (the sum's rounding, ~3e-16, dominates).
_SIN_TAYLOR = tuple(
    (-1) ** k / float(np.prod(np.arange(2, 2 * k + 2, dtype=float))) for k in range(11)
)
_COS_TAYLOR = tuple(
    (-1) ** k / float(np.prod(np.arange(1, 2 * k + 1, dtype=float))) for k in range(11)
)


def _sincos_half(theta):
    """(sin(theta / 2), cos(theta / 2)) for |theta| <= pi [rad], by Taylor polynomials.

    XLA's general-purpose float64 sine and cosine (argument reduction for any x) cost
    about seven times an exp on CPU; rim angles stay within |theta| <= pi, where two
    short polynomials in the half-angle are exact to rounding (tested against NumPy).
    """
    x = theta / 2
    x2 = x * x
    sin_poly = jnp.zeros_like(x2)
    cos_poly = jnp.zeros_like(x2)
    for cs, cc in zip(_SIN_TAYLOR[::-1], _COS_TAYLOR[::-1]):
        sin_poly = sin_poly * x2 + cs
        cos_poly = cos_poly * x2 + cc
    return x * sin_poly, cos_poly
