"""The rigid wheel (the thesis's model of a tyre on soft snow, section 4.1)."""

from __future__ import annotations

import equinox as eqx
from jaxtyping import Array, Float

from .._constants import THESIS_DIAMETER, THESIS_TIRE_WIDTH
from .._leaves import _as_float, _check_real_leaves


class RigidWheel(eqx.Module):
    """A rigid wheel (the thesis's model of a tyre on soft snow, section 4.1).

    **Fields:**

    - `diameter`: D [m].
    - `width`: b [m].
    """

    __check_init__ = _check_real_leaves

    diameter: Float[Array, "..."] = eqx.field(converter=_as_float)
    width: Float[Array, "..."] = eqx.field(converter=_as_float)

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
