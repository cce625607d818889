"""Normal-stress distributions around the rim of a rigid wheel.

The thesis (chapter 4) integrates only the front of the contact, 0 <= theta <= theta0,
with the normal stress given by the pressure–sinkage law at the rim's sinkage: this is
`distribution=None` in `solve_wheel`.  `WongReece` is the distribution of Wong & Reece
(1967), used by most terramechanics codes: the stress peaks at theta_m and the rear of
the contact, theta_r <= theta <= theta_m, carries the stress of the mirrored front angle.
"""

from __future__ import annotations

import equinox as eqx
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _as_float, _check_real_leaves

__all__ = ["WongReece"]


class WongReece(eqx.Module):
    """Wong & Reece (1967) stress distribution around the rim.

    Wong, J. Y. & Reece, A. R. (1967), "Prediction of rigid wheel performance based on
    the analysis of soil–wheel stresses, Part I", *J. Terramechanics* 4(1):81-98.

    - maximum-stress angle `theta_m = (c1 + c2 i) theta0` (i the slip);
    - exit (rear) angle `theta_r = c3 theta0` (negative behind the vertical);
    - front region theta_m <= theta <= theta0: `sigma(z(theta))`, the terrain's
      pressure–sinkage law at the rim sinkage z(theta) = r (cos theta - cos theta0);
    - rear region theta_r <= theta <= theta_m: sigma at the mirrored angle
      `theta* = theta0 - (theta - theta_r) / (theta_m - theta_r) (theta0 - theta_m)`;
    - shear stress from the shear displacement (4.10) over the whole contact; the
      resultants integrate over theta_r ... theta0.

    **Fields** (array leaves: they broadcast, vmap and differentiate like terrain
    parameters): `c1` [-], `c2` [-], `c3` [-] (default 0: the contact ends under the
    axle).  Wong & Reece give c1 ~ 0.43, c2 ~ 0.32 for sand.

    **Valid range** (checked per element; invalid elements get `Status.INVALID_INPUT`,
    concrete inputs raise `ValueError`): `0 <= c1 + c2 i < 1` and `-1 < c3 <= c1 + c2 i`.
    """

    __check_init__ = _check_real_leaves

    c1: Float[Array, "..."] = eqx.field(converter=_as_float)
    c2: Float[Array, "..."] = eqx.field(converter=_as_float)
    c3: Float[Array, "..."] = eqx.field(converter=_as_float, default=0.0)

    def angle_fractions(self, slip: Float[ArrayLike, "..."]) -> tuple[Array, Array]:
        """(theta_m / theta0, theta_r / theta0) = (c1 + c2 i, c3) at driving slip i [-]."""
        return self.c1 + self.c2 * slip, self.c3 + 0.0 * slip

    def constraints(self, slip) -> list[tuple[str, Array, Array, str]]:
        """Validity per element: (name, value, ok mask, allowed range)."""
        fm, fr = WongReece.angle_fractions(self, slip)
        return [
            ("distribution.c1 + c2 * slip", fm, (fm >= 0) & (fm < 1), "in [0, 1)"),
            (
                "distribution.c3",
                self.c3 + 0.0 * fm,
                (fr > -1) & (fr <= fm),
                "in (-1, c1 + c2 * slip]",
            ),
        ]

    @classmethod
    def reference(cls) -> "WongReece":
        """c1 = 0.43, c2 = 0.32, c3 = 0 (Wong & Reece 1967, sand)."""
        return cls(c1=0.43, c2=0.32, c3=0.0)
