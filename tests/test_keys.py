"""The blackboard keys a user never types: one helper per field, and a table that says when each is written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bt_arrange.behaviours import keys

ROOT = Path(__file__).resolve().parents[1]
#: The field constants (``keys.POSE`` ...); ``STALLED``, ``WHOLE_FACE``, ``FREE_EDGES``, ``NOT_MEASURED`` and
#: ``TOUCHING_PARTS``, ``LOOKED_IN_FINGERS``, ``SET_DOWN``, ``NOT_BLOCKED`` and ``ALLOWED`` are values of a key,
#: ``TARGET_SETTER`` a writer's name.
FIELDS = {
    name: value
    for name, value in vars(keys).items()
    if name.isupper()
    and isinstance(value, str)
    and name
    not in (
        "STALLED",
        "WHOLE_FACE",
        "FREE_EDGES",
        "NOT_MEASURED",
        "TOUCHING_PARTS",
        "NOT_BLOCKED",
        "ALLOWED",
        "LOOKED_IN_FINGERS",
        "SET_DOWN",
        "TARGET_SETTER",
    )
}


def test_the_fields_are_the_ones_the_behaviours_use() -> None:
    assert {"POSE", "TARGET", "OFFSET_MM", "OFFSET_XY_MM", "PUSH_AXIS", "YAW_ERROR_DEG"} <= set(FIELDS)


@pytest.mark.parametrize("field", sorted(FIELDS.values()))
def test_each_field_has_a_helper_that_gives_a_parts_key(field: str) -> None:
    helper = getattr(keys, field, None)
    assert callable(helper), f"keys.{field}(obj) is missing"
    assert helper("red") == keys.key("red", field) == f"/red/{field}"
    assert keys.object_of_key(helper("slab 3")) == "slab 3"


def test_the_helpers_read_as_the_docs_show() -> None:
    assert keys.pose("red") == "/red/pose"
    assert keys.offset_mm("red") == "/red/offset_mm"
    assert keys.push_axis("blue") == "/blue/push_axis"
    assert keys.target("green") == "/green/target"


@pytest.mark.parametrize("where", ["keys.py", "docs/behaviours.md"])
def test_every_key_is_in_the_table_with_when_it_is_written(where: str) -> None:
    text = (keys.__doc__ or "") if where == "keys.py" else (ROOT / where).read_text(encoding="utf-8")
    for field in FIELDS.values():
        line = next((line for line in _entries(text) if f"/<obj>/{field}`" in line), None)
        assert line is not None, f"{where} does not list /<obj>/{field}"
        assert re.search(r"\b(as|when|each time|once|before|after)\b", line), f"{where}: when is {field} written?"
    assert "next* push" in text or "*next* push" in text, "push_axis is the axis of the next push"
    assert not re.search(r"\(issue \d+\)", text), f"{where}: the table cites an issue number"


def _entries(text: str) -> list[str]:
    """Table rows and list items, each as one line (a list item's continuation lines joined)."""
    entries: list[str] = []
    for line in text.split("\n"):
        if line.startswith(("|", "- ")):
            entries.append(line)
        elif line.startswith("  ") and entries and entries[-1].startswith("- "):
            entries[-1] += " " + line.strip()
    return entries
