"""The README and the manual's pages (docs/*.md) hold together: every relative link leads to a file
that exists and every #anchor to a heading of its target, as GitHub makes anchors; and the Python
page names every public name of the package."""
import pathlib
import re
from collections import Counter

import vkray

ROOT = pathlib.Path(__file__).resolve().parents[2]


def documents():
    """The README, then the manual's pages in the order of their names."""
    return [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def prose(text):
    """The text outside fenced code blocks and inline code spans (which may run over a line break),
    where Markdown makes links and headings; each fenced line is kept as an empty line."""
    lines, fenced = [], False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
            lines.append("")
        else:
            lines.append("" if fenced else line)
    return re.sub(r"(`+)(?:(?!\1)(?!\n\n).)+?\1", "", "\n".join(lines), flags=re.S)


def github_anchor(title):
    """GitHub's anchor of a heading: its text (code spans keep their text, links theirs) lower case,
    punctuation but - and _ dropped, each space a -."""
    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title).replace("`", "")
    return re.sub(r"[^\w\- ]", "", title.strip().lower()).replace(" ", "-")


def anchors(path):
    """Every anchor GitHub makes in a Markdown file: one a heading, a repeated one numbered -1, -2, ..."""
    seen, made = Counter(), set()
    fenced = False
    for line in path.read_text().splitlines():
        if line.startswith("```"):
            fenced = not fenced
            continue
        match = None if fenced else re.match(r"^#{1,6} (.+?)\s*#*\s*$", line)
        if match:
            anchor = github_anchor(match.group(1))
            made.add(anchor if not seen[anchor] else f"{anchor}-{seen[anchor]}")
            seen[anchor] += 1
    return made


def relative_links(path):
    """(target, line) of each link and image of the file that is not a URL."""
    text = prose(path.read_text())
    found = []
    for match in re.finditer(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text):
        target = match.group(1)
        if not re.match(r"^[a-z][a-z0-9+.-]*:", target):  # https:, mailto:, ...
            found.append((target, text.count("\n", 0, match.start()) + 1))
    return found


def broken_links(path, root=ROOT):
    broken = []
    for target, line in relative_links(path):
        file, _, anchor = target.partition("#")
        destination = (path.parent / file).resolve() if file else path
        where = f"{path.relative_to(root)}:{line}: ({target})"
        if not destination.exists():
            broken.append(f"{where}: no file {file}")
        elif anchor and (destination.suffix != ".md" or anchor not in anchors(destination)):
            broken.append(f"{where}: no heading #{anchor} in {destination.relative_to(root)}")
    return broken


def test_every_relative_link_and_anchor_leads_somewhere():
    checked = [link for page in documents() for link in relative_links(page)]
    assert len(checked) > 100, "fewer links than the README and docs/ hold: is the link pattern right?"
    broken = [line for page in documents() for line in broken_links(page)]
    assert not broken, "\n".join(broken)


def test_a_broken_link_or_anchor_is_found(tmp_path):
    """The check itself: a missing file, a missing heading, and a repeated heading's numbered anchor."""
    (tmp_path.resolve() / "other.md").write_text("# Other\n\n## Part\n\n## Part\n\n```sh\n# not a heading\n```\n")
    page = tmp_path.resolve() / "page.md"
    page.write_text("# Page\n\n[ok](other.md#part-1) [code](`x`) `[not a link](nowhere.md)`\n[gone](missing.md),"
                    " [no heading](other.md#part-2), [here](#page) [not here](#not-a-heading) [url](https://example.com/x)\n")
    broken = broken_links(page, root=tmp_path.resolve())
    assert [line.split(": ", 1)[1] for line in broken] == [
        "(missing.md): no file missing.md", "(other.md#part-2): no heading #part-2 in other.md",
        "(#not-a-heading): no heading #not-a-heading in page.md"], broken


def public_names():
    """vkray's public names: __all__ and the module's constants, then each public class's own members
    (not those every object or exception has)."""
    names = [f"vkray.{name}" for name in vkray.__all__]
    names += [f"vkray.{name}" for name in dir(vkray) if name.isupper() and f"vkray.{name}" not in names]
    for name in vkray.__all__:
        cls = getattr(vkray, name)
        if isinstance(cls, type):
            inherited = set(dir(BaseException if issubclass(cls, BaseException) else object))
            names += [f"{name}.{member}" for member in dir(cls) if not member.startswith("_") and member not in inherited]
    return names


def test_the_python_page_names_every_public_name():
    names = public_names()
    assert {"vkray.RAY_OUTPUTS", "Renderer.set_transforms", "Scene.mesh_count", "Reference.count_intersections"} <= set(names)
    page = (ROOT / "docs" / "python.md").read_text()
    missing = [name for name in names if not re.search(r"`" + re.escape(name) + r"[`(]", page)]
    assert not missing, f"docs/python.md does not name {missing} (as `vkray.NAME` or `Class.member`)"
