"""The ```python blocks of the README and of the manual's pages (docs/*.md) run as written, from the
repository root (matplotlib draws nowhere: MPLBACKEND=Agg)."""
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def documents():
    """The README, then the manual's pages in the order of their names."""
    return [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


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


def every_block():
    """Each ```python block of the pages, with its page and place there: a test each."""
    return [pytest.param(page, block, id=f"{page.relative_to(ROOT)}:{k + 1}")
            for page in documents() for k, block in enumerate(python_blocks(page.read_text()))]


def test_the_pages_hold_python_examples():
    assert python_blocks((ROOT / "README.md").read_text()), "the README has no ```python block"
    assert len(every_block()) >= 6, "the README and docs/ hold fewer ```python blocks than expected"


@pytest.mark.parametrize("page, block", every_block())
def test_every_python_example_in_the_readme_runs(page, block):
    if not os.path.isdir(os.environ.get("VKRAY_MODELS_DIR", "")):
        pytest.skip("the README's examples use ../shared/models, which is absent")
    # Each runs from the package alone: the wheel holds no file of docs/ to import.
    assert not re.search(r"sys\.path|^\s*(from|import)\s+(obj_arrays|robot_loop|sensor_mask)\b", block, re.M), \
        f"{page.relative_to(ROOT)}: an example imports from the repository, which the wheel does not hold:\n{block}"
    # The paths are relative to the repository root, the models beside it.
    code = block.replace("../shared/models", os.environ["VKRAY_MODELS_DIR"])
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                            env=dict(os.environ, MPLBACKEND="Agg"))
    assert result.returncode == 0, f"{page.relative_to(ROOT)}: example failed:\n{block}\n{result.stderr}"


def test_the_one_line_import_in_the_readme_runs():
    """The manual's `PYTHONPATH=build/python /usr/bin/python3 -c ...` line, with this build's package
    (under the interpreter this test runs under): it prints the version and the built-in scene's size."""
    lines = [line for page in documents() for line in page.read_text().splitlines()
             if line.startswith("PYTHONPATH=build/python /usr/bin/python3 -c ")]
    assert lines, "the README and docs/ show no one-line import"
    for line in lines:
        code = line.split(" -c ", 1)[1].strip().strip("'")
        result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=os.environ)
        assert result.returncode == 0, f"{line}\n{result.stderr}"
        assert result.stdout.strip() == f"{vkray_version()} (600, 800)", result.stdout


def vkray_version():
    import vkray
    return vkray.__version__


def test_one_interpreter_name_throughout():
    """Every command that runs Python names /usr/bin/python3, the interpreter python3-numpy is
    installed for (docs/python.md says why): a bare `python3` may be pyenv's, without numpy."""
    bare = re.compile(r"(?<![\w/.-])python3(?= -| docs/| engine/| [\w./]+\.py)")
    found = [f"{page.relative_to(ROOT)}:{number}: {line.strip()}" for page in documents()
             for number, line in enumerate(page.read_text().splitlines(), 1) if bare.search(line)]
    assert not found, "\n".join(found)


def github_anchor(title):
    return re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")


def headings(text, level):
    """The text's headings of exactly `level` #s, outside code blocks."""
    titles, fenced = [], False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
        elif not fenced and line.startswith("#" * level + " "):
            titles.append(line[level + 1:].strip())
    return titles


def test_the_readme_opens_with_contents_that_list_every_heading():
    """The README starts with what vkray is, then the two commands and the quick start (a ```python
    block the test above runs); its contents, "The manual", list every page of docs/ and each ##
    heading of every page (accuracy.md, generated, by its page alone), in the page's order; each page
    opens with its title and a statement of what it covers that links back to the README (but
    accuracy.md, which opens with the command that generated it)."""
    readme = (ROOT / "README.md").read_text()
    sections = headings(readme, 2)
    assert sections[:2] == ["Two commands", "Quick start"], sections
    assert "The manual" in sections
    lines = readme.splitlines()
    start = lines.index("## The manual")
    end = next(i for i in range(start + 1, len(lines)) if lines[i].startswith("## "))
    contents = "\n".join(lines[start + 1:end])
    links = re.findall(r"\[[^\]]+\]\((docs/[^)#]+\.md)(?:#([^)]+))?\)", contents)
    pages = sorted((ROOT / "docs").glob("*.md"))
    for page in pages:
        name = f"docs/{page.name}"
        assert (name, "") in links, f"the README's contents do not link {name}"
        text = page.read_text()
        assert text.startswith("# "), f"{name} opens without its title"
        if page.name == "accuracy.md":
            continue  # generated by the command docs/precision.md shows: it opens with that command
        scope = text.split("\n\n")[1]
        assert "](../README.md" in scope, f"{name}: the paragraph after the title should say what it covers and link back to the README"
        listed = [anchor for linked, anchor in links if linked == name and anchor]
        expected = [github_anchor(title) for title in headings(text, 2)]
        assert listed == expected, f"the README's contents list {name}'s headings as {listed}, the page has {expected}"
    quick = readme[readme.index("\n## Quick start\n"):]
    quick = quick[:quick.index("\n## ", 2)]
    assert "```python" in quick and "vkray.Renderer" in quick
