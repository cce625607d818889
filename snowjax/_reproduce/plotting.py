"""Helpers shared by the figure modules of `snowjax reproduce`."""

from __future__ import annotations

from collections.abc import Iterable

from .._wheel.equilibrium import Status


def subplots(nrows=1, ncols=1, figsize=None):
    """A figure without pyplot (no global state, no backend switch): `(fig, axes)`."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols)


def thesis_title(ax, number, text) -> None:
    """The standard axes title "Fig. <number> (cf. thesis): <text>"."""
    ax.set_title(f"Fig. {number} (cf. thesis): {text}", fontsize=10)


def status_names(codes: Iterable[int]) -> set[str]:
    """Names of the `Status` codes of a wheel solve, e.g. {"CONVERGED"}."""
    return {Status(c).name for c in codes}
