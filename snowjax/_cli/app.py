"""The `snowjax` command line: `snowjax reproduce | fit | sweep | validate`.

Each subcommand lives in its own module of this package with a `register(subparsers)`
function that adds its parser and sets `run`, the function called with the parsed
arguments (it returns the exit code).  Modules import JAX lazily so `--help` is fast.
"""

from __future__ import annotations

import argparse
import sys

from . import fit, reproduce, sweep, validate

_SUBCOMMANDS = (reproduce, fit, sweep, validate)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="snowjax",
        description="Differentiable wheel-on-snow terramechanics (Sankapalli 2004).",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for module in _SUBCOMMANDS:
        module.register(sub)
    args = parser.parse_args(argv)
    return int(args.run(args))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
