"""The documentation's Python runs: docs/python.md cell by cell (one namespace,
as a notebook) and the numpy example of python/README.md.

Run as a script to make the notebook's images in a directory:
``python python/tests/test_docs.py docs`` (from the repository root).
"""

import os
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def cells(path):
    return re.findall(r"```python\n(.*?)```", Path(path).read_text(), re.S)


def run(path, where, only=None):
    namespace = {"__name__": "__doc__"}
    here = os.getcwd()
    os.chdir(where)
    try:
        for code in cells(path):
            if only is None or only(code):
                exec(compile(code, str(path), "exec"), namespace)
    finally:
        os.chdir(here)


def test_the_notebook_runs(tmp_path):
    pytest.importorskip("yt")
    pytest.importorskip("matplotlib")
    run(ROOT / "docs" / "python.md", tmp_path)
    for image in ("python-disc.png", "python-projection.png", "python-amr.png", "python-yt.png",
                  "python-yt-scene.png"):  # fmt: skip
        assert (tmp_path / image).stat().st_size > 1000, image


def test_the_readme_example_runs(tmp_path):
    run(ROOT / "python" / "README.md", tmp_path, only=lambda code: code.startswith("import numpy"))
    assert (tmp_path / "first.png").stat().st_size > 1000


if __name__ == "__main__":
    run(ROOT / "docs" / "python.md", sys.argv[1])
