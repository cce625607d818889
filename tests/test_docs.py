"""The API reference site: `mkdocs build --strict` passes and documents every public name.

The build needs the `docs` extra (mkdocs, mkdocs-material, mkdocstrings[python],
mkdocs-jupyter).  Without it the build test is skipped locally, but fails when CI=true.
"""

import ast
import importlib.util
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS_PACKAGES = ("mkdocs", "material", "mkdocstrings_handlers.python", "mkdocs_jupyter")


def _public_names():
    """Every `from ... import X as X` re-export of snowjax/__init__.py."""
    tree = ast.parse((ROOT / "snowjax" / "__init__.py").read_text(encoding="utf-8"))
    return [
        alias.asname
        for node in tree.body
        if isinstance(node, ast.ImportFrom)
        for alias in node.names
        if alias.asname is not None and alias.asname == alias.name
    ]


def _missing_docs_packages():
    missing = []
    for name in DOCS_PACKAGES:
        try:
            found = importlib.util.find_spec(name) is not None
        except ModuleNotFoundError:  # parent package absent
            found = False
        if not found:
            missing.append(name)
    return missing


# Public submodules (not imported by `import snowjax`), documented by their own `__all__`.
SUBMODULES = ("mjx", "playground")


def _submodule_names(name):
    """`__all__` of snowjax/<name>.py, read from the source (no MuJoCo import needed)."""
    tree = ast.parse((ROOT / "snowjax" / f"{name}.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
        ):
            return list(ast.literal_eval(node.value))
    raise AssertionError(f"snowjax/{name}.py has no __all__")


def test_every_public_name_is_documented():
    pages = "".join(p.read_text(encoding="utf-8") for p in (ROOT / "docs").rglob("*.md"))
    documented = set(re.findall(r"^::: snowjax\.(\w+)\s*$", pages, flags=re.MULTILINE))
    names = _public_names()
    assert len(names) > 100
    missing = [n for n in names if n not in documented]
    assert not missing, f"public names on no page of docs/: {missing}"
    unknown = sorted(documented - set(names) - set(SUBMODULES))
    assert not unknown, f"docs/ documents names snowjax does not export: {unknown}"
    for module in SUBMODULES:
        found = set(re.findall(rf"^::: snowjax\.{module}\.(\w+)\s*$", pages, flags=re.MULTILINE))
        missing = sorted(set(_submodule_names(module)) - found)
        assert not missing, f"snowjax.{module} names on no page of docs/: {missing}"


def test_mkdocs_build_strict(tmp_path):
    missing = _missing_docs_packages()
    if missing:
        message = f"docs extra not installed (missing {missing}): pip install -e '.[docs]'"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(message)
        pytest.skip(message)
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict"]
    cmd += ["--config-file", str(ROOT / "mkdocs.yml"), "--site-dir", str(site)]
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    page = site / "api" / "wheel" / "index.html"
    assert page.is_file()
    html = page.read_text(encoding="utf-8")
    assert 'id="snowjax.solve_wheel"' in html
    assert (site / "notebooks" / "quick_start" / "index.html").is_file()


# ---------------------------------------------------------------------------------------
# The README and the guide
# ---------------------------------------------------------------------------------------

GUIDE = ROOT / "docs" / "guide"
GUIDE_PAGES = (
    "wheel", "terrains", "steering", "tyres", "ruts", "vehicles", "mjx", "rl", "calibration",
    "sweeps", "validation", "performance", "reliability", "thesis", "extending",
)  # fmt: skip
NOTEBOOKS = sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb"))
# A commit hash (7-40 hex digits with a letter and a digit), a date (2026-11-27), an issue
# number, or the words of a development log.
HISTORY = re.compile(
    r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}\b"
    r"|\b(19|20)\d\d-\d\d-\d\d\b"
    r"|\b[Ii]ssues? #?\d+"
    r"|issue's aim"
)


def python_blocks(text: str) -> list[str]:
    """The ```python blocks of a Markdown page (at the start of a line; ```py blocks
    are shown, not run)."""
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.M | re.S)


def test_readme_is_a_front_door():
    """At most 200 lines; the two commands first; every guide page linked."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200, len(text.splitlines())
    commands = text.split("```bash\n", 1)[1].split("```", 1)[0].splitlines()
    assert [c.split()[:2] for c in commands] == [["make", "reproduce"], ["make", "test"]]
    for page in GUIDE_PAGES:
        assert f"(docs/guide/{page}.md)" in text, page


def test_no_history_in_the_readme_and_the_guide():
    """No commit hash, date of a measurement, issue number or "issue's aim" in what a user
    reads (the CHANGELOG keeps the history)."""
    pages = [ROOT / "README.md", ROOT / "docs" / "index.md", *sorted(GUIDE.glob("*.md"))]
    for page in pages:
        found = [m.group(0) for m in HISTORY.finditer(page.read_text(encoding="utf-8"))]
        assert not found, (page.name, found)


def test_every_guide_page_and_notebook_is_on_the_site():
    """Each guide page exists, has a runnable example (a ```python block) and is in the
    site's navigation; every notebook is in the navigation and linked from the index."""
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    assert sorted(p.stem for p in GUIDE.glob("*.md")) == sorted(GUIDE_PAGES)
    for page in GUIDE_PAGES:
        assert python_blocks((GUIDE / f"{page}.md").read_text(encoding="utf-8")), page
        assert f"guide/{page}.md" in nav and f"guide/{page}.md" in index, page
    assert len(NOTEBOOKS) == 7
    for notebook in NOTEBOOKS:
        assert f"notebooks/{notebook}" in nav and f"notebooks/{notebook}" in index, notebook


def test_readme_quick_start_runs_as_written():
    """The README's quick start, executed as written (float64)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    (block,) = python_blocks(text)
    namespace: dict = {}
    exec(compile(block, "README.md", "exec"), namespace)  # noqa: S102
    st = namespace["st"]
    assert int(st.status) == 0 and float(st.lateral_force) > 0
