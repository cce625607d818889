"""mkdocs hook: the README's repository-relative image paths, on the site's README page.

README.md (shown on GitHub from the repository root) links its figures as
`docs/figures/x.png`; `docs/readme.md` includes it (`--8<-- "README.md"`), where the same
files are at `figures/x.png`.  The include is expanded here, before the links are checked,
with the paths rewritten.
"""

from __future__ import annotations

import pathlib

INCLUDE = '--8<-- "README.md"'


def on_page_markdown(markdown, page, config, files):
    if page.file.src_uri != "readme.md" or INCLUDE not in markdown:
        return markdown
    readme = pathlib.Path(config["config_file_path"]).parent / "README.md"
    text = readme.read_text(encoding="utf-8").replace("](docs/figures/", "](figures/")
    return markdown.replace(INCLUDE, text)
