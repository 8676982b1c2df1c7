"""No broken links: every relative link and image of README.md and docs/ resolves.

A link to a page must name a file of the repository; a link with an anchor (``cli.md#the-replay-page``,
``#object-types``) a heading of that page, as GitHub makes its anchor; an image a file that exists.
Addresses with a scheme (``https:``, ``mailto:``) are not followed: the suite has no network.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote, urlsplit

import docblocks
import pytest
from docblocks import ROOT

PAGES = docblocks.pages()


def broken_links(path: Path) -> list[str]:
    """Every link of the page at ``path`` that does not resolve, as ``page:line: target (why)``."""
    page = docblocks.read_page(path)
    problems = []
    for number, target in docblocks.links(page):
        parts = urlsplit(target)
        if parts.scheme or parts.netloc:
            continue
        where = f"{path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}:{number}: {target}"
        linked = (path.parent / unquote(parts.path)).resolve() if parts.path else path
        if not linked.exists():
            problems.append(f"{where} (no such file)")
            continue
        if not linked.is_relative_to(ROOT) and path.is_relative_to(ROOT):
            problems.append(f"{where} (outside the repository)")
            continue
        if parts.fragment:
            if linked.suffix != ".md":
                problems.append(f"{where} (an anchor into a file that is not a page)")
            elif unquote(parts.fragment) not in docblocks.read_page(linked).anchors:
                problems.append(f"{where} (no heading with that anchor in {linked.name})")
    return problems


@pytest.mark.parametrize("path", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_and_image_resolves(path: Path) -> None:
    assert broken_links(path) == []


def test_the_pages_have_links_to_check() -> None:
    """The parser finds the README's links to the guides and its images (else the test above checks nothing)."""
    targets = [target for _, target in docblocks.links(docblocks.read_page(ROOT / "README.md"))]
    assert "docs/cli.md#the-replay-page" in targets
    assert "docs/images/replay.png" in targets
    assert sum(len(docblocks.links(docblocks.read_page(path))) for path in PAGES) > 100


def test_a_broken_link_anchor_or_image_is_found(tmp_path: Path) -> None:
    (tmp_path / "other.md").write_text(
        "# Other\n\n## The `replay` page\n\n## Shapes and the gripper (`bt_arrange.shapes`)\n"
    )
    page = tmp_path / "page.md"
    page.write_text(
        "# Page\n\n## Here\n\n"
        "[fine](other.md#the-replay-page) [fine too](other.md#shapes-and-the-gripper-bt_arrangeshapes) [here](#here)\n"
        "[gone](missing.md) [no anchor](other.md#nowhere) [not here](#there)\n"
        "![picture](images/none.png) [web](https://example.org/x) `[code](not-a-link.md)`\n"
    )
    problems = broken_links(page)
    assert [problem.split(": ", 1)[1] for problem in problems] == [
        "missing.md (no such file)",
        "other.md#nowhere (no heading with that anchor in other.md)",
        "#there (no heading with that anchor in page.md)",
        "images/none.png (no such file)",
    ]


def test_anchors_are_github_s() -> None:
    assert (
        docblocks.slug("Exit 3: the run finished, its record did not") == "exit-3-the-run-finished-its-record-did-not"
    )
    assert docblocks.slug("Shapes and the gripper (`bt_arrange.shapes`)") == "shapes-and-the-gripper-bt_arrangeshapes"
    assert docblocks.slug("A real cell: the paper's real column") == "a-real-cell-the-papers-real-column"
    assert docblocks.slug("Interrupted, killed, resumed") == "interrupted-killed-resumed"
