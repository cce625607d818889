"""Every guide page's examples run as written (docs/guide/*.md): each page's ```python
blocks in order, in one namespace, in a fresh directory (float64, as the pages say).
The README's quick start runs in `tests/test_docs.py`; the guide's MuJoCo example is
also the fixture of `tests/test_mjx.py`."""

from __future__ import annotations

import importlib
import os
import sys
import types

import pytest

from .test_docs import GUIDE, GUIDE_PAGES, python_blocks


@pytest.mark.slow  # the examples compile as a user's would: about 3 minutes in all
@pytest.mark.parametrize("page", GUIDE_PAGES)
def test_guide_example_runs(page, tmp_path, monkeypatch):
    extra = {"mjx": "snowjax.mjx", "ruts": "snowjax.mjx", "rl": "snowjax.playground"}
    if page in extra:
        try:
            importlib.import_module(extra[page])
        except ImportError:
            if os.environ.get("CI", "").lower() == "true":
                raise
            pytest.skip(f"the extra {extra[page]} needs is not installed")
    monkeypatch.chdir(tmp_path)
    text = (GUIDE / f"{page}.md").read_text(encoding="utf-8")
    # A module of its own (a class defined in an example, e.g. a dataclass, looks its
    # module up in sys.modules).
    module = types.ModuleType(f"guide_{page}")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    for k, block in enumerate(python_blocks(text)):
        code = compile(block, f"docs/guide/{page}.md, example {k + 1}", "exec")
        exec(code, module.__dict__)  # noqa: S102
