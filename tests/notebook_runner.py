"""Execute a notebook from `notebooks/` in a fresh kernel, on small sizes.

Notebooks read `SNOWJAX_NOTEBOOK_SMALL` (set to "1" here) and shrink their grids, batch
sizes and iteration counts so that the test suite stays fast; run by hand they use the
full sizes.  A failing cell raises `nbclient.exceptions.CellExecutionError` with the
cell's traceback, which fails the calling test.
"""

from __future__ import annotations

import os
import pathlib

import nbformat
from nbclient import NotebookClient

NOTEBOOKS = pathlib.Path(__file__).resolve().parents[1] / "notebooks"


def run_notebook(name: str, tmp_path: pathlib.Path, timeout: int = 600) -> nbformat.NotebookNode:
    """Run `notebooks/<name>` with cwd = tmp_path; returns the executed notebook."""
    path = NOTEBOOKS / name
    nb = nbformat.read(path, as_version=4)
    os.environ["SNOWJAX_NOTEBOOK_SMALL"] = "1"
    os.environ.setdefault("MPLBACKEND", "Agg")
    client = NotebookClient(
        nb,
        timeout=timeout,
        kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    )
    client.execute()
    return nb


def outputs_text(nb: nbformat.NotebookNode) -> str:
    """All stream and text/plain outputs of an executed notebook, concatenated."""
    parts = []
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            if out.get("output_type") == "stream":
                parts.append(out.get("text", ""))
            elif "data" in out and "text/plain" in out["data"]:
                parts.append(out["data"]["text/plain"])
    return "\n".join(parts)
