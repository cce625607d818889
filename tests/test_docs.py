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
SUBMODULES = ("mjx",)


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
