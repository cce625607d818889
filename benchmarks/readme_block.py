"""Write a generated block into README.md between `<!-- NAME:start -->` and `<!-- NAME:end -->`."""

from __future__ import annotations

import pathlib

README = pathlib.Path(__file__).resolve().parents[1] / "README.md"


def write_block(name: str, text: str) -> None:
    """Replace the block's content by `text`; SystemExit if the markers are missing."""
    content = README.read_text()
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    if start not in content or end not in content:
        raise SystemExit(f"README.md has no {start} ... {end} block")
    head, rest = content.split(start, 1)
    _, tail = rest.split(end, 1)
    README.write_text(f"{head}{start}\n{text}\n{end}{tail}")
