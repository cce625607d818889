"""The package layout rules of CONTRIBUTING.md, checked on the source.

- nothing inside snowjax/ imports from the package's top level (`snowjax/__init__.py` is the
  public surface only);
- each concept package imports only the layers below it;
- no module is longer than 800 lines unless its docstring says why.
"""

import ast
import pathlib
import re

import pytest

PKG = pathlib.Path(__file__).resolve().parents[1] / "snowjax"

# What each part may import (besides itself).
ALLOWED = {
    "_leaves": set(),
    "_constants": set(),
    "_terrain": {"_leaves", "_constants"},
    "_wheel": {"_leaves", "_constants", "_terrain"},
    "_tire": {"_leaves", "_constants"},
    "_empirical": {"_leaves", "_constants", "_terrain", "_wheel"},
}
WORKFLOWS = {"_fit", "_sweep", "_sim", "_validate", "_reproduce", "_coupled"}
MODELS = {"_leaves", "_constants", "_terrain", "_wheel", "_tire", "_empirical"}
for name in WORKFLOWS:
    ALLOWED[name] = MODELS | WORKFLOWS
ALLOWED["_cli"] = MODELS | WORKFLOWS
ALLOWED["_mjx"] = MODELS | WORKFLOWS  # the optional MuJoCo MJX bridge
ALLOWED["mjx"] = {"_mjx"}  # snowjax.mjx: its public names
ALLOWED["playground"] = {"_mjx"}  # snowjax.playground: its public names


def _modules():
    return sorted(p for p in PKG.rglob("*.py") if p.name != "__init__.py" or p.parent != PKG)


def _imports(path):
    """(line, absolute module) of every snowjax import in `path`."""
    rel = path.relative_to(PKG.parent).with_suffix("")
    package = list(rel.parts[:-1])
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "snowjax":
                    yield node.lineno, a.name
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if (node.module or "").split(".")[0] == "snowjax":
                    yield node.lineno, node.module
                continue
            base = package[: len(package) - (node.level - 1)]
            if node.module:
                yield node.lineno, ".".join([*base, node.module])
            else:
                for a in node.names:
                    yield node.lineno, ".".join([*base, a.name])


def test_modules_found():
    assert len(_modules()) > 30


def test_nothing_imports_the_top_level():
    bad = [
        f"{p.relative_to(PKG.parent)}:{line} imports {mod}"
        for p in _modules()
        for line, mod in _imports(p)
        if mod == "snowjax"
    ]
    assert not bad, "\n".join(bad)


def test_layers():
    bad = []
    for p in _modules():
        part = p.relative_to(PKG).parts[0].removesuffix(".py")
        for line, mod in _imports(p):
            if mod == "snowjax":  # reported by test_nothing_imports_the_top_level
                continue
            target = mod.split(".")[1]
            if target != part and target not in ALLOWED[part]:
                bad.append(f"{p.relative_to(PKG.parent)}:{line}: {part} may not import {mod}")
    assert not bad, "\n".join(bad)


def test_module_length():
    long = []
    for p in _modules():
        n = len(p.read_text().splitlines())
        doc = ast.get_docstring(ast.parse(p.read_text())) or ""
        if n > 800 and not re.search(r"over 800 lines", doc):
            long.append(f"{p.relative_to(PKG.parent)}: {n} lines")
    assert not long, "\n".join(long)


def _recipe_linear_soil():
    """The `LinearSoil` of the extending guide's recipe, executed as written there."""
    text = (PKG.parent / "docs" / "guide" / "extending.md").read_text()
    heading = "## Adding a terrain law, a stress distribution, a shear law or a wheel"
    recipe = text[text.index(heading) :]
    code = recipe[recipe.index("```python\n") + len("```python\n") : recipe.index("```\n\n")]
    namespace: dict = {}
    exec(compile(code, "extending.md", "exec"), namespace)
    return namespace["LinearSoil"]


def _plain_linear_soil():
    """The same law with plain `eqx.field`s (no metadata): the shear-strength fields get
    the standard rules, the modulus none."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    import snowjax as sj

    class LinearSoil(sj.Terrain):
        modulus: jax.Array = eqx.field(converter=jnp.asarray)
        cohesion: jax.Array = eqx.field(converter=jnp.asarray)
        tan_phi: jax.Array = eqx.field(converter=jnp.asarray)
        shear_modulus: jax.Array = eqx.field(converter=jnp.asarray)

        def pressure(self, sinkage, width):
            return self.modulus * jnp.maximum(jnp.asarray(sinkage), 0.0)

        @classmethod
        def reference(cls):
            return cls(2e6, 1e3, 0.4, 0.01)

    return LinearSoil


@pytest.mark.parametrize("make", [_recipe_linear_soil, _plain_linear_soil])
def test_a_new_terrain_law_is_one_class(make):
    """A law defined outside the package (one class) runs through solve_wheel.

    A linear law sigma = k z is Bekker's with n = 1, k_c = 0: both must give the same
    equilibrium, front region and Wong-Reece, batched.
    """
    import numpy as np

    import snowjax as sj  # float64: tests/conftest.py

    LinearSoil = make()
    wheel = sj.RigidWheel(1.0, 0.4)
    mine = LinearSoil(2e6, 1e3, 0.4, 0.01)
    bekker = sj.BekkerSoil(n=1.0, k_c=0.0, k_phi=2e6, cohesion=1e3, tan_phi=0.4,
                           shear_modulus=0.01)  # fmt: skip
    load, slip = np.array([2e3, 4e3, 6e3]), np.array([0.1, 0.3, 0.5])
    for dist in (None, sj.WongReece(0.43, 0.32)):
        a = sj.solve_wheel(wheel, sj.ContactModel(mine, dist), load, slip)
        b = sj.solve_wheel(wheel, sj.ContactModel(bekker, dist), load, slip)
        assert np.all(np.asarray(a.status) == 0)
        np.testing.assert_allclose(a.sinkage, b.sinkage, rtol=1e-12)
        np.testing.assert_allclose(a.drawbar_pull, b.drawbar_pull, rtol=1e-10)
    with pytest.raises(ValueError, match=r"terrain\.cohesion must be finite and >= 0 Pa"):
        sj.solve_wheel(wheel, LinearSoil(2e6, -1.0, 0.4, 0.01), 2e3, 0.1)


def test_no_function_holds_over_100_lines_of_code():
    """No function of the package holds over 100 lines of code (its docstring, comment
    lines and blank lines not counted)."""
    long = []
    for path in sorted(PKG.rglob("*.py")):
        lines = path.read_text().splitlines()
        for node in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            body = node.body
            if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                body = body[1:]  # the docstring
            if not body:
                continue
            span = lines[body[0].lineno - 1 : body[-1].end_lineno]
            code = [x for x in span if x.strip() and not x.strip().startswith("#")]
            if len(code) > 100:
                long.append(f"{path.relative_to(PKG.parent)}::{node.name} ({len(code)} lines)")
    assert not long, long


def test_no_public_function_takes_over_10_parameters():
    """The settings that travel together are modules (`ContactModel`, `InitialState`,
    `Stepping`, `SweepRun`, `SnowCover`, ...), so no public function or method of
    `snowjax` or `snowjax.mjx` takes more than 10 parameters (`self` not counted)."""
    import importlib
    import inspect

    names = []
    for module_name in ("snowjax", "snowjax.mjx"):
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", None) or dir(module):
            obj = getattr(module, name)
            if name.startswith("_"):
                continue
            if inspect.isfunction(obj):
                names.append((f"{module_name}.{name}", obj))
            elif inspect.isclass(obj) and obj.__module__.startswith("snowjax"):
                for attr, value in vars(obj).items():
                    if inspect.isfunction(value) and not attr.startswith("_"):
                        names.append((f"{module_name}.{name}.{attr}", value))
    assert len(names) > 100  # the public surface was found
    wide = []
    for label, function in names:
        parameters = [p for p in inspect.signature(function).parameters if p != "self"]
        if len(parameters) > 10:
            wide.append(f"{label}: {len(parameters)} parameters")
    assert not wide, wide


def test_the_contact_has_few_optional_branches():
    """The contact's optional parts are modules (the wheel's contact, the running
    `Straight` / `SlipAngle`, the force terms, the ground), not `None` branches: at most
    30 `is None` / `is not None` in `snowjax/_wheel` and `snowjax/_terrain` together
    (docstrings and comments included; 80 before the contact became modules)."""
    count = 0
    for part in ("_wheel", "_terrain"):
        for path in sorted((PKG / part).rglob("*.py")):
            count += len(re.findall(r"\bis (?:not )?None\b", path.read_text()))
    assert 0 < count <= 30, count
