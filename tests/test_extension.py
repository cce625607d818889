"""A terrain law and a stress distribution defined outside the package, one class each.

`HyperbolicSnow` (sigma = k z / (1 - z / h), a compressible layer of depth h on a hard
base) and `LinearRear` (the contact continues behind the axle to theta_r = -a theta0, the
stress falling from the axle's to zero at the exit) are written here, against the public
API only (`snowjax.AbstractTerrain`, `snowjax.AbstractStressDistribution`,
`snowjax.parameter`, `snowjax.as_float`), and then run through `solve_wheel` (checked
against the independent SciPy reference of `tests/reference_terrain.py`), `jax.grad`
(against central differences), `fit_wheel` and `sweep`, with no other edit anywhere:
the recipe of the extending guide's "Adding a terrain law, a stress distribution or a shear
law".  A shear law (`KondnerShear`) likewise, through both contact rules.
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jaxtyping import Array, Float

import snowjax as sj

from . import reference_terrain as ref

# The reference's quad warns about round-off at its 1e-13 target on a few subintervals.
pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")


class HyperbolicSnow(sj.AbstractTerrain):
    """sigma = k z / (1 - z / h) [Pa]: linear at first, diverging at the base z = h."""

    modulus: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("Pa/m", "initial slope k", lower=0.0, open_lower=True),
    )
    layer_depth: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("m", "depth h of the base", lower=0.0, open_lower=True),
    )
    cohesion: Float[Array, "..."] = eqx.field(
        converter=sj.as_float, metadata=sj.parameter("Pa", "cohesion c", lower=0.0)
    )
    tan_phi: Float[Array, "..."] = eqx.field(
        converter=sj.as_float, metadata=sj.parameter("-", "tan phi", lower=0.0)
    )
    shear_modulus: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("m", "shear modulus K", lower=0.0, open_lower=True),
    )

    def pressure(self, sinkage, width):
        z = jnp.clip(jnp.asarray(sinkage), 0.0, None)
        below = z < self.layer_depth
        safe = jnp.where(below, z, 0.0)
        return jnp.where(below, self.modulus * safe / (1 - safe / self.layer_depth), jnp.inf)

    @property
    def depth(self):
        return self.layer_depth

    @classmethod
    def reference(cls):
        return cls(4e5, 0.25, 2e3, 0.2, 0.01)


class LinearRear(sj.AbstractStressDistribution):
    """Front region as in the thesis; behind the axle, down to theta_r = -a theta0, the
    stress of the front angle -theta / a (the axle's stress at theta = 0, none at the exit)."""

    rear: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("-", "theta_r / theta0, negated", lower=0.0, open_lower=True),
    )

    def exit_angle(self, entry_angle, slip):
        return -self.rear * entry_angle

    def breakpoints(self, entry_angle, slip):
        return (jnp.zeros_like(entry_angle),)

    def stress_angle(self, theta, entry_angle, slip):
        return jnp.where(theta >= 0, theta, -theta / self.rear)

    def rear_angles(self, angle, entry_angle, slip):
        return (-self.rear * angle,)

    def constraints(self, slip):
        ok = (self.rear > 0) & (self.rear < 1)
        return [("distribution.rear", self.rear, ok, "in (0, 1)")]

    @classmethod
    def reference(cls):
        return cls(0.3)


WHEEL = sj.RigidWheel(0.736, 0.235)
SNOW = HyperbolicSnow(4e5, 0.25, 2e3, 0.2, 0.01)
REAR = LinearRear(0.3)
N = 4
LOADS = np.array([1500.0, 3000.0, 1500.0, 3000.0])  # [N]
SLIPS = np.array([0.1, 0.4, -0.2, 0.25])


def _full(tree):
    """Every leaf as N elements: all solves of this module share one compiled program
    per distribution."""
    return jax.tree_util.tree_map(lambda x: jnp.full(N, x), tree)


def _solve(snow=SNOW, distribution=REAR, loads=LOADS):
    return sj.solve_wheel(_full(WHEEL), _full(snow), loads, SLIPS, distribution=distribution)


@pytest.mark.parametrize("distribution", [None, REAR], ids=["front-region", "linear-rear"])
def test_solve_wheel_matches_the_scipy_reference(distribution):
    law = lambda z, b: 4e5 * max(z, 0.0) / (1 - max(z, 0.0) / 0.25)  # noqa: E731
    dist = None if distribution is None else _full(distribution)
    st = _solve(distribution=dist)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED), st.status
    for k in range(N):
        fr = 0.0 if distribution is None else -0.3
        theta0, (w, r, t, m) = ref.solve(
            LOADS[k], SLIPS[k], 0.736, 0.235, law, 2e3, 0.2, 0.01, 0.0, fr, depth=0.25
        )
        assert float(st.entry_angle[k]) == pytest.approx(theta0, rel=1e-7)
        assert float(st.drawbar_pull[k]) == pytest.approx(t - r, rel=1e-6, abs=1e-7 * LOADS[k])
        assert float(st.torque[k]) == pytest.approx(m, rel=1e-7)


def test_the_new_distribution_is_wong_reece_with_its_peak_at_the_axle():
    """LinearRear(a) is WongReece(c1 = 0, c2 = 0, c3 = -a): same equilibrium to rounding."""
    a = _solve(distribution=_full(REAR))
    b = _solve(distribution=_full(sj.WongReece(0.0, 0.0, -0.3)))
    np.testing.assert_allclose(a.entry_angle, b.entry_angle, rtol=1e-12)
    np.testing.assert_allclose(a.drawbar_pull, b.drawbar_pull, rtol=1e-10, atol=1e-8)


@pytest.mark.slow  # gradients through both classes (make test-slow)
def test_gradients_through_both_new_classes_match_central_differences():
    def out(modulus, rear):
        snow = eqx.tree_at(lambda s: s.modulus, _full(SNOW), jnp.full(N, modulus))
        st = _solve(snow, _full(LinearRear(rear)))
        return jnp.stack([st.sinkage, st.drawbar_pull / 1e3])

    x0 = (4e5, 0.3)
    grads = jax.jacfwd(out, argnums=(0, 1))(*x0)
    for k, h in enumerate((40.0, 1e-5)):

        def f(v, k=k):
            args = list(x0)
            args[k] = v
            return np.asarray(out(*args))

        fd = (f(x0[k] + h) - f(x0[k] - h)) / (2 * h)
        np.testing.assert_allclose(grads[k], fd, rtol=1e-5, atol=1e-9 * np.max(np.abs(fd)))
    g = jax.grad(lambda m: jnp.sum(out(m, 0.3)[1]))(4e5)  # reverse mode
    assert float(g) == pytest.approx(float(jnp.sum(grads[0][1])), rel=1e-8)


def test_bad_values_are_named_with_the_unit_and_range_of_the_field():
    with pytest.raises(ValueError, match=r"terrain\.modulus must be finite and > 0 Pa/m"):
        sj.solve_wheel(WHEEL, HyperbolicSnow(-1.0, 0.25, 2e3, 0.2, 0.01), 1000.0, 0.1)
    with pytest.raises(ValueError, match=r"distribution\.rear must be finite and in \(0, 1\)"):
        sj.solve_wheel(WHEEL, SNOW, 1000.0, 0.1, distribution=LinearRear(1.5))


@pytest.mark.slow  # a fit's own compiles (make test-slow)
def test_fit_wheel_recovers_both_new_classes_parameters():
    st = _solve(distribution=_full(REAR))
    start = HyperbolicSnow(3e5, 0.25, 2e3, 0.2, 0.01)
    assert sj.fit_parameter_names(start, LinearRear(0.5)) == (
        "modulus", "layer_depth", "cohesion", "tan_phi", "shear_modulus", "rear"
    )  # fmt: skip
    result = sj.fit_wheel(
        WHEEL,
        start,
        LOADS,
        SLIPS,
        fit=("modulus", "rear"),
        sinkage=np.asarray(st.sinkage),
        drawbar_pull=np.asarray(st.drawbar_pull),
        distribution=LinearRear(0.5),
    )
    assert result.params["modulus"] == pytest.approx(4e5, rel=1e-6)
    assert result.params["rear"] == pytest.approx(0.3, rel=1e-6)
    by_model = sj.fit_wheel(
        WHEEL,
        sj.ContactModel(start, LinearRear(0.5)),
        LOADS,
        SLIPS,
        fit=("modulus", "rear"),
        sinkage=np.asarray(st.sinkage),
        drawbar_pull=np.asarray(st.drawbar_pull),
    )
    assert by_model.params == result.params
    # From the fields' metadata: units, and log space for the two positive parameters.
    assert result.units == {"modulus": "Pa/m", "rear": "-"}
    assert result.info["transforms"] == {"modulus": "log", "rear": "log"}


@pytest.mark.slow  # a sweep's own compiles (make test-slow)
def test_sweep_rows_equal_solve_wheel(tmp_path):
    snows = [SNOW, eqx.tree_at(lambda s: s.modulus, SNOW, 5e5)]
    result = sj.sweep(
        WHEEL,
        snows,
        np.array([1500.0, 3000.0]),
        np.array([0.1, -0.2]),
        distribution=REAR,
        out=tmp_path / "sweep",
        progress=False,
        formats=("npz",),
    )
    rows = dict(np.load(result.files["npz"]))
    assert {"modulus", "layer_depth"} <= set(rows)  # columns of the leaves that vary
    assert len(rows["load"]) == 8
    st = sj.solve_wheel(
        WHEEL,
        HyperbolicSnow(rows["modulus"], 0.25, 2e3, 0.2, 0.01),
        rows["load"],
        rows["slip"],
        distribution=REAR,
    )
    np.testing.assert_allclose(rows["sinkage"], st.sinkage, rtol=1e-12)
    np.testing.assert_allclose(rows["drawbar_pull"], st.drawbar_pull, rtol=1e-10, atol=1e-9)


def test_shear_laws_are_modules_or_their_names():
    """`shear=` takes a shear-law module or its name, with the same result; a law says
    what it needs (the thesis's simplified law: Wong snow on the front region)."""
    by_name = _solve(distribution=_full(REAR))
    by_module = sj.solve_wheel(
        _full(WHEEL), _full(SNOW), LOADS, SLIPS, sj.JanosiHanamoto(), distribution=_full(REAR)
    )
    np.testing.assert_array_equal(by_name.drawbar_pull, by_module.drawbar_pull)
    assert sj.NoShear().name == "none" and sj.ThesisSimplified().name == "simplified"
    with pytest.raises(ValueError, match="needs a WongSnow terrain"):
        sj.solve_wheel(WHEEL, SNOW, 1000.0, 0.1, sj.ThesisSimplified())
    with pytest.raises(ValueError, match="shear must be one of"):
        sj.solve_wheel(WHEEL, SNOW, 1000.0, 0.1, "wet")
    fresh = sj.WongSnow.thesis_fresh_snow()
    thesis = sj.solve_wheel(WHEEL, fresh, 3000.0, 0.2, sj.ThesisSimplified())
    assert float(thesis.drawbar_pull) == float(
        sj.solve_wheel(WHEEL, fresh, 3000.0, 0.2, "simplified").drawbar_pull
    )


def test_a_contact_model_bundles_terrain_distribution_and_shear_law():
    """`ContactModel` in place of the terrain: the same results as the separate keywords,
    gradients w.r.t. its leaves, the combination checked when it is built, and a
    keyword given twice refused."""
    model = sj.ContactModel(_full(SNOW), _full(REAR), sj.JanosiHanamoto())
    by_keywords = _solve(distribution=_full(REAR))
    by_model = sj.solve_wheel(_full(WHEEL), model, LOADS, SLIPS)
    for field in ("entry_angle", "drawbar_pull", "torque", "status"):
        np.testing.assert_array_equal(getattr(by_model, field), getattr(by_keywords, field))
    forces = sj.contact_forces(WHEEL, model, by_model.entry_angle, SLIPS)
    np.testing.assert_array_equal(
        forces.vertical_load,
        sj.contact_forces(WHEEL, _full(SNOW), by_model.entry_angle, SLIPS, distribution=REAR)
        .vertical_load,
    )  # fmt: skip
    np.testing.assert_allclose(forces.vertical_load, LOADS, rtol=1e-8)

    def pull(model):
        return jnp.sum(sj.solve_wheel(_full(WHEEL), model, LOADS, SLIPS).drawbar_pull)

    def pull_by_keywords(snow, rear):
        return jnp.sum(_solve(snow, rear).drawbar_pull)

    grad = jax.grad(pull)(model)
    expected = jax.grad(pull_by_keywords, argnums=(0, 1))(_full(SNOW), _full(REAR))
    np.testing.assert_allclose(grad.terrain.modulus, expected[0].modulus, rtol=1e-12)
    np.testing.assert_allclose(grad.distribution.rear, expected[1].rear, rtol=1e-12)
    assert np.all(np.asarray(grad.distribution.rear) != 0)

    # Spellings: None is the front region, a name is its law; defaults classic, front.
    default = sj.ContactModel(SNOW, None, "none")
    assert isinstance(default.distribution, sj.FrontRegion)
    assert isinstance(default.shear, sj.NoShear)
    assert isinstance(sj.ContactModel(SNOW).shear, sj.JanosiHanamoto)
    with pytest.raises(ValueError, match="needs a WongSnow terrain"):
        sj.ContactModel(SNOW, shear=sj.ThesisSimplified())
    with pytest.raises(TypeError, match="ContactModel.terrain must be a snowjax.Terrain"):
        sj.ContactModel(REAR)
    with pytest.raises(TypeError, match="shear, nodes_per_panel given both"):
        sj.solve_wheel(WHEEL, model, 1000.0, 0.1, "none", nodes_per_panel=12)
    with pytest.raises(ValueError, match="nodes_per_panel must be >= 2"):
        sj.ContactModel(SNOW, nodes_per_panel=1)


class KondnerShear(sj.AbstractShearLaw):
    """Kondner's hyperbolic mobilisation, g = (j / K) / (1 + |j / K|): the shear stress
    rises like Janosi–Hanamoto's at small displacement and approaches the strength as
    1 / j instead of exponentially (Kondner 1963, "Hyperbolic stress-strain response:
    cohesive soils", J. Soil Mech. Found. Div. 89(SM1):115-143)."""

    name: ClassVar[str] = "kondner"
    nodes_closed_form: ClassVar = (12, (12, 12, 12, 12))
    nodes_any_terrain: ClassVar = (12, 16)

    def check(self, terrain, distribution) -> None:
        """Applies everywhere."""

    def mobilisation(self, j, modulus, sigma, theta0, slip, diameter, terrain):
        x = j / modulus
        return x / (1 + jnp.abs(x))

    def braking_panels(self, theta0, slip, diameter, terrain, z0_rel, entry_scale):
        # The sign change is that of j, as for Janosi–Hanamoto.
        return sj.JanosiHanamoto.braking_panels(
            self, theta0, slip, diameter, terrain, z0_rel, entry_scale
        )

    def axle_mobilisation(self, theta0, slip, diameter, terrain, z0_rel):
        r = diameter / 2
        x = r * (theta0 - (1 - slip) * jnp.sin(theta0)) / terrain.shear_modulus
        # dg/dtheta = g'(x) dx/dtheta, dj/dtheta = -r i at theta = 0.
        return x / (1 + jnp.abs(x)), -r * slip / terrain.shear_modulus / (1 + jnp.abs(x)) ** 2


def test_a_shear_law_defined_outside_the_package_on_both_contact_rules():
    """`KondnerShear` (one class, public API only) through `solve_wheel` on the new
    terrain (the any-terrain rule) and `contact_forces` on Wong snow's front region (the
    closed-form rule, whose singularity subtraction uses the law's axle values), against
    the SciPy reference with the same mobilisation; driving and braking."""
    law = KondnerShear()
    kondner = lambda x: x / (1 + abs(x))  # noqa: E731
    st = sj.solve_wheel(_full(WHEEL), _full(SNOW), LOADS, SLIPS, law)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED), st.status
    hyperbolic = lambda z, b: 4e5 * max(z, 0.0) / (1 - max(z, 0.0) / 0.25)  # noqa: E731
    for k in range(N):
        theta0, (w, r, t, m) = ref.solve(
            LOADS[k], SLIPS[k], 0.736, 0.235, hyperbolic, 2e3, 0.2, 0.01,
            depth=0.25, mobilisation=kondner,
        )  # fmt: skip
        assert float(st.entry_angle[k]) == pytest.approx(theta0, rel=1e-7)
        assert float(st.drawbar_pull[k]) == pytest.approx(t - r, rel=1e-6, abs=1e-7 * LOADS[k])
    snow = sj.WongSnow(2e4, 0.2, 1e3, 0.3, 0.02)
    theta0 = np.array([0.3, 0.5, 0.3, 0.5])
    forces = sj.contact_forces(WHEEL, snow, theta0, SLIPS, law)
    wong = lambda z, b: -2e4 * math.log1p(-z / 0.2)  # noqa: E731
    for k in range(N):
        exp = ref.contact(
            theta0[k], SLIPS[k], 0.736, 0.235, wong, 1e3, 0.3, 0.02, mobilisation=kondner
        )
        got = [forces.vertical_load[k], forces.motion_resistance[k], forces.thrust[k]]
        np.testing.assert_allclose(got, exp[:3], rtol=1e-7, atol=1e-7 * exp[0])
