"""Write a generated block into a page of the documentation site between
`<!-- NAME:start -->` and `<!-- NAME:end -->`: the benchmark tables live on
`docs/guide/performance.md` and `docs/guide/reliability.md`, where `make bench` and
`make robustness` rewrite them."""

from __future__ import annotations

import argparse
import pathlib

GUIDE = pathlib.Path(__file__).resolve().parents[1] / "docs" / "guide"
# The page of each block.
PAGES = {
    "benchmarks": "performance.md",
    "mjx-benchmarks": "performance.md",
    "accuracy": "performance.md",
    "rut-benchmarks": "performance.md",
    "robustness": "reliability.md",
}


def write_block(name: str, text: str, page: str | None = None) -> pathlib.Path:
    """Replace the block's content by `text` on its page (`PAGES`, or `page`, a file name
    under docs/guide/); SystemExit if the markers are missing.  Returns the page's path."""
    path = GUIDE / (page or PAGES[name])
    content = path.read_text(encoding="utf-8")
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    if start not in content or end not in content:
        raise SystemExit(f"{path} has no {start} ... {end} block")
    head, rest = content.split(start, 1)
    _, tail = rest.split(end, 1)
    path.write_text(f"{head}{start}\n{text}\n{end}{tail}", encoding="utf-8")
    return path


def add_no_docs(parser: argparse.ArgumentParser) -> None:
    """The `--no-docs` flag of every benchmark: print the table only."""
    parser.add_argument(
        "--no-docs", action="store_true", help="do not rewrite the table on its page of docs/guide/"
    )
