"""`snowjax fit` (work in progress in this session; to be replaced by its owner)."""

from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser("fit", help="calibrate parameters against measurements (issue 5, in progress)")
    p.set_defaults(run=run)


def run(args) -> int:
    print("snowjax fit: not available yet")
    return 2
