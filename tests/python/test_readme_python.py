"""The README's ```python blocks run as written, from the repository root (matplotlib draws
nowhere: MPLBACKEND=Agg)."""
import os
import pathlib
import re
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
    """The README's `PYTHONPATH=build/python /usr/bin/python3 -c ...` line, with this build's package
    (under the interpreter this test runs under): it prints the version and the built-in scene's size."""
    lines = [line for line in (ROOT / "README.md").read_text().splitlines()
             if line.startswith("PYTHONPATH=build/python /usr/bin/python3 -c ")]
    assert lines, "the README shows no one-line import"
    for line in lines:
        code = line.split(" -c ", 1)[1].strip().strip("'")
        result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=os.environ)
        assert result.returncode == 0, f"{line}\n{result.stderr}"
        assert result.stdout.strip() == f"{vkray_version()} (600, 800)", result.stdout


def vkray_version():
    import vkray
    return vkray.__version__


def github_anchor(title):
    return re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")


def test_the_readme_opens_with_contents_that_list_every_heading():
    """The first heading is the contents; its entries are the README's ## and ### headings, in
    order, with the anchors GitHub gives them; the quick start, a ```python block the test above
    runs, comes early."""
    lines = (ROOT / "README.md").read_text().splitlines()
    headings = [(i, line) for i, line in enumerate(lines) if re.match(r"^##+ ", line)]
    assert headings[0][1] == "## Contents"
    start = headings[0][0]
    end = headings[1][0]
    entries = [line for line in lines[start + 1:end] if line.strip()]
    expected = []
    for _, line in headings[1:]:
        level, title = line.split(" ", 1)
        if level in ("##", "###"):
            expected.append(("  " if level == "###" else "") + f"- [{title}](#{github_anchor(title)})")
    assert entries == expected
    titles = [line for _, line in headings]
    assert [title for title in titles if title.startswith("## ")][:3] == ["## Contents", "## Two commands", "## Quick start"]
    quick = "\n".join(lines[headings[titles.index("## Quick start")][0]:headings[titles.index("## Quick start") + 1][0]])
    assert "```python" in quick and "vkray.Renderer" in quick
