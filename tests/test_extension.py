"""A terrain law, a stress distribution and a shear law defined outside the package, one
class each.

`HyperbolicSnow` (sigma = k z / (1 - z / h), a compressible layer of depth h on a hard
base) and `LinearRear` (the contact continues behind the axle to theta_r = -a theta0, the
stress falling from the axle's to zero at the exit) are written here, against the public
API only (`snowjax.AbstractTerrain`, `snowjax.AbstractStressDistribution`,
`snowjax.parameter`, `snowjax.as_float`), and then run through `solve_wheel` (checked
against the independent SciPy reference of `tests/reference_terrain.py`), `jax.grad`
(against central differences), `fit_wheel` and `sweep`, with no other edit anywhere:
the recipe of the extending guide's "Adding a terrain law, a stress distribution, a shear
law or a wheel".  The shear law (`KondnerShear`, one method) likewise: on both contact rules, and,
driving and braking, through `solve_wheel`, `jax.grad`, `fit_wheel`, `sweep`,
`simulate_longitudinal`, `simulate_planar` and `snowjax.mjx.step`, against SciPy
references (`tests/reference_terrain.py`, and `_reference_contact` here for a slip
angle).  A wheel whose contact widens with depth (`BulgingWheel`, one method) and a force
term (`FrontDrag`, one method) go through the same workflows.
"""

from __future__ import annotations

import json
import math
import os

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
    return sj.solve_wheel(_full(WHEEL), sj.ContactModel(_full(snow), distribution), loads, SLIPS)


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
        sj.solve_wheel(WHEEL, sj.ContactModel(SNOW, LinearRear(1.5)), 1000.0, 0.1)


@pytest.mark.slow  # a fit's own compiles (make test-slow)
def test_fit_wheel_recovers_both_new_classes_parameters():
    st = _solve(distribution=_full(REAR))
    start = HyperbolicSnow(3e5, 0.25, 2e3, 0.2, 0.01)
    assert sj.fit_parameter_names(start, LinearRear(0.5)) == (
        "modulus", "layer_depth", "cohesion", "tan_phi", "shear_modulus", "rear"
    )  # fmt: skip
    result = sj.fit_wheel(
        WHEEL,
        sj.ContactModel(start, LinearRear(0.5)),
        LOADS,
        SLIPS,
        {"sinkage": np.asarray(st.sinkage), "drawbar_pull": np.asarray(st.drawbar_pull)},
        fit=("modulus", "rear"),
    )
    assert result.params["modulus"] == pytest.approx(4e5, rel=1e-6)
    assert result.params["rear"] == pytest.approx(0.3, rel=1e-6)
    by_model = sj.fit_wheel(
        WHEEL,
        sj.ContactModel(start, LinearRear(0.5)),
        LOADS,
        SLIPS,
        {"sinkage": np.asarray(st.sinkage), "drawbar_pull": np.asarray(st.drawbar_pull)},
        fit=("modulus", "rear"),
    )
    assert by_model.params == result.params
    # From the fields' metadata: units, and log space for the two positive parameters.
    assert result.units == {"modulus": "Pa/m", "rear": "-"}
    assert result.info["transforms"] == {"modulus": "log", "rear": "log"}


@pytest.mark.slow  # a sweep's own compiles (make test-slow)
def test_sweep_rows_equal_solve_wheel(tmp_path):
    snows = [SNOW, eqx.tree_at(lambda s: s.modulus, SNOW, 5e5)]
    stacked = jax.tree_util.tree_map(lambda *x: np.stack(x), *snows)  # 1-D leaves: two sets
    result = sj.sweep(
        WHEEL,
        sj.ContactModel(stacked, REAR),
        np.array([1500.0, 3000.0]),
        np.array([0.1, -0.2]),
        out=tmp_path / "sweep",
        progress=False,
        formats=("npz",),
    )
    rows = dict(np.load(result.files["npz"]))
    assert {"modulus", "layer_depth"} <= set(rows)  # columns of the leaves that vary
    assert len(rows["load"]) == 8
    st = sj.solve_wheel(
        WHEEL,
        sj.ContactModel(HyperbolicSnow(rows["modulus"], 0.25, 2e3, 0.2, 0.01), REAR),
        rows["load"],
        rows["slip"],
    )
    np.testing.assert_allclose(rows["sinkage"], st.sinkage, rtol=1e-12)
    np.testing.assert_allclose(rows["drawbar_pull"], st.drawbar_pull, rtol=1e-10, atol=1e-9)


def test_shear_laws_are_modules_or_their_names():
    """`shear=` takes a shear-law module or its name, with the same result; a law says
    what it needs (the thesis's simplified law: Wong snow on the front region)."""
    by_name = _solve(distribution=_full(REAR))
    by_module = sj.solve_wheel(
        _full(WHEEL),
        sj.ContactModel(_full(SNOW), distribution=_full(REAR), shear=sj.JanosiHanamoto()),
        LOADS,
        SLIPS,
    )
    np.testing.assert_array_equal(by_name.drawbar_pull, by_module.drawbar_pull)
    assert sj.NoShear().name == "none" and sj.ThesisSimplified().name == "simplified"
    with pytest.raises(ValueError, match="needs a WongSnow terrain"):
        sj.solve_wheel(WHEEL, sj.ContactModel(SNOW, shear=sj.ThesisSimplified()), 1000.0, 0.1)
    with pytest.raises(ValueError, match="shear must be one of"):
        sj.solve_wheel(WHEEL, sj.ContactModel(SNOW, shear="wet"), 1000.0, 0.1)
    fresh = sj.WongSnow.thesis_fresh_snow()
    thesis = sj.solve_wheel(WHEEL, sj.ContactModel(fresh, shear=sj.ThesisSimplified()), 3000.0, 0.2)
    assert float(thesis.drawbar_pull) == float(
        sj.solve_wheel(WHEEL, sj.ContactModel(fresh, shear="simplified"), 3000.0, 0.2).drawbar_pull
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
        sj.contact_forces(WHEEL, sj.ContactModel(_full(SNOW), REAR), by_model.entry_angle, SLIPS)
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
    # The model's parts are not keywords of the functions: the error names the model.
    with pytest.raises(TypeError, match=r"solve_wheel\(shear=...\) is now spelled ContactModel"):
        sj.solve_wheel(WHEEL, SNOW, 1000.0, 0.1, shear="none")
    with pytest.raises(TypeError, match="takes 4 positional arguments, got 5: .*ContactModel"):
        sj.solve_wheel(WHEEL, SNOW, 1000.0, 0.1, "none")
    with pytest.raises(TypeError, match=r"contact_forces\(nodes_per_panel=...\) is now spelled"):
        sj.contact_forces(WHEEL, model, 0.3, 0.1, nodes_per_panel=12)
    with pytest.raises(ValueError, match="nodes_per_panel must be >= 2"):
        sj.ContactModel(SNOW, nodes_per_panel=1)


class KondnerShear(sj.AbstractShearLaw):
    """Kondner's hyperbolic mobilisation, g = (j / K) / (1 + |j / K|): the shear stress
    rises like Janosi–Hanamoto's at small displacement and approaches the strength as
    1 / j instead of exponentially (Kondner 1963, "Hyperbolic stress-strain response:
    cohesive soils", J. Soil Mech. Found. Div. 89(SM1):115-143).  One method: every
    other part of a shear law has a default."""

    def mobilisation(self, j, modulus, sigma, theta0, slip, diameter, terrain):
        x = j / modulus
        return x / (1 + jnp.abs(x))


def test_a_shear_law_defined_outside_the_package_on_both_contact_rules():
    """`KondnerShear` (one class, public API only) through `solve_wheel` on the new
    terrain (the any-terrain rule) and `contact_forces` on Wong snow's front region (the
    closed-form rule, whose singularity subtraction uses the law's axle values), against
    the SciPy reference with the same mobilisation; driving and braking."""
    law = KondnerShear()
    kondner = lambda x: x / (1 + abs(x))  # noqa: E731
    st = sj.solve_wheel(_full(WHEEL), sj.ContactModel(_full(SNOW), shear=law), LOADS, SLIPS)
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
    forces = sj.contact_forces(WHEEL, sj.ContactModel(snow, shear=law), theta0, SLIPS)
    wong = lambda z, b: -2e4 * math.log1p(-z / 0.2)  # noqa: E731
    for k in range(N):
        exp = ref.contact(
            theta0[k], SLIPS[k], 0.736, 0.235, wong, 1e3, 0.3, 0.02, mobilisation=kondner
        )
        got = [forces.vertical_load[k], forces.motion_resistance[k], forces.thrust[k]]
        np.testing.assert_allclose(got, exp[:3], rtol=1e-7, atol=1e-7 * exp[0])


class FrontDrag(sj.AbstractForceTerm):
    """A constant pressure q [Pa] against the travel on the vertical projection of the
    front contact: Bekker's compaction resistance R_c = b * integral of p dz (Bekker 1969,
    *Introduction to Terrain-Vehicle Systems*) with p = q, a resistance per unit sinkage
    and width (q b z0 on a rim).  One method: its part of the resultants at the contact's
    nodes."""

    pressure: Float[Array, "..."] = eqx.field(converter=sj.as_float)

    def forces(self, nodes):
        front = jnp.where(nodes.theta > 0, nodes.sin, 0.0)
        dz = nodes.radius * front * nodes.weight  # the depth's element along the contact
        return sj.Resultants(motion_resistance=self.pressure * jnp.sum(nodes.points.width * dz))


DRAG = FrontDrag(4e3)


def test_a_force_term_defined_outside_the_package_on_both_contact_rules():
    """`FrontDrag` (one class, public API only) in a `ContactModel`: through `solve_wheel`
    on the new terrain (the any-terrain rule) and `contact_forces` on Wong snow's front
    region (the closed-form rule), driving and braking, against the SciPy reference plus
    q b z0; and d(drawbar pull)/dq by `jax.grad` against central differences of it."""
    model = sj.ContactModel(_full(SNOW), terms=(_full(DRAG),))
    st = sj.solve_wheel(_full(WHEEL), model, LOADS, SLIPS)
    assert np.all(np.asarray(st.status) == sj.Status.CONVERGED), st.status

    def reference(k, q=4e3):
        theta0, (_, r, t, _) = ref.solve(
            LOADS[k], SLIPS[k], 0.736, 0.235, _hyperbolic(), 2e3, 0.2, 0.01, depth=0.25
        )
        return theta0, t - r - q * 0.235 * 0.368 * (1 - math.cos(theta0))

    for k in range(N):
        theta0, pull = reference(k)
        assert float(st.entry_angle[k]) == pytest.approx(theta0, rel=1e-7)
        assert float(st.drawbar_pull[k]) == pytest.approx(pull, rel=1e-6, abs=1e-7 * LOADS[k])

    def total_pull(q):
        drag = FrontDrag(jnp.full(N, q))
        return jnp.sum(sj.solve_wheel(_full(WHEEL), eqx.tree_at(
            lambda m: m.terms, model, (drag,)), LOADS, SLIPS).drawbar_pull)  # fmt: skip

    h = 1.0  # [Pa]; the reference is linear in q
    expected = sum(reference(k, 4e3 + h)[1] - reference(k, 4e3 - h)[1] for k in range(N)) / (2 * h)
    assert float(jax.grad(total_pull)(4e3)) == pytest.approx(expected, rel=1e-7)

    snow = sj.WongSnow(2e4, 0.2, 1e3, 0.3, 0.02)
    theta0 = np.array([0.3, 0.5, 0.3, 0.5])
    forces = sj.contact_forces(WHEEL, sj.ContactModel(snow, terms=(DRAG,)), theta0, SLIPS)
    wong = lambda z, b: -2e4 * math.log1p(-z / 0.2)  # noqa: E731
    for k in range(N):
        w, r, t, _ = ref.contact(theta0[k], SLIPS[k], 0.736, 0.235, wong, 1e3, 0.3, 0.02)
        r += 4e3 * 0.235 * 0.368 * (1 - math.cos(theta0[k]))
        got = [forces.vertical_load[k], forces.motion_resistance[k], forces.thrust[k]]
        np.testing.assert_allclose(got, [w, r, t], rtol=1e-7, atol=1e-7 * w)
    with pytest.raises(TypeError, match="terms must be a tuple of snowjax.AbstractForceTerm"):
        sj.ContactModel(snow, terms=(lambda nodes: None,))


class ExtraPressure(sj.AbstractForceTerm):
    """A uniform normal stress q [Pa] over the contact (it carries part of the load)."""

    pressure: Float[Array, "..."] = eqx.field(
        converter=sj.as_float, metadata=sj.parameter("Pa", "pressure q", lower=0.0)
    )

    def forces(self, nodes):
        return nodes.integrate(normal=self.pressure * jnp.ones_like(nodes.theta))


def test_a_force_terms_parameters_are_checked_like_the_terrains():
    """A NaN or out-of-range term parameter: `ValueError` naming it for concrete values;
    under `jax.jit` `INVALID_INPUT` for that element alone, the others solved as without
    it (the invalid element's term replaced by its `reference()`, so that it cannot upset
    the batch's Newton iteration)."""
    snow = sj.BekkerSoil.snow_us()
    loads, slips = np.array([300.0, 500.0, 700.0]), np.array([0.2, -0.3, 0.5])

    def solve(pressure):
        model = sj.ContactModel(snow, terms=(ExtraPressure(pressure),))
        return sj.solve_wheel(WHEEL, model, loads, slips)

    with pytest.raises(ValueError, match=r"terms\[0\]\.pressure must be finite and >= 0"):
        solve(np.array([1e3, np.nan, 1e3]))
    with pytest.raises(ValueError, match=r"terms\[0\]\.pressure must be finite and >= 0"):
        solve(np.array([1e3, -1.0, 1e3]))
    with pytest.raises(ValueError, match=r"terms\[0\]\.pressure must be finite and real"):
        sj.solve_wheel(WHEEL, sj.ContactModel(snow, terms=(FrontDrag(np.inf),)), 300.0, 0.2)
    jitted = jax.jit(solve)
    bad, good = jitted(jnp.array([1e3, jnp.nan, 1e3])), jitted(jnp.full(3, 1e3))
    np.testing.assert_array_equal(bad.status, [0, sj.Status.INVALID_INPUT, 0])
    np.testing.assert_array_equal(bad.drawbar_pull[::2], good.drawbar_pull[::2])
    assert np.isnan(bad.drawbar_pull[1])


# --------------------------------------------------------------------------------------
# A wheel whose contact widens with depth, the one-method shear law and the force term,
# through every workflow, against SciPy references written here
# --------------------------------------------------------------------------------------


class BulgingWheel(sj.AbstractWheel):
    """A rigid wheel whose section widens with depth (a bulging sidewall): the contact's
    width at a point z deep is b(z) = b0 + 2 z tan(alpha).  One method over a rigid
    wheel's fields: `contact_width`."""

    diameter: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("m", "wheel diameter D", lower=0.0, open_lower=True),
    )
    width: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("m", "width b0 at the surface", lower=0.0, open_lower=True),
    )
    flare: Float[Array, "..."] = eqx.field(
        converter=sj.as_float,
        metadata=sj.parameter("-", "tan(alpha) of the sidewall", lower=0.0),
    )

    def contact_width(self, sinkage):
        return self.width + 2 * sinkage * self.flare

    @classmethod
    def reference(cls):
        return cls(0.736, 0.2, 0.3)


def _kondner(u):
    return u / (1 + abs(u))


def _janosi_hanamoto(u):
    return -math.expm1(-u)


def _reference_contact(theta0, slip, beta, case):
    """(W, R, T, M, F_y) [N, N m] of a rigid wheel on the front region by SciPy's adaptive
    quadrature: at a point of the rim z = r (cos theta - cos theta0) deep (4.5), the
    contact `case["width"](z)` wide, the normal stress `case["pressure"](z, b)`, and tau
    along the resultant of the shear displacements (4.10) and j_y = r (1 - i)(theta0 -
    theta) tan(beta) with K_y = K (`Lateral()`), g = `case["g"]` of the resultant; the
    panels cut where j_x changes sign and graded at the entry.  `case["drag"]` q [Pa]:
    `FrontDrag`'s resistance, q times the integral of the width over the depth."""
    from scipy import integrate, optimize

    r = case["diameter"] / 2
    c, tan_phi, k = case["c"], case["tan_phi"], case["k"]

    def depth(th):
        return max(r * (math.cos(th) - math.cos(theta0)), 0.0)

    def sig(th):
        return case["pressure"](depth(th), case["width"](depth(th)))

    def j_x(th):
        return r * ((theta0 - th) - (1 - slip) * (math.sin(theta0) - math.sin(th)))

    def taus(th):
        a, b = j_x(th) / k, r * (1 - slip) * (theta0 - th) * math.tan(beta) / k
        u = math.hypot(a, b)
        tau = (c + sig(th) * tan_phi) * case["g"](u)
        return (tau * a / u, tau * b / u) if u > 0 else (0.0, 0.0)

    pts = {0.0, theta0} | {theta0 - m * k / r for m in (1, 4, 16, 64) if m * k / r < theta0}
    grid = np.linspace(0.0, theta0, 2001)
    vals = [j_x(t) for t in grid]
    for i in range(len(grid) - 2):  # the sign change of j_x inside the contact
        if vals[i] * vals[i + 1] < 0:
            pts.add(optimize.brentq(j_x, grid[i], grid[i + 1], xtol=1e-15))
    pts = sorted(pts)
    fns = [
        lambda t: sig(t) * math.cos(t) + taus(t)[0] * math.sin(t),
        lambda t: sig(t) * math.sin(t),
        lambda t: taus(t)[0] * math.cos(t),
        lambda t: taus(t)[0] * r,
        lambda t: taus(t)[1],
    ]
    quad = lambda f: sum(  # noqa: E731
        integrate.quad(lambda t: f(t) * case["width"](depth(t)), lo, hi, epsabs=0.0,
                       epsrel=1e-12, limit=400)[0]
        for lo, hi in zip(pts[:-1], pts[1:])
    )  # fmt: skip
    out = np.array([quad(f) * r for f in fns])
    out[1] += case.get("drag", 0.0) * quad(lambda t: math.sin(t)) * r  # quad weighs by b(z)
    return out


def _check_against_reference(case, load, slip, beta, entry_angle, drawbar_pull, lateral_force):
    """The recorded forces of wheels at (load, slip, slip angle) against the reference at
    their entry angle: W = load (the equilibrium), T - R and F_y within 1e-6 of the load."""
    for k in range(len(load)):
        w, r, t, _, fy = _reference_contact(
            float(entry_angle[k]), float(slip[k]), float(beta[k]), case
        )
        scale = float(load[k])
        assert w == pytest.approx(scale, rel=1e-6)
        assert float(drawbar_pull[k]) == pytest.approx(t - r, abs=1e-6 * scale)
        assert float(lateral_force[k]) == pytest.approx(fy, abs=1e-6 * scale)


FRESH = sj.WongSnow.thesis_fresh_snow()
KONDNER = KondnerShear()
BULGING = BulgingWheel(0.736, 0.2, 0.3)


def _case(wheel, law, snow=FRESH, terms=()):
    """The reference's description of a (wheel, shear law, force terms) on Wong snow or
    Bekker soil."""
    if isinstance(snow, sj.WongSnow):
        p_w, z_w = float(snow.p_w), float(snow.z_w)
        pressure = lambda z, b: -p_w * math.log1p(-z / z_w)  # noqa: E731
    else:
        n, k_c, k_phi = float(snow.n), float(snow.k_c), float(snow.k_phi)
        pressure = lambda z, b: (k_c / b + k_phi) * z**n  # noqa: E731
    b0 = float(wheel.width)
    flare = float(getattr(wheel, "flare", 0.0))
    return {
        "diameter": float(wheel.diameter),
        "pressure": pressure,
        "width": lambda z: b0 + 2 * z * flare,
        "g": _kondner if law is KONDNER else _janosi_hanamoto,
        "c": float(snow.cohesion),
        "tan_phi": float(snow.tan_phi),
        "k": float(snow.shear_modulus),
        "drag": sum(float(t.pressure) for t in terms),
    }


EXTENSIONS = {  # name: (wheel, shear law, force terms)
    "kondner-shear": (sj.RigidWheel.thesis_tire(), KONDNER, ()),
    "bulging-wheel": (BULGING, sj.JanosiHanamoto(), ()),
    "front-drag": (sj.RigidWheel.thesis_tire(), sj.JanosiHanamoto(), (DRAG,)),
}


@pytest.mark.slow  # its own compiles (make test-slow)
def test_a_wheel_that_widens_with_depth_matches_the_reference():
    """`BulgingWheel` (one method over a rim's fields) on Bekker soil, whose pressure
    depends on the width, and on Wong snow (the any-terrain rule: its contact is not the
    closed-form rule's rim of constant width), driving and braking, straight and under a
    slip angle, against the SciPy reference; it sinks less than the rim of its surface
    width."""
    loads, slips = np.array([2000.0, 3500.0, 3500.0]), np.array([0.3, -0.2, 0.1])
    angles = np.array([0.0, 0.0, 0.15])
    for snow in (sj.BekkerSoil.snow_us(), FRESH):
        st = sj.solve_wheel(BULGING, snow, loads, slips, slip_angle=angles)
        assert np.all(np.asarray(st.status) == sj.Status.CONVERGED), st.status
        _check_against_reference(
            _case(BULGING, None, snow), loads, slips, angles, st.entry_angle,
            st.drawbar_pull, st.lateral_force,
        )  # fmt: skip
        rim = sj.solve_wheel(sj.RigidWheel(0.736, 0.2), snow, loads, slips, slip_angle=angles)
        assert np.all(np.asarray(st.sinkage) < np.asarray(rim.sinkage))


@pytest.mark.slow  # the simulations' own compiles (make test-slow)
@pytest.mark.parametrize("name", EXTENSIONS)
def test_extensions_drive_and_brake_in_both_simulations(name):
    """`KondnerShear` (one method), `BulgingWheel` and `FrontDrag` in
    `simulate_longitudinal` and `simulate_planar`: the wheels' recorded forces, driving and
    braking, equal the SciPy reference's at their recorded slip, slip angle and entry
    angle."""
    wheel, law, terms = EXTENSIONS[name]
    case = _case(wheel, law, terms=terms)
    model = sj.ContactModel(FRESH, shear=law, terms=terms)
    load = 3500.0
    vehicle = sj.Vehicle(mass=2 * load / 9.80665, wheel_inertia=1.5, wheel=wheel, num_wheels=2)
    torque = sj.TorqueProfile(jnp.array([0.0, 0.6, 1.2]), jnp.array([600.0, 600.0, -400.0]))
    traj = sj.simulate_longitudinal(
        vehicle, model, torque, 1.2, 0.05, initial=sj.InitialState(speed=2.0)
    )
    slips = np.asarray(traj.slip[:, 0])
    rows = [int(np.argmax(slips)), int(np.argmin(slips))]
    assert slips[rows[0]] > 0.05 and slips[rows[1]] < -0.05, slips  # driving and braking
    assert np.all(np.asarray(traj.status) == sj.Status.CONVERGED)
    _check_against_reference(
        case, np.full(2, load), slips[rows], np.zeros(2), np.asarray(traj.entry_angle[rows, 0]),
        np.asarray(traj.drawbar_pull[rows, 0]), np.zeros(2),
    )  # fmt: skip

    planar = sj.PlanarVehicle(1400.0, 1400.0 * (2.5**2 + 1.5**2) / 12, 1.5, wheel, 2.5, 1.5)
    drive = sj.TorqueProfile(jnp.array([0.0, 0.6, 1.2]), jnp.array([600.0, 600.0, -300.0]))
    traj = sj.simulate_planar(
        planar, model, 0.15, drive, 1.2, 0.05, initial=sj.InitialState(speed=2.0)
    )
    assert np.all(np.asarray(traj.status) == sj.Status.CONVERGED)
    slips = np.asarray(traj.slip)
    rows = np.array([np.argmax(slips[:, 0]), np.argmin(slips[:, 0])])
    assert slips[rows[0], 0] > 0.05 and slips[rows[1], 0] < -0.05, slips[:, 0]
    beta = np.asarray(traj.slip_angle)[rows]
    assert np.all(np.abs(beta[:, :2]) > 1e-3), beta  # the steered wheels slide sideways
    loads = np.asarray(planar.wheel_load)
    for k in range(4):
        _check_against_reference(
            case, np.full(2, loads[k]), slips[rows, k], beta[:, k],
            np.asarray(traj.entry_angle)[rows, k], np.asarray(traj.drawbar_pull)[rows, k],
            np.asarray(traj.lateral_force)[rows, k],
        )  # fmt: skip


@pytest.mark.slow  # an MJX step's own compile (make test-slow)
@pytest.mark.parametrize("name", EXTENSIONS)
def test_extensions_in_an_mjx_step(name):
    """`KondnerShear`, `BulgingWheel` and `FrontDrag` in `snowjax.mjx.step`: the shipped
    rover moving forwards and sideways, front wheels driven and rear wheels braked; each
    wheel's forces equal the SciPy reference's at its slip, slip angle and entry angle."""
    try:
        from mujoco import mjx

        from snowjax import mjx as smjx
    except ImportError:
        if os.environ.get("CI", "").lower() == "true":
            raise
        pytest.skip("the snowjax[mjx] extra is not installed")
    wheel, law, terms = EXTENSIONS[name]
    model, wheels = smjx.load_rover(wheel=wheel)
    contact = sj.ContactModel(FRESH, shear=law, terms=terms)
    m = mjx.put_model(model)
    d0 = mjx.make_data(m)
    radius = float(wheel.diameter) / 2
    spins = 2.0 / (radius * np.array([0.8, 0.8, 1.25, 1.25]))
    qvel = d0.qvel.at[0].set(2.0).at[1].set(0.4).at[np.asarray(wheels.dof_ids)].set(spins)
    _, f = jax.jit(lambda d: smjx.step(m, d, wheels, contact))(d0.replace(qvel=qvel))
    slip = np.asarray(f.slip)
    assert np.all(slip[:2] > 0.05) and np.all(slip[2:] < -0.05), slip
    assert np.all(np.abs(np.asarray(f.slip_angle)) > 1e-3)
    assert np.all(np.asarray(f.status) == sj.Status.CONVERGED)
    _check_against_reference(
        _case(wheel, law, terms=terms), np.asarray(f.load), slip, np.asarray(f.slip_angle),
        np.asarray(f.entry_angle), np.asarray(f.longitudinal_force), np.asarray(f.lateral_force),
    )  # fmt: skip


def _hyperbolic(modulus=4e5):
    return lambda z, b: modulus * max(z, 0.0) / (1 - max(z, 0.0) / 0.25)  # noqa: E731


def _kondner_reference(k, modulus=4e5, shear_modulus=0.01):
    """(theta0, sinkage, drawbar pull) of point k of (LOADS, SLIPS) on `HyperbolicSnow` with
    Kondner's law, by SciPy (`reference_terrain`)."""
    theta0, (_, r, t, _) = ref.solve(
        LOADS[k], SLIPS[k], 0.736, 0.235, _hyperbolic(modulus), 2e3, 0.2, shear_modulus,
        depth=0.25, mobilisation=_kondner,
    )  # fmt: skip
    return theta0, 0.368 * (1 - math.cos(theta0)), t - r


@pytest.mark.slow  # a gradient's own compile (make test-slow)
def test_gradients_of_the_one_method_shear_law_match_the_reference():
    """d(drawbar pull)/d(K) and d/d(k) through `solve_wheel` with `KondnerShear`, driving
    and braking, against central differences of the SciPy reference (relative step 1e-4:
    truncation and the reference's rounding both below 1e-8 of the derivative)."""

    def pull(snow):
        return sj.solve_wheel(
            _full(WHEEL), sj.ContactModel(snow, shear=KONDNER), LOADS, SLIPS
        ).drawbar_pull

    grads = jax.jacrev(lambda s: pull(s))(_full(SNOW))
    for field, value in (("shear_modulus", 0.01), ("modulus", 4e5)):
        h = 1e-4 * value
        for k in range(N):
            up = _kondner_reference(k, **{field: value + h})[2]
            down = _kondner_reference(k, **{field: value - h})[2]
            expected = (up - down) / (2 * h)
            got = float(getattr(grads, field)[k, k])
            assert got == pytest.approx(expected, rel=1e-6, abs=1e-9 * LOADS[k] / value), field


@pytest.mark.slow  # a fit's and a sweep's own compiles (make test-slow)
def test_fit_wheel_and_sweep_take_the_one_method_shear_law(tmp_path):
    """`fit_wheel` recovers k and K from SciPy-reference sinkages and drawbar pulls with
    `KondnerShear` (driving and braking points), and `sweep`'s rows equal the reference
    within 1e-6 of the load."""
    reference = [_kondner_reference(k) for k in range(N)]
    result = sj.fit_wheel(
        WHEEL,
        sj.ContactModel(HyperbolicSnow(3e5, 0.25, 2e3, 0.2, 0.02), shear=KONDNER),
        LOADS,
        SLIPS,
        {
            "sinkage": np.array([x[1] for x in reference]),
            "drawbar_pull": np.array([x[2] for x in reference]),
        },
        fit=("modulus", "shear_modulus"),
    )
    assert result.params["modulus"] == pytest.approx(4e5, rel=1e-6)
    assert result.params["shear_modulus"] == pytest.approx(0.01, rel=1e-6)
    assert "shear='KondnerShear'" in result.info["title"]
    swept = sj.sweep(
        WHEEL,
        sj.ContactModel(SNOW, shear=KONDNER),
        LOADS,
        SLIPS,
        grid=False,
        out=tmp_path / "sweep",
        progress=False,
        formats=("npz",),
    )
    rows = dict(np.load(swept.files["npz"]))
    manifest = json.loads((tmp_path / "sweep" / "manifest.json").read_text())
    assert manifest["definition"]["shear"] == "KondnerShear"  # the law's name, recorded
    for k, (_, sinkage, pull) in enumerate(reference):
        assert rows["sinkage"][k] == pytest.approx(sinkage, rel=1e-6)
        assert rows["drawbar_pull"][k] == pytest.approx(pull, abs=1e-6 * LOADS[k])


BEKKER = sj.BekkerSoil(1.1, 5e3, 800e3, 1.5e3, 0.55, shear_modulus=0.02)  # a firm soil
BULGE_LOADS, BULGE_SLIPS = np.array([2000.0, 3500.0]), np.array([0.3, -0.2])


def _bulging_reference(load, slip, flare=0.3, k_phi=None):
    """(sinkage [m], drawbar pull [N]) of `BulgingWheel` at (load [N], slip) on `BEKKER`,
    by brentq on the SciPy reference's W."""
    from scipy import optimize

    wheel = BulgingWheel(0.736, 0.2, flare)
    snow = BEKKER if k_phi is None else eqx.tree_at(lambda s: s.k_phi, BEKKER, k_phi)
    case = _case(wheel, None, snow)
    theta0 = optimize.brentq(
        lambda th: _reference_contact(th, slip, 0.0, case)[0] - load,
        1e-3, 1.4, xtol=1e-15, rtol=1e-14,
    )  # fmt: skip
    _, r, t, _, _ = _reference_contact(theta0, slip, 0.0, case)
    return 0.368 * (1 - math.cos(theta0)), t - r


@pytest.mark.slow  # a gradient's, a fit's and a sweep's own compiles (make test-slow)
def test_a_wheel_that_widens_with_depth_in_grad_fit_and_sweep(tmp_path):
    """`BulgingWheel` on a Bekker soil: d(drawbar pull)/d(flare) and d/d(k_phi) against
    central differences of the SciPy reference (relative step 1e-4), `fit_wheel`
    recovering k_phi from the reference's sinkages and drawbar pulls, and `sweep`'s rows
    (a column for the flare) equal to the reference within 1e-6 of the load."""
    wheel = jax.tree_util.tree_map(lambda x: jnp.full(2, x), BULGING)
    snow = jax.tree_util.tree_map(lambda x: jnp.full(2, x), BEKKER)

    def pull(wheel, snow):
        return sj.solve_wheel(wheel, snow, BULGE_LOADS, BULGE_SLIPS).drawbar_pull

    d_wheel, d_snow = jax.jacrev(pull, argnums=(0, 1))(wheel, snow)
    k_phi = float(BEKKER.k_phi)
    for k in range(2):
        for got, field, value in ((d_wheel.flare, "flare", 0.3), (d_snow.k_phi, "k_phi", k_phi)):
            h = 1e-4 * value
            point = (float(BULGE_LOADS[k]), float(BULGE_SLIPS[k]))
            up = _bulging_reference(*point, **{field: value + h})[1]
            down = _bulging_reference(*point, **{field: value - h})[1]
            expected = (up - down) / (2 * h)
            got = float(got[k, k])
            assert got == pytest.approx(expected, rel=1e-6, abs=1e-9 * BULGE_LOADS[k]), field

    reference = [_bulging_reference(*point) for point in zip(BULGE_LOADS, BULGE_SLIPS)]
    result = sj.fit_wheel(
        BULGING,
        eqx.tree_at(lambda s: s.k_phi, BEKKER, 0.5 * k_phi),
        BULGE_LOADS,
        BULGE_SLIPS,
        {
            "sinkage": np.array([x[0] for x in reference]),
            "drawbar_pull": np.array([x[1] for x in reference]),
        },
        fit=("k_phi",),
    )
    assert result.params["k_phi"] == pytest.approx(k_phi, rel=1e-6)
    swept = sj.sweep([BULGING, BulgingWheel(0.736, 0.2, 0.5)], BEKKER, BULGE_LOADS, BULGE_SLIPS,
                     out=tmp_path / "sweep", progress=False, formats=("npz",))  # fmt: skip
    rows = dict(np.load(swept.files["npz"]))
    assert "flare" in rows
    for i in range(len(rows["load"])):
        point = (float(rows["load"][i]), float(rows["slip"][i]))
        sinkage, drawbar_pull = _bulging_reference(*point, flare=float(rows["flare"][i]))
        assert rows["sinkage"][i] == pytest.approx(sinkage, rel=1e-6)
        assert rows["drawbar_pull"][i] == pytest.approx(drawbar_pull, abs=1e-6 * rows["load"][i])


@pytest.mark.slow  # a fit's and a sweep's own compiles (make test-slow)
def test_fit_wheel_and_sweep_take_a_force_term(tmp_path):
    """A `ContactModel` with `FrontDrag`: `fit_wheel` recovers k and K of the new terrain
    from the SciPy reference's sinkages and drawbar pulls with the drag (driving and
    braking points), and `sweep`'s rows equal the reference within 1e-6 of the load, the
    term recorded in its manifest."""
    reference = []
    for k in range(N):
        theta0, (_, r, t, _) = ref.solve(
            LOADS[k], SLIPS[k], 0.736, 0.235, _hyperbolic(), 2e3, 0.2, 0.01, depth=0.25
        )
        sinkage = 0.368 * (1 - math.cos(theta0))
        reference.append((sinkage, t - r - 4e3 * 0.235 * sinkage))
    start = sj.ContactModel(HyperbolicSnow(3e5, 0.25, 2e3, 0.2, 0.02), terms=(DRAG,))
    result = sj.fit_wheel(
        WHEEL,
        start,
        LOADS,
        SLIPS,
        {
            "sinkage": np.array([x[0] for x in reference]),
            "drawbar_pull": np.array([x[1] for x in reference]),
        },
        fit=("modulus", "shear_modulus"),
    )
    assert result.params["modulus"] == pytest.approx(4e5, rel=1e-6)
    assert result.params["shear_modulus"] == pytest.approx(0.01, rel=1e-6)
    model = sj.ContactModel(SNOW, terms=(DRAG,))
    swept = sj.sweep(WHEEL, model, LOADS, SLIPS, grid=False, out=tmp_path / "sweep",
                     progress=False, formats=("npz",))  # fmt: skip
    rows = dict(np.load(swept.files["npz"]))
    manifest = json.loads((tmp_path / "sweep" / "manifest.json").read_text())
    assert manifest["definition"]["terms"] == [{"type": "FrontDrag", "values": [4e3]}]
    for k, (sinkage, pull) in enumerate(reference):
        assert rows["sinkage"][k] == pytest.approx(sinkage, rel=1e-6)
        assert rows["drawbar_pull"][k] == pytest.approx(pull, abs=1e-6 * LOADS[k])
