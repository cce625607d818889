"""mkdocs hook: the repository-relative paths of README.md and CONTRIBUTING.md, on the
site's pages that include them.

README.md and CONTRIBUTING.md (shown on GitHub from the repository root) link the site's
figures and guide as `docs/figures/x.png` and `docs/guide/x.md`, and the repository's
files (`CONTRIBUTING.md`, `CHANGELOG.md`, `LICENSE`) by their names; `docs/readme.md` and
`docs/contributing.md` include them (`--8<-- "README.md"`), where the same pages are at
`figures/x.png`, `guide/x.md`, `contributing.md` and `changelog.md`, and the licence is
not a page.  The include is expanded here, before the links are checked, with the paths
rewritten.
"""

from __future__ import annotations

import pathlib

INCLUDES = {"readme.md": "README.md", "contributing.md": "CONTRIBUTING.md"}
REWRITES = (
    ("](docs/", "]("),
    ("](CONTRIBUTING.md)", "](contributing.md)"),
    ("](CHANGELOG.md)", "](changelog.md)"),
    ("([LICENSE](LICENSE))", "(the repository's `LICENSE`)"),
)


def on_page_markdown(markdown, page, config, files):
    source = INCLUDES.get(page.file.src_uri)
    include = f'--8<-- "{source}"'
    if source is None or include not in markdown:
        return markdown
    path = pathlib.Path(config["config_file_path"]).parent / source
    text = path.read_text(encoding="utf-8")
    for old, new in REWRITES:
        text = text.replace(old, new)
    return markdown.replace(include, text)
