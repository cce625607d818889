"""A rut map: the depth of the ruts on a grid over the ground, read and marked by wheels
that drive anywhere (Chrono SCM's plastic memory per terrain node, in JAX).

**State.**  One number per cell of a regular grid of square cells (size h): the deepest
point below the original surface that any wheel has reached there, z_max [m] (0: virgin
snow).  Memory: `nx * ny` numbers (8 bytes each in float64, 4 in float32), whatever
happens on it; `RutMap.nbytes`.

**Reading** (`RutMap.read`): a wheel at position p with heading t and width b sees the
mean of the map, bilinearly interpolated, over `samples` points across its width at
`p + lookahead * t`, (k + 1/2) / samples - 1/2 of b to the side (k = 0..samples-1):
the depth of the rut it is about to enter, where a wheel half in a rut sees half its
depth (the width-weighted split of `snowjax.Ruts`).  Outside the grid the snow is
virgin (0).  Its `Rut(virgin, depth, b, k_0, a_u)` is the terrain the wheel runs on.

**Marking** (`RutMap.mark`): a wheel that moved from p_0 to p_1 in a step raises every
cell whose centre lies within the rectangle swept by the segment p_0 p_1 (along it:
from sqrt(2) h behind p_0 to p_1; across it: within b/2 + sqrt(2) h of it) to the depth
the wheel reached: `z_max <- max(z_max, z)`.  The sqrt(2) h margin across makes a
straight rut, read back by a wheel of the same width in the same track, exactly the
depth written (every bilinear sample then interpolates between marked cells): the map's
ruts are up to sqrt(2) h wider on each side than the wheel.  The margin behind p_0
closes the wedges a curved path leaves between consecutive segments where b/2 times the
change of heading in a step is below sqrt(2) h.  A wheel at rest marks nothing.  Only a
square window of `window` cells about the segment's midpoint is updated (the cost per
wheel and step is `window^2`, independent of the map's size); a step whose width plus
travel exceeds the map's `reach` raises (`eqx.error_if`; raise `reach` in
`RutMap.empty`).

**Its own rut.**  A wheel marks behind its axle and reads `lookahead` ahead of it: it
never reads what it marked as long as `lookahead > sqrt(2) h` (checked), and a following
wheel needs `lookahead + sqrt(2) h` less than its distance behind its leader.

**Differentiable.**  Reading is linear in the map and piecewise bilinear in the
position; marking is a maximum (its derivative follows the wheel that set the depth);
the footprint itself is a step function of position (no derivative w.r.t. where the
rut's edges lie).  `jax.jit`, `jax.vmap` (over environments: one map each) and forward
and reverse mode work.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._leaves import _as_float, _is_traced, parameter

__all__ = ["RutMap"]

# The default cap on the memory of a map's cells and of one mark's window [bytes].
MAX_BYTES = 4 * 2**30


class RutMap(eqx.Module):
    """The depth of the ruts on a grid (see `snowjax._terrain.rut_map` for the model).

    Build an empty one with `RutMap.empty`.  **Fields:**

    - `depth`: z_max of each cell [m], shape (nx, ny) (cell (i, j) is centred at
      `origin + h (i, j)`).
    - `k_0` [Pa/m], `a_u` [Pa/m^2]: the unloading modulus k_u = k_0 + A_u z_u of the
      snow's ruts (`Rut`).
    - `origin`: (x, y) of cell (0, 0)'s centre [m] (static).
    - `cell_size`: h [m] (static).
    - `window`: the side of the square of cells one wheel's mark updates (static).
    """

    depth: Float[Array, "nx ny"]
    k_0: Float[Array, ""] = eqx.field(
        converter=_as_float,
        metadata=parameter(
            "Pa/m", "unloading modulus at zero sinkage k_0", lower=0.0, open_lower=True, scale=1e6
        ),
    )
    a_u: Float[Array, ""] = eqx.field(
        converter=_as_float,
        metadata=parameter("Pa/m^2", "growth A_u of the unloading modulus", lower=0.0, scale=1e7),
    )
    origin: tuple[float, float] = eqx.field(static=True)
    cell_size: float = eqx.field(static=True)
    window: int = eqx.field(static=True)

    @classmethod
    def empty(
        cls,
        extent: tuple[float, float, float, float],
        cell_size: float,
        k_0: Float[ArrayLike, ""],
        a_u: Float[ArrayLike, ""],
        *,
        reach: float = 0.5,
        dtype=None,
        max_bytes: float = MAX_BYTES,
    ) -> "RutMap":
        """A map of virgin snow over `extent = (x_min, x_max, y_min, y_max)` [m] in cells
        of `cell_size` h [m]; `k_0` [Pa/m], `a_u` [Pa/m^2] as in `Rut`; `reach` [m]: the
        largest extent of one wheel's mark in one step (its width plus its travel),
        which sets `window = ceil(reach / h) + 8` cells (a mark that does not fit
        raises at run time, `eqx.error_if`); `dtype`: of `depth`, `k_0` and `a_u`
        (default JAX's float); `max_bytes` [bytes]: the most the map's cells, or one mark's
        window, may take (default `MAX_BYTES`, 4 GiB; raise it for a larger map).

        **Raises:** `ValueError` for a non-positive size or an empty extent, and, before
        anything is allocated, for a map or a window larger than `max_bytes` (naming the
        cell size and the memory it would take)."""
        x0, x1, y0, y1 = (float(v) for v in extent)
        h = float(cell_size)
        if not (math.isfinite(h) and h > 0 and math.isfinite(reach) and reach > 0):
            raise ValueError(f"cell_size and reach must be finite and > 0 m; got {h}, {reach}")
        if not (x1 > x0 and y1 > y0 and all(map(math.isfinite, (x0, x1, y0, y1)))):
            raise ValueError(f"extent must be finite (x_min, x_max, y_min, y_max); got {extent}")
        dtype = jnp.result_type(float) if dtype is None else dtype
        # Sizes checked in Python first: a count of 10^19 cells would overflow XLA's
        # shape arithmetic (a C++ abort, not a Python error).
        nx, ny = math.ceil((x1 - x0) / h), math.ceil((y1 - y0) / h)
        cells = nx * ny
        window = math.ceil(reach / h) + 8
        itemsize = jnp.dtype(dtype).itemsize
        for what, count in (("the map", cells), (f"one mark's window ({window} x {window})",
                                                 window * window)):  # fmt: skip
            if count * itemsize > max_bytes:
                raise ValueError(
                    f"RutMap.empty: cell_size = {h:.3g} m makes {what} {count:.3g} cells, "
                    f"{_size(count * itemsize)} in {jnp.dtype(dtype).name} (max_bytes = "
                    f"{_size(max_bytes)}): use larger cells, a smaller extent or reach, or "
                    "raise max_bytes"
                )
        _check_modulus(k_0, a_u)
        # The moduli in the map's dtype, not weakly typed: a map that comes back from a
        # `lax.scan` (a rollout's) has the same types as the empty one, so a jitted
        # function called again with it is not compiled again.
        k_0, a_u = jnp.asarray(k_0, dtype), jnp.asarray(a_u, dtype)
        return cls(jnp.zeros((nx, ny), dtype), k_0, a_u, (x0 + h / 2, y0 + h / 2), h, int(window))

    @property
    def nbytes(self) -> int:
        """Memory of the map's state [bytes]."""
        return int(self.depth.size * self.depth.dtype.itemsize)

    def _index(self, position):
        """Continuous cell coordinates of positions (..., 2)."""
        return (jnp.asarray(position) - jnp.asarray(self.origin, self.depth.dtype)) / self.cell_size

    def sample(self, position: Float[ArrayLike, "... 2"]) -> Float[Array, "..."]:
        """The map's depth at positions (..., 2) [m], bilinear, 0 outside the grid."""
        u = self._index(position)
        base = jnp.floor(u)
        frac = u - base
        base = base.astype(jnp.int32)
        nx, ny = self.depth.shape
        total = 0.0
        for di in (0, 1):
            for dj in (0, 1):
                i, j = base[..., 0] + di, base[..., 1] + dj
                inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
                value = self.depth[jnp.clip(i, 0, nx - 1), jnp.clip(j, 0, ny - 1)]
                wx = frac[..., 0] if di else 1 - frac[..., 0]
                wy = frac[..., 1] if dj else 1 - frac[..., 1]
                total = total + jnp.where(inside, value, 0.0) * wx * wy
        return total

    def check_lookahead(self, lookahead) -> None:
        """`ValueError` unless a concrete `lookahead` [m] exceeds sqrt(2) h."""
        if not _is_traced(lookahead) and not float(lookahead) > math.sqrt(2) * self.cell_size:
            raise ValueError(
                f"lookahead must exceed sqrt(2) * cell_size = "
                f"{math.sqrt(2) * self.cell_size:.4g} m (a wheel would read its own rut); "
                f"got {lookahead!r}"
            )

    def read(
        self,
        position: Float[ArrayLike, "... 2"],
        heading: Float[ArrayLike, "..."],
        width: Float[ArrayLike, "..."],
        lookahead: float,
        samples: int = 5,
    ) -> Float[Array, "..."]:
        """The rut depth a wheel sees [m]: the mean over `samples` points across its
        `width` b [m] at `lookahead` [m] ahead of its `position` (x, y) [m] along its
        `heading` [rad] (from x towards y).  `lookahead` must exceed sqrt(2) h (module
        docs: a wheel must not read its own mark)."""
        self.check_lookahead(lookahead)
        heading = jnp.asarray(heading)
        t = jnp.stack([jnp.cos(heading), jnp.sin(heading)], -1)
        n = jnp.stack([-t[..., 1], t[..., 0]], -1)
        centre = jnp.asarray(position) + lookahead * t
        side = (jnp.arange(samples) + 0.5) / samples - 0.5  # fractions of the width
        points = (
            centre[..., None, :]
            + (side * jnp.asarray(width)[..., None])[..., None] * n[..., None, :]
        )
        return jnp.mean(self.sample(points), -1)

    def mark(
        self,
        previous: Float[ArrayLike, "n 2"],
        position: Float[ArrayLike, "n 2"],
        width: Float[ArrayLike, " n"],
        depth: Float[ArrayLike, " n"],
    ) -> "RutMap":
        """The map after n wheels moved from `previous` to `position` (x, y) [m] in a
        step, each reaching `depth` [m] below the original surface; `width` b [m]."""
        previous, position = jnp.asarray(previous), jnp.asarray(position)
        n = previous.shape[0]
        width = jnp.broadcast_to(jnp.asarray(width), (n,))
        depth = jnp.broadcast_to(jnp.asarray(depth), (n,))
        grid = self.depth
        for k in range(n):
            grid = self._mark_one(grid, previous[k], position[k], width[k], depth[k])
        return eqx.tree_at(lambda m: m.depth, self, grid)

    def _mark_one(self, grid, start, end, width, depth):
        nx, ny = grid.shape
        wx, wy = min(self.window, nx), min(self.window, ny)
        centre = jnp.round(self._index((start + end) / 2)).astype(jnp.int32)
        i0 = jnp.clip(centre[0] - wx // 2, 0, nx - wx)
        j0 = jnp.clip(centre[1] - wy // 2, 0, ny - wy)
        block = jax.lax.dynamic_slice(grid, (i0, j0), (wx, wy))
        h = self.cell_size
        x = self.origin[0] + (i0 + jnp.arange(wx))[:, None] * h - start[0]
        y = self.origin[1] + (j0 + jnp.arange(wy))[None, :] * h - start[1]
        seg = jax.lax.stop_gradient(end - start)
        length = jnp.linalg.norm(seg)
        # The footprint (length + sqrt(2) h) x (width + 2 sqrt(2) h), about the window's
        # centre cell, fits in any orientation while length + width <= (window - 8) h.
        # (The check is on the scalar, not on the grid: on the grid it would stop XLA
        # updating the map in place, 10x the cost of a mark.)
        reach = (self.window - 8) * h
        too_big = (length + width > reach) & ((wx < nx) | (wy < ny))
        length = eqx.error_if(
            length,
            too_big,
            "RutMap.mark: a wheel's width plus its travel in one step exceeds the map's "
            "reach; build the map with a larger reach (RutMap.empty) or take shorter steps",
        )
        moving = length > 0
        t = jnp.where(moving, seg / jnp.where(moving, length, 1.0), 0.0)
        along = x * t[0] + y * t[1]
        across = jnp.abs(-x * t[1] + y * t[0])
        half = jax.lax.stop_gradient(width) / 2 + math.sqrt(2) * h
        behind = math.sqrt(2) * h  # behind the start: closes the gaps between segments
        inside = moving & (along >= -behind) & (along <= length) & (across <= half)
        block = jnp.where(inside, jnp.maximum(block, depth.astype(block.dtype)), block)
        return jax.lax.dynamic_update_slice(grid, block, (i0, j0))


def _size(nbytes: float) -> str:
    """A byte count in the binary unit that reads best ("3.2 GiB")."""
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if nbytes < 1024:
            return f"{nbytes:.3g} {unit}"
        nbytes /= 1024
    return f"{nbytes:.3g} PiB"


def _check_modulus(k_0, a_u) -> None:
    for name, value, positive in (("k_0", k_0, True), ("a_u", a_u, False)):
        if _is_traced(value):
            continue
        v = np.asarray(value, float)
        ok = np.all(np.isfinite(v)) and np.all(v > 0 if positive else v >= 0)
        if not ok:
            raise ValueError(
                f"{name} must be finite and {'> 0 Pa/m' if positive else '>= 0 Pa/m^2'}; "
                f"got {value!r}"
            )
