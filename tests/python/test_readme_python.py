"""The README's ```python blocks run as written, from the repository root (matplotlib draws
nowhere: MPLBACKEND=Agg)."""
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def python_blocks(readme):
    blocks, block = [], None
    for line in readme.splitlines():
        if line.startswith("```"):
            if block is None and line == "```python":
                block = []
            elif block is not None:
                blocks.append("\n".join(block))
                block = None
            continue
        if block is not None:
            block.append(line)
    return blocks


def test_every_python_example_in_the_readme_runs():
    if not os.path.isdir(os.environ.get("VKRAY_MODELS_DIR", "")):
        pytest.skip("the README's examples use ../shared/models, which is absent")
    blocks = python_blocks((ROOT / "README.md").read_text())
    assert blocks, "the README has no ```python block"
    for block in blocks:
        # The README's paths are relative to the repository root, the models beside it.
        code = block.replace("../shared/models", os.environ["VKRAY_MODELS_DIR"])
        result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                                env=dict(os.environ, MPLBACKEND="Agg"))
        assert result.returncode == 0, f"README example failed:\n{block}\n{result.stderr}"


def test_the_one_line_import_in_the_readme_runs():
    """The README's `PYTHONPATH=build/python /usr/bin/python3 -c ...` line, with this build's module
    (and the interpreter it was built for, the one this test runs under)."""
    lines = [line for line in (ROOT / "README.md").read_text().splitlines()
             if line.startswith("PYTHONPATH=build/python /usr/bin/python3 -c ")]
    assert lines, "the README shows no one-line import"
    for line in lines:
        code = line.split(" -c ", 1)[1].strip().strip("'")
        result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=os.environ)
        assert result.returncode == 0, f"{line}\n{result.stderr}"
        assert result.stdout.strip() == "(600, 800)", result.stdout
