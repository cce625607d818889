"""Input checks of the wheel solver: eager errors naming the argument (concrete inputs) and
the per-element validity mask (traced inputs, `Status.INVALID_INPUT`).
"""

from __future__ import annotations

import functools
import math
import reprlib
import weakref

import jax
import jax.numpy as jnp
import numpy as np

from .._leaves import _is_traced, _module_leaves
from .distribution import _as_distribution, _is_front
from .geometry import AbstractWheel, _plain_rim
from .lateral import Lateral
from .shear_law import _shear_law
from .terms import _one_term_rules

# ---------------------------------------------------------------------------------------
# Input validation
# ---------------------------------------------------------------------------------------


def _checks(wheel, terrain, distribution, load, slip, shear):
    """Every validity rule: (name, value, ok mask, description of the allowed range).

    Works on NumPy values (eager errors) and on traced, flattened batches (status): the
    rules use only arithmetic and comparisons.
    """
    # Unbound calls: an equinox bound method costs ~40 us to create, and this runs on
    # every eager call.
    rules = _argument_rules(load, slip) + type(wheel).constraints(wheel)
    kind, law = type(terrain), _shear_law(shear)
    rules += [
        (f"{terrain.label}.{name}", value, ok, allowed)
        for name, value, ok, allowed in kind.constraints(terrain)
        + kind.wheel_constraints(terrain, wheel.width)
        + type(law).constraints(law, terrain)
    ]
    return rules + _distribution_rules(distribution, slip)


def _distribution_rules(distribution, slip):
    """The distribution's slip-dependent rules (unbound call, as above)."""
    return type(distribution).constraints(distribution, slip)


def _argument_rules(load, slip):
    return [
        ("load", load, load > 0, "> 0 N"),
        ("slip", slip, (slip >= -1) & (slip <= 1), "in [-1, 1]"),
    ]


# Wheels and terrains already checked: (id(wheel), id(terrain), type of the shear law) ->
# (weak references to both, their leaves' (type, dtype, weak type) key).  Parameter sets
# are immutable and usually reused across calls (a simulation, a sweep), so at batch 1
# this halves the cost of the eager checks.  Weak references make a reused id of a dead
# object a miss.
_CHECKED: dict[tuple[int, int, type], tuple] = {}


def _leaf_key(leaves) -> tuple:
    return tuple(
        (type(x), getattr(x, "dtype", None), bool(getattr(x, "weak_type", False))) for x in leaves
    )


def _checked_parameters(wheel, terrain, shear):
    """The leaf key of an already-validated (wheel, terrain) pair, else None."""
    entry = _CHECKED.get((id(wheel), id(terrain), type(_shear_law(shear))))
    if entry is None:
        return None
    (wheel_ref, terrain_ref), key = entry
    return key if wheel_ref() is wheel and terrain_ref() is terrain else None


def _remember_checked(wheel, terrain, shear, key) -> None:
    leaves = jax.tree_util.tree_leaves((wheel, terrain))
    if not all(isinstance(x, jax.Array) and not _is_traced(x) for x in leaves):
        return  # NumPy leaves are mutable: check them every time
    if len(_CHECKED) >= 256:
        _CHECKED.clear()
    _CHECKED[(id(wheel), id(terrain), type(_shear_law(shear)))] = (
        (weakref.ref(wheel), weakref.ref(terrain)),
        key,
    )


def _numeric_argument(name: str, value):
    """`value` as an array if it is concrete (lists and scalars accepted), else unchanged.

    Raises TypeError naming the argument for None, strings, booleans and complex numbers:
    a load of `True` is not 1 N.
    """
    if _is_traced(value) or isinstance(value, jax.Array):
        arr = value
    else:
        try:
            arr = np.asarray(value)
        except (TypeError, ValueError) as err:  # ragged nested lists
            raise TypeError(f"solve_wheel: {name} must be a real number or array: {err}") from None
    kind = np.dtype(arr.dtype).kind
    if kind not in "iuf":
        # An object array holds what was given (None, a dict, ...): named by its repr.
        kinds = {"b": "a boolean", "c": "a complex number", "U": "a string", "S": "bytes"}
        what = kinds.get(kind, reprlib.repr(value) if kind == "O" else type(value).__name__)
        raise TypeError(f"solve_wheel: {name} must be a real number or array, got {what}")
    return value if _is_traced(value) or isinstance(value, jax.Array) else arr


def _broadcast_shape(
    wheel, terrain, distribution, load, slip, guess, running, terms=()
) -> tuple[int, ...]:
    """The broadcast shape of every input, or ValueError naming the shapes that clash."""
    shapes = _leaf_shapes(wheel) + _leaf_shapes(terrain) + _leaf_shapes(distribution)
    shapes += [np.shape(x) for x in jax.tree_util.tree_leaves((load, slip, guess, running))]
    for term in terms:
        shapes += _leaf_shapes(term)
    try:
        return tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        pass
    named = {"load": load, "slip": slip, "initial_entry_angle": guess}
    named |= {name: value for name, value, *_ in type(running).rules(running)}  # slip_angle, ...
    trees = (("wheel", wheel), (terrain.label, terrain), ("distribution", distribution))
    trees += tuple((f"terms[{k}]", term) for k, term in enumerate(terms))
    for label, tree in trees:
        for path, leaf in _module_leaves(tree).items():
            named[f"{label}.{path}"] = leaf
    shapes = {k: tuple(np.shape(v)) for k, v in named.items()}
    try:
        return tuple(np.broadcast_shapes(*shapes.values()))
    except ValueError:
        shown = ", ".join(f"{k} {v}" for k, v in shapes.items() if v)
        raise ValueError(
            f"solve_wheel: the input shapes do not broadcast together (NumPy rules): {shown}"
        ) from None


def _check_options(max_steps) -> None:
    """`solve_wheel`'s Newton limit (the nodes per panel are checked by `ContactModel`)."""

    def integer(x):
        return isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_))

    if not (integer(max_steps) and max_steps >= 1):
        raise ValueError(f"solve_wheel: max_steps must be an integer >= 1, got {max_steps!r}")


def _validate_eagerly(wheel, terrain, distribution, load, slip, shear) -> np.dtype:
    """Raise ValueError naming the argument when concrete inputs are out of range; return
    the working dtype.

    Concrete leaves are checked with NumPy (no JAX dispatch per rule); traced ones skipped.
    """
    distribution = _as_distribution(distribution)
    known = _checked_parameters(wheel, terrain, shear)
    checked = known is not None  # the wheel and terrain rules passed before: the rest
    parameter_key = known if checked else _leaf_key(jax.tree_util.tree_leaves((wheel, terrain)))
    front = _is_front(distribution)  # no leaves, no rules
    trees = (wheel, terrain, distribution, load, slip)
    distribution_key, distribution_np = ((), distribution) if front else _concrete(distribution)
    dtype = _working_dtype_of(parameter_key + distribution_key + _leaf_key((load, slip)), trees)
    small, large = _magnitude_window(dtype)
    with np.errstate(invalid="ignore", over="ignore"):
        if checked:
            slip_np = _to_numpy(slip)
            rules = _argument_rules(_to_numpy(load), slip_np)
            if not front:
                rules += _distribution_rules(distribution_np, slip_np)
        else:
            w, t, d, ld, sl = jax.tree_util.tree_map(_to_numpy, trees)
            rules = _checks(w, t, d, ld, sl, shear)
    _check_rules(rules, dtype, small, large)
    if not checked:
        _remember_checked(wheel, terrain, shear, parameter_key)
    return dtype


def _per_module(table: dict, module, compute, key=(), limit: int = 256):
    """`compute(module)`, remembered in `table` per module object (and `key`) when the
    module's leaves are concrete JAX arrays (immutable): parameter sets are usually
    reused across calls (a simulation, a sweep), and at batch 1 each of these eager steps
    costs tens of microseconds.  An entry goes when its module is collected (a weak
    reference's callback), and the table is emptied at `limit` entries (a value that
    holds its module keeps it alive until then)."""
    ref, value = table.get((id(module), key), _MISS)
    if ref() is module:
        return value
    value = compute(module)
    leaves = jax.tree_util.tree_leaves(module)
    if all(isinstance(x, jax.Array) and not _is_traced(x) for x in leaves):
        if len(table) >= limit:
            table.clear()
        entry = (id(module), key)
        table[entry] = (weakref.ref(module, lambda _: table.pop(entry, None)), value)
    return value


_MISS = (lambda: _MISS, None)  # a dead reference: the value to compute
_VALID_MODULES: dict = {}  # modules whose rules passed, per working dtype
_LEAF_SHAPES: dict = {}  # the shapes of a module's leaves
_CONCRETE: dict = {}  # a module's leaf key and its copy with NumPy leaves


def _check_module_rules(module, rules_of, dtype) -> None:
    """Check `rules_of(module)` (as `_check_rules`), once per module object and dtype
    (`_per_module`): the parts of the contact model that do not change between calls
    (`Lateral`, force terms)."""

    def check(module):
        rules = rules_of(jax.tree_util.tree_map(_to_numpy, module))
        _check_rules(rules, dtype, *_magnitude_window(dtype))

    _per_module(_VALID_MODULES, module, check, dtype)


def _check_lateral_and_terms(lateral, terms, dtype) -> None:
    """The rules of a model's lateral law (None: none) and force terms, once per object
    (`_check_module_rules`)."""
    if isinstance(lateral, Lateral):
        _check_module_rules(lateral, Lateral.constraints, dtype)
    for k, term in enumerate(terms):
        _check_module_rules(term, functools.partial(_one_term_rules, k), dtype)


def _to_numpy(x):
    return np.asarray(x) if not _is_traced(x) else x


def _leaf_shapes(module) -> list:
    return _per_module(
        _LEAF_SHAPES, module, lambda m: [np.shape(x) for x in jax.tree_util.tree_leaves(m)]
    )


def _concrete(module) -> tuple:
    """(leaf key, the module with NumPy leaves) (`_per_module`)."""

    def compute(module):
        key = _leaf_key(jax.tree_util.tree_leaves(module))
        return key, jax.tree_util.tree_map(_to_numpy, module)

    return _per_module(_CONCRETE, module, compute)


def _check_rules(rules, dtype, small, large) -> None:
    for name, value, ok, allowed in rules:
        if _is_traced(value) or _is_traced(ok):
            continue
        if np.ndim(value) == 0 and np.ndim(ok) == 0:  # scalars: no array round trip
            v = float(value)
            if bool(ok) and math.isfinite(v) and _fits(v, name, small, large):
                continue
        arr = np.asarray(value, dtype=float)
        good = np.isfinite(arr) & np.asarray(ok)
        if np.all(good):
            fits = _fits(arr, name, small, large)
            if not np.all(fits):
                bad = np.argwhere(~np.broadcast_to(fits, arr.shape))
                first = arr[tuple(bad[0])] if arr.ndim else arr
                where = f" at index {tuple(int(k) for k in bad[0])}" if arr.ndim else ""
                raise ValueError(
                    f"solve_wheel: {name} = {float(first)!r}{where} is outside what"
                    f" {np.dtype(dtype).name} arithmetic can carry through the model:"
                    f" magnitudes up to {large:.1e}"
                    f" (and from {small:.1e} or 0, except the slip) are accepted"
                    f" ({len(bad)} such element(s))."
                )
            continue
        if not np.all(good):
            good = np.broadcast_to(good, np.broadcast_shapes(good.shape, arr.shape))
            arr = np.broadcast_to(arr, good.shape)
            bad = np.argwhere(~good)
            where = f" at index {tuple(int(k) for k in bad[0])}" if arr.ndim else ""
            first = arr[tuple(bad[0])] if arr.ndim else arr
            raise ValueError(
                f"solve_wheel: {name} must be finite and {allowed}; got {float(first)!r}{where}"
                f" ({len(bad)} invalid element(s))."
            )


def _working_dtype_of(key, trees) -> np.dtype:
    """The floating dtype the solve runs in (`jnp.result_type(*leaves, float)`), cached
    by the leaves' (type, dtype, weak type) `key`: `jnp.result_type` costs ~90 us at
    batch 1.  Python scalars (no dtype) are left to JAX, uncached."""
    if any(k[0] in _PYTHON_SCALARS for k in key):
        return np.dtype(jnp.result_type(*jax.tree_util.tree_leaves(trees), float))
    return _result_type_of(key)


_PYTHON_SCALARS = (bool, int, float, complex)


@functools.lru_cache(maxsize=256)
def _result_type_of(key) -> np.dtype:
    # A weakly typed leaf acts like a Python scalar of its kind.
    python = {"f": 0.0, "i": 0, "u": 0, "b": False, "c": 0j}
    dummies = [
        python.get(np.dtype(dtype).kind, 0.0) if weak else np.zeros((), dtype)
        for _, dtype, weak in key
    ]
    return np.dtype(jnp.result_type(*dummies, float))


@functools.lru_cache(maxsize=8)
def _magnitude_window(dtype) -> tuple[float, float]:
    """(smallest, largest) nonzero magnitude accepted for an input in this dtype.

    The model forms up to cubes of ratios of its inputs (e.g. (sigma / c)^3 in the
    simplified shear model), so an input whose fourth power under- or overflows the
    working precision cannot be carried through it: 1.2e-77 to 1.1e77 in float64,
    1.1e-10 to 1.4e9 in float32.  The lower limit does not apply to the slip (a slip
    near 0 is an ordinary rolling wheel, and no quantity is divided by it).
    """
    info = np.finfo(dtype)
    return float(info.tiny) ** 0.25, float(info.max) ** 0.25


def _fits(value, name, small, large):
    """Whether |value| lies in the magnitude window (works on NumPy and JAX values)."""
    magnitude = abs(value)
    if name in ("slip", "slip_angle"):
        return magnitude <= large
    return (magnitude == 0) | ((magnitude >= small) & (magnitude <= large))


def _valid_mask(wheel, terrain, distribution, load, slip, shear):
    small, large = _magnitude_window(load.dtype)
    valid = jnp.ones(load.shape, bool)
    for name, value, ok, _ in _checks(wheel, terrain, distribution, load, slip, shear):
        valid &= jnp.isfinite(value) & ok & _fits(value, name, small, large)
    return valid


def _check_model(wheel, model) -> None:
    """The wheel's type and the refused wheel / shear law pairs (a `ContactModel` checks
    its own parts, and the terrain / distribution / shear law combination, when built)."""
    if not isinstance(wheel, AbstractWheel):
        raise TypeError(
            "wheel must be a snowjax.RigidWheel, snowjax.DeflectingTire or another "
            f"snowjax.AbstractWheel, got {type(wheel).__name__}"
        )
    law = model.shear
    if not _plain_rim(wheel) and law.nodes_any_terrain is None:
        raise ValueError(
            f"shear={law.name!r} ({type(law).__name__}) is derived for a rigid rim: use "
            f"shear='classic' (or 'none') with a {type(wheel).__name__}."
        )
