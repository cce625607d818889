"""`snowjax sweep` (work in progress in this session; to be replaced by its owner)."""

from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser("sweep", help="chunked, resumable sweeps to disk (issue 8, in progress)")
    p.set_defaults(run=run)


def run(args) -> int:
    print("snowjax sweep: not available yet")
    return 2
