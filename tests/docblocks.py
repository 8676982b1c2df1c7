"""The documentation as the tests read it: fenced blocks, their markers, links and headings.

The pages are README.md and every ``docs/*.md``. A fenced block is what a user copies; the HTML comment
on the line before it (blank lines between are allowed) is a marker a reader never sees:

- ``<!-- skip: REASON -->`` before a ```python or ```bash block: the suite does not run it (a full
  campaign, an install, a server that waits for a client); the reason is the test's skip message.
- ``<!-- needs: chromium -->`` (tools, by commas): the block runs where they are installed, else skips.
- A ```text block right after a run block (only blank lines between) is the output the block prints;
  the suite compares it line by line, where a ``...`` inside a line matches any text and a line that
  is only ``...`` matches any number of lines (wall times, paths). ``<!-- output: numbers within 0.001 -->``
  before it: each number is compared within that tolerance, the text between numbers exactly (poses a
  camera measured, which the last digits of another machine's floating point may change);
  ``<!-- output: shown only: REASON -->``: the output is shown, not compared.

Headings become anchors as GitHub makes them (lower case, punctuation dropped, spaces to hyphens, a
``-1``, ``-2`` ... for repeats), which is also what the site's ``toc`` extension is set to make.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`\s]*)[^`]*$")
MARKER = re.compile(r"^\s*<!--\s*(?P<kind>skip|output|needs)\s*:\s*(?P<text>.*?)\s*-->\s*$")
HEADING = re.compile(r"^(?P<hashes>#{1,6})\s+(?P<title>.*?)\s*#*\s*$")
# [text](target) and ![alt](target), not inside code spans; the target without an optional "title".
LINK = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\((?P<target><[^>]*>|[^)\s]+)(?:\s+\"[^\"]*\")?\)")
HTML_SRC = re.compile(r"""<(?:img|a)\s[^>]*(?:src|href)\s*=\s*["'](?P<target>[^"']+)["']""", re.I)
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1")


@dataclass
class Block:
    """One fenced block of a page."""

    page: Path
    line: int  # 1-based line of the opening fence
    language: str
    code: str
    skip: str | None = None  # the reason of a "skip:" marker
    needs: str | None = None  # tools of a "needs:" marker (e.g. "chromium"): skipped without them
    output: Block | None = None  # the ```text block that shows what this one prints
    output_checked: bool = True
    output_tolerance: float = 0.0  # numbers of the output compared within this (0: as text)

    @property
    def where(self) -> str:
        page = self.page.relative_to(ROOT) if self.page.is_relative_to(ROOT) else self.page
        return f"{page}:{self.line}"


@dataclass
class Page:
    """A Markdown page: its blocks, the lines outside them, its anchors."""

    path: Path
    blocks: list[Block] = field(default_factory=list)
    prose: list[tuple[int, str]] = field(default_factory=list)  # (line number, text) outside fences
    anchors: set[str] = field(default_factory=set)


def pages() -> list[Path]:
    """README.md and every page of docs/, in a stable order."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def slug(title: str) -> str:
    """A heading's anchor as GitHub makes it (and the site, through toc's slugify)."""
    text = re.sub(r"<[^>]+>", "", title)  # tags go, their text stays
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link's text stays
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)  # punctuation (backticks, dots, commas, parentheses) goes
    return text.replace(" ", "-")


def read_page(path: Path) -> Page:
    """Parse one page: fenced blocks with their markers and output blocks, prose lines and anchors."""
    page = Page(path)
    lines = path.read_text(encoding="utf-8").split("\n")
    pending: dict[str, str] = {}  # markers seen since the last non-blank line
    previous: Block | None = None  # the last block, while only blank lines followed it
    seen: dict[str, int] = {}
    index = 0
    while index < len(lines):
        line = lines[index]
        opening = FENCE.match(line)
        if opening:
            fence = opening["fence"]
            end = index + 1
            while end < len(lines) and not lines[end].strip().startswith(fence):
                end += 1
            indent = len(opening["indent"])
            code = "\n".join(text[indent:] if text[:indent].isspace() else text for text in lines[index + 1 : end])
            block = Block(
                path,
                index + 1,
                opening["info"].lower(),
                code + "\n",
                skip=pending.get("skip"),
                needs=pending.get("needs"),
            )
            if previous is not None and block.language == "text" and previous.language in ("python", "bash"):
                previous.output = block
                marker_text = pending.get("output", "")
                previous.output_checked = not marker_text.startswith("shown only")
                tolerance = re.fullmatch(r"numbers within ([0-9.eE+-]+)", marker_text)
                if tolerance:
                    previous.output_tolerance = float(tolerance[1])
                elif marker_text and previous.output_checked:
                    raise ValueError(f"{path}:{index + 1}: unknown output marker {marker_text!r}")
            page.blocks.append(block)
            pending, previous = {}, block
            index = end + 1
            continue
        marker = MARKER.match(line)
        if marker:
            pending[marker["kind"]] = marker["text"]
        elif line.strip():
            pending, previous = {}, None
            page.prose.append((index + 1, line))
            heading = HEADING.match(line)
            if heading:
                anchor = slug(heading["title"])
                count = seen.get(anchor, 0)
                seen[anchor] = count + 1
                page.anchors.add(anchor if count == 0 else f"{anchor}-{count}")
        index += 1
    return page


def links(page: Page) -> list[tuple[int, str]]:
    """Every link and image target of a page's prose (not of its code), with its line number."""
    found = []
    for number, line in page.prose:
        text = CODE_SPAN.sub("", line)
        for match in LINK.finditer(text):
            found.append((number, match["target"].strip("<>")))
        for match in HTML_SRC.finditer(text):
            found.append((number, match["target"]))
    return found


NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def expected_output_matches(expected: str, actual: str, tolerance: float = 0.0) -> bool:
    """Whether ``actual`` is ``expected``: ``...`` in a line is any text, a ``...`` line any lines.

    With a ``tolerance``, each number of ``expected`` matches a number of ``actual`` within it.
    """
    numbers: list[float] = []

    def line_pattern(line: str) -> str:
        pieces = []
        for part in line.rstrip().split("..."):
            if tolerance <= 0:
                pieces.append(re.escape(part))
                continue
            position, pattern = 0, ""
            for match in NUMBER.finditer(part):
                pattern += re.escape(part[position : match.start()]) + f"({NUMBER.pattern})"
                numbers.append(float(match[0]))
                position = match.end()
            pieces.append(pattern + re.escape(part[position:]))
        return ".*".join(pieces) + r"[ \t]*\n"

    patterns = []
    for line in expected.rstrip("\n").split("\n"):
        patterns.append(r"(?:.*\n)*?" if line.strip() == "..." else line_pattern(line))
    match = re.fullmatch("".join(patterns), actual.rstrip("\n") + "\n")
    if match is None:
        return False
    return all(abs(float(got) - want) <= tolerance for got, want in zip(match.groups(), numbers, strict=True))
