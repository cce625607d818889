"""mkdocs hook: serve `notebooks/*.ipynb` (outside `docs/`) as pages `notebooks/<name>/`.

Each notebook keeps its real path (source directory: the repository root), so mkdocs-jupyter,
whose `on_files` runs after this one, renders it from `notebooks/`, unexecuted.
"""

from __future__ import annotations

import pathlib

from mkdocs.plugins import event_priority
from mkdocs.structure.files import File


@event_priority(100)  # before mkdocs-jupyter wraps the notebook files
def on_files(files, config):
    root = pathlib.Path(config["config_file_path"]).parent
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        files.append(
            File(
                f"notebooks/{path.name}",
                src_dir=str(root),
                dest_dir=config["site_dir"],
                use_directory_urls=config["use_directory_urls"],
            )
        )
    return files
