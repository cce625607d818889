"""mkdocs hook: `[0, t1] [s]` in a docstring is an interval and a unit, not a link.

The docstrings write units in brackets after the quantity ("over [0, t1] [s]").  Python-Markdown
accepts one space between the two brackets of a reference link `[text] [id]`, so mkdocs-autorefs
would read that as a cross-reference to `s` and fail the strict build.  CommonMark allows no
space there; this makes autorefs follow it: `[text][id]` and `[text][]` still link, `[a] [b]`
stays text.
"""

from __future__ import annotations

import re

from mkdocs_autorefs import AutorefsInlineProcessor


def on_config(config):
    AutorefsInlineProcessor.RE_LINK = re.compile(r"\[([^\]]*)\]", re.DOTALL | re.UNICODE)
    return config
