"""A griffe extension for the API reference (mkdocs.yml): the docstrings' reStructuredText habits as Markdown.

The docstrings are written to be read in the source, with a few reStructuredText habits that Markdown
would print as they are:

- a role, ``:class:`~bt_arrange.errors.PerceptionError```: a code span of the name (its last part
  with ``~``, as Sphinx shows it);
- a paragraph ending ``::`` and the indented block after it: a colon, and the block fenced as text
  (trees drawn with box characters stay as drawn);
- a doctest (``>>>`` lines and their output): fenced as a Python console session.

The source is not changed; only the text mkdocstrings renders.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|attr|mod|data|exc|obj|const):`(~?)([^`]+)`")


def _role(match: re.Match[str]) -> str:
    name = match[2]
    return f"`{name.rpartition('.')[2] if match[1] else name}`"


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip(" "))


def to_markdown(text: str) -> str:
    """The docstring ``text`` with roles, literal blocks and doctests as Markdown."""
    lines = ROLE.sub(_role, text).split("\n")
    out: list[str] = []
    index = 0
    while index < len(lines):
        line = lines[index]
        if line.rstrip().endswith("::") and index + 1 < len(lines) and not lines[index + 1].strip():
            base = _indent(line)
            end = index + 2
            while end < len(lines) and (not lines[end].strip() or _indent(lines[end]) > base):
                end += 1
            block = lines[index + 2 : end]
            while block and not block[-1].strip():
                block.pop()
            if block:
                inner = min(_indent(text) for text in block if text.strip())
                stem = line.rstrip()[:-2].rstrip()
                out.append((stem + ":") if stem.strip() else "")
                out += [
                    "",
                    " " * base + "```text",
                    *(" " * base + text[inner:] for text in block),
                    " " * base + "```",
                    "",
                ]
                index = end
                continue
        if line.lstrip().startswith(">>> "):
            base = _indent(line)
            end = index
            while end < len(lines) and lines[end].strip():
                end += 1
            out += [" " * base + "```pycon", *lines[index:end], " " * base + "```"]
            index = end
            continue
        out.append(line)
        index += 1
    return "\n".join(out)


class DocstringMarkdown(griffe.Extension):
    """Rewrites every docstring griffe loads with ``to_markdown``."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        """Rewrite ``obj``'s docstring, once, as griffe visits it."""
        if obj.docstring is not None:
            obj.docstring.value = to_markdown(obj.docstring.value)
