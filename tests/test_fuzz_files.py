"""Fuzzing the readers of shared files with hypothesis: every input is a valid object or a one-line error.

The plan loader (``plans.load``), the XML tree loader (``xmltree.load_xml``) and the calibration
reader (``read_calibration``) each get random bytes, the shipped files with random edits (slices
cut, repeated, or replaced with tokens of the format), and random structures written as TOML or XML
(the format's own keys, ports and tags, with values of every type). Whatever comes in, the reader
returns what it promises or raises a ``BtArrangeError`` of one line; any other exception is a
finding. Example counts are modest (the suite's seconds), and each reader's work is bounded by the
file limits (``bt_arrange.filelimits``), which ``tests/test_outline_limits.py`` counts.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from collections.abc import Callable
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import py_trees
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bt_arrange import plans, xmltree
from bt_arrange.calibration import CameraCalibration, read_calibration
from bt_arrange.errors import BtArrangeError

ROOT = Path(__file__).resolve().parents[1]
# The fresco example is left out of the edited files: each fracture it asks for takes a second.
PLAN_TEXTS = [p.read_text() for p in sorted((ROOT / "bt_arrange" / "examples").glob("*.toml")) if p.stem != "fresco"]
XML_TEXTS = [p.read_text() for p in sorted((ROOT / "trees").glob("*.xml")) if p.stat().st_size < 20000]
CALIBRATION_TEXT = """cell = "real"
date = "2026-12-01T10:00:00+00:00"
width_px = 1920
height_px = 1080
fx_px = 1371.0
fy_px = 1371.0
cx_px = 959.5
cy_px = 539.5
distortion = [-0.12, 0.06, 0.0008, -0.0005, 0.0]
reprojection_error_px = 0.12
views = 18

[camera_to_base]
x_mm = 500.0
y_mm = 0.0
z_mm = 700.0
roll_deg = 180.0
pitch_deg = 0.0
yaw_deg = -93.0
"""

FUZZ = settings(
    max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)


def judged(read: Callable[[Path], Any], path: Path, promised: type) -> None:
    """``read(path)`` is a ``promised`` or a one-line ``BtArrangeError``; anything else fails the test."""
    try:
        result = read(path)
    except BtArrangeError as error:
        message = str(error)
        assert message.strip() and "\n" not in message, repr(message)
        return
    assert isinstance(result, promised), type(result)


# ----------------------------------------------------------------------------------------------
# Edits of a file's text, and TOML written from random structures
# ----------------------------------------------------------------------------------------------

TOML_TOKENS = ["nan", "inf", "-inf", "-1", "0", "1e308", "9" * 40, "[", "]", "{", "}", '"', "'", "=", ",", ".",
               "\n[[targets]]\n", "\n[objects.x]\n", "\n[colours.x]\n", "\n[fresco.x]\n", "\n[scene]\n", "\\u0000",
               "true", "1979-05-27", "[[0, 0], [60, 0], [15, 45]]", "\ufeff", "\x00"]  # fmt: skip
XML_TOKENS = ["<", ">", "/>", "</", "<Sequence>", "</Sequence>", '<SubTree ID="A"/>', '<SubTree ID="MainTree"/>',
              "&amp;", "&#0;", "&lt;", "<!DOCTYPE r [<!ENTITY a 'b'>]>", "<![CDATA[x]]>", '"', "=", "nan", "-1",
              "1e9", '<BehaviorTree ID="A">', "</BehaviorTree>", '<Repeat num_cycles="-1">', "\x00",
              "\ufeff"]  # fmt: skip


@st.composite
def edited(draw: st.DrawFn, texts: list[str], tokens: list[str]) -> str:
    """One of ``texts`` with one to four edits: a slice cut, repeated, or replaced with tokens or text."""
    text = draw(st.sampled_from(texts))
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(text)))
        j = draw(st.integers(i, min(len(text), i + 60)))
        kind = draw(st.sampled_from(["cut", "repeat", "replace", "insert"]))
        new = draw(st.one_of(st.sampled_from(tokens), st.text(max_size=6)))
        if kind == "cut":
            text = text[:i] + text[j:]
        elif kind == "repeat":
            text = text[:j] + text[i:j] * draw(st.integers(1, 3)) + text[j:]
        elif kind == "replace":
            text = text[:i] + new + text[j:]
        else:
            text = text[:i] + new + text[i:]
    return text


def toml_value(value: Any) -> str:
    """A value written as TOML (inline tables and arrays, so any nesting is one line)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        escaped = "".join(c if c.isprintable() and c not in '"\\' else f"\\u{ord(c):04x}" for c in value)
        return f'"{escaped}"'
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


def toml_key(key: str) -> str:
    return key if key and all(c.isalnum() or c in "_-" for c in key) and key.isascii() else toml_value(key)


def toml_text(data: dict[str, Any]) -> str:
    return "".join(f"{toml_key(key)} = {toml_value(value)}\n" for key, value in data.items())


scalars = st.one_of(
    st.booleans(),
    st.integers(-(2**63), 2**63 - 1),
    st.integers(-100, 900),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-1000, 1000),
    st.text(max_size=8),
    st.sampled_from(["cube", "red", "green", "blue", "orange", "ell", "each", "after_all", "x", ""]),
)
values = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
    max_leaves=10,
)
points = st.lists(st.lists(st.floats(-100, 100) | st.integers(-100, 100), min_size=1, max_size=3), max_size=8)


def table(keys: tuple[str, ...], extra: st.SearchStrategy[Any] = values) -> st.SearchStrategy[dict[str, Any]]:
    """Dictionaries of the format's ``keys`` (and now and then another), with any values."""
    return st.dictionaries(st.sampled_from([*keys, "bogus"]), st.one_of(values, extra), max_size=len(keys) + 1)


plan_structures = st.fixed_dictionaries(
    {},
    optional={
        "threshold_mm": values,
        "yaw_threshold_deg": values,
        "correct": values,
        "max_pushes": values,
        "objects": st.dictionaries(st.sampled_from(["ell", "bar", "cube", "x y"]), table(plans.OBJECT_KEYS, points),
                                   max_size=3),
        "colours": st.dictionaries(st.sampled_from(["orange", "red", "teal"]), table(plans.COLOUR_KEYS), max_size=2),
        "targets": st.lists(table(plans.TARGET_KEYS), max_size=4) | values,
        "fresco": st.dictionaries(st.sampled_from(["tile"]), table(plans.FRESCO_KEYS), max_size=1),
        "scene": table(plans.SCENE_KEYS, st.lists(table(plans.START_KEYS), max_size=3)),
        "bogus": values,
    },
)  # fmt: skip


def _cheap_frescoes(data: dict[str, Any]) -> dict[str, Any]:
    """At most three pieces a fresco: a fracture of many pieces takes a second, too long for many examples."""
    for entry in (data.get("fresco") or {}).values():
        if isinstance(entry, dict) and isinstance(entry.get("pieces"), int) and entry["pieces"] > 3:
            entry["pieces"] = 3
    return data


calibration_structures = st.fixed_dictionaries(
    {},
    optional={
        **{key: st.one_of(values, st.floats(-2000, 3000), st.integers(-10, 3000)) for key in
           ("cell", "date", "width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px", "reprojection_error_px",
            "views", "skipped_views", "hand_eye_residual_mm", "board", "lens")},
        "distortion": st.lists(st.floats(allow_nan=True) | st.integers(-3, 3) | st.text(max_size=2), max_size=15),
        "camera_to_base": table(("x_mm", "y_mm", "z_mm", "roll_deg", "pitch_deg", "yaw_deg"), st.floats(-200, 200)),
    },
)  # fmt: skip


# ----------------------------------------------------------------------------------------------
# The plan loader
# ----------------------------------------------------------------------------------------------


@FUZZ
@given(data=st.binary(max_size=400))
def test_random_bytes_are_a_plan_or_one_line(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "plan.toml"
    path.write_bytes(data)
    judged(plans.load, path, plans.Plan)


@FUZZ
@given(text=edited(PLAN_TEXTS, TOML_TOKENS))
def test_an_edited_shipped_plan_is_a_plan_or_one_line(tmp_path: Path, text: str) -> None:
    path = tmp_path / "plan.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    judged(plans.load, path, plans.Plan)


@FUZZ
@given(data=plan_structures)
def test_a_random_plan_structure_is_a_plan_or_one_line(tmp_path: Path, data: dict[str, Any]) -> None:
    path = tmp_path / "plan.toml"
    path.write_text(toml_text(_cheap_frescoes(data)), encoding="utf-8", errors="surrogatepass")
    judged(plans.load, path, plans.Plan)


# ----------------------------------------------------------------------------------------------
# The XML tree loader
# ----------------------------------------------------------------------------------------------


def _attribute_values() -> list[str]:
    """Every attribute value of the shipped XML trees: the ports' own texts (targets, poses, colours)."""
    found: set[str] = set()
    for text in XML_TEXTS:
        for element in ElementTree.fromstring(text).iter():
            found.update(element.attrib.values())
    return sorted(found)


SHIPPED_VALUES = _attribute_values()
tags = st.sampled_from([*xmltree.registry.REGISTRY, "SubTree", "BehaviorTree", "Sequense", "TreeNodesModel", "root"])
ports = sorted({p.name for m in xmltree.registry.REGISTRY.values() for p in m.ports} | {"name", "ID", "_skipIf"})
attributes = st.dictionaries(
    st.sampled_from(ports), st.one_of(st.sampled_from(SHIPPED_VALUES), st.text(max_size=8), st.sampled_from(
        ["-1", "0", "1e9", "nan", "inf", "{x}", "red", "A", "B", "MainTree", "true", "0.5,0,0"])), max_size=3,
)  # fmt: skip
nodes = st.recursive(
    st.tuples(tags, attributes, st.just(())),
    lambda children: st.tuples(tags, attributes, st.lists(children, max_size=3)),
    max_leaves=12,
)


def _xml(node: tuple[str, dict[str, str], tuple | list]) -> str:
    tag, attrs, children = node
    text = "".join(f" {key}={quoteattr(value)}" for key, value in attrs.items())
    inner = "".join(_xml(child) for child in children)
    return f"<{tag}{text}>{inner}</{tag}>" if inner else f"<{tag}{text}/>"


@FUZZ
@given(data=st.binary(max_size=400))
def test_random_bytes_are_a_tree_or_one_line(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "tree.xml"
    path.write_bytes(data)
    judged(xmltree.load_xml, path, py_trees.behaviour.Behaviour)


@FUZZ
@given(text=edited(XML_TEXTS, XML_TOKENS))
def test_an_edited_shipped_tree_is_a_tree_or_one_line(tmp_path: Path, text: str) -> None:
    path = tmp_path / "tree.xml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    judged(xmltree.load_xml, path, py_trees.behaviour.Behaviour)


@FUZZ
@given(trees=st.dictionaries(st.sampled_from(["MainTree", "A", "B"]), nodes, min_size=1, max_size=3),
       main=st.sampled_from([None, "MainTree", "A", "Z"]))  # fmt: skip
def test_a_random_xml_structure_is_a_tree_or_one_line(tmp_path: Path, trees: dict, main: str | None) -> None:
    body = "".join(f'<BehaviorTree ID="{tree_id}">{_xml(node)}</BehaviorTree>' for tree_id, node in trees.items())
    chosen = f' main_tree_to_execute="{main}"' if main else ""
    path = tmp_path / "tree.xml"
    path.write_text(f'<root BTCPP_format="4"{chosen}>{body}</root>', encoding="utf-8", errors="surrogatepass")
    judged(xmltree.load_xml, path, py_trees.behaviour.Behaviour)


# ----------------------------------------------------------------------------------------------
# The calibration reader
# ----------------------------------------------------------------------------------------------


def test_the_calibration_the_fuzzing_starts_from_is_valid(tmp_path: Path) -> None:
    path = tmp_path / "camera.toml"
    path.write_text(CALIBRATION_TEXT)
    assert isinstance(read_calibration(path), CameraCalibration)


@FUZZ
@given(data=st.binary(max_size=400))
def test_random_bytes_are_a_calibration_or_one_line(tmp_path: Path, data: bytes) -> None:
    path = tmp_path / "camera.toml"
    path.write_bytes(data)
    judged(read_calibration, path, CameraCalibration)


@FUZZ
@given(text=edited([CALIBRATION_TEXT], TOML_TOKENS))
def test_an_edited_calibration_is_a_calibration_or_one_line(tmp_path: Path, text: str) -> None:
    path = tmp_path / "camera.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    judged(read_calibration, path, CameraCalibration)


@FUZZ
@given(data=calibration_structures)
def test_a_random_calibration_structure_is_a_calibration_or_one_line(tmp_path: Path, data: dict[str, Any]) -> None:
    path = tmp_path / "camera.toml"
    path.write_text(toml_text(data), encoding="utf-8", errors="surrogatepass")
    judged(read_calibration, path, CameraCalibration)


@pytest.mark.parametrize("reader", [plans.load, xmltree.load_xml, read_calibration], ids=["plan", "xml", "calibration"])
def test_a_folder_or_a_missing_file_is_one_line(tmp_path: Path, reader: Callable[[Path], Any]) -> None:
    for path in (tmp_path, tmp_path / "missing"):
        with pytest.raises(BtArrangeError) as raised:
            reader(path)
        assert "\n" not in str(raised.value)
