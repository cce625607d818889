"""The optional extras the test modules need (`snowjax[mjx]`, `snowjax[rl]`)."""

import importlib
import os

import pytest


def require_extra(extra: str, *modules: str) -> None:
    """Import `modules`; where one is missing, skip the calling test module (at import)
    locally, and fail under CI (`CI=true`), where `make test` installs every extra."""
    try:
        for name in modules:
            importlib.import_module(name)
    except ImportError:
        if os.environ.get("CI", "").lower() == "true":
            raise
        pytest.skip(
            f"the snowjax[{extra}] extra ({', '.join(modules)}) is not installed",
            allow_module_level=True,
        )
