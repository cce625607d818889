"""The `snowjax` command line: `snowjax reproduce | fit | sweep | validate`.

Each subcommand lives in its own module of this package with a `register(subparsers)`
function that adds its parser and sets `run`, the function called with the parsed
arguments (it returns the exit code).  Modules import JAX lazily so `--help` is fast.

An expected failure (a bad option, file or value) is one line on stderr and exit status
2: usage errors included (`_Parser`).  NumPy's floating-point `RuntimeWarning`s are not
shown: every command reports non-finite results itself (a status, an error message).
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings

from . import fit, reproduce, sweep, validate

_SUBCOMMANDS = (reproduce, fit, sweep, validate)


_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d)")


def _attach_negative_values(argv: list[str]) -> list[str]:
    """`--slips -0.5:0:3` -> `--slips=-0.5:0:3`.

    argparse takes a token starting with `-` for an option unless it is a plain negative
    number, so a value such as `-0.5:0:3` after `--slips` would be refused.  No snowjax
    option name starts with a digit, so a `-<digit>` token after a `--long` option is
    always that option's value.
    """
    out: list[str] = []
    for tok in argv:
        if out and out[-1].startswith("--") and "=" not in out[-1] and _NEGATIVE_VALUE.match(tok):
            out[-1] = f"{out[-1]}={tok}"
        else:
            out.append(tok)
    return out


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line: the problem and where to find
    help (argparse's default prints the whole usage first).  Subcommand parsers inherit
    it."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def main(argv: list[str] | None = None) -> int:
    parser = _Parser(
        prog="snowjax",
        description="Differentiable wheel-on-snow terramechanics (Sankapalli 2004).",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for module in _SUBCOMMANDS:
        module.register(sub)
    args = parser.parse_args(_attach_negative_values(sys.argv[1:] if argv is None else argv))
    args.argv = list(sys.argv[1:] if argv is None else argv)  # to run it again (sweep)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return int(args.run(args))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
