"""The XML writer: a tree as a BehaviorTree.CPP v4 document with the ``TreeNodesModel`` Groot2 needs.

Every node is written from its registered model (``registry.model_of``): its tag, its ``name``
and each port's text; a port whose text is its default's is left out. Each part of a plan (the
subtree ``render_part`` marks with its ``part``, with the decorators right above it) is a
``<SubTree>`` of a ``<BehaviorTree>`` declared once: the part's values are the SubTree's ports
(``obj``, ``colour``, ``target_pose``, the thresholds), written ``{obj}`` inside, and its results
are remapped to the part's own blackboard entries (``offset_mm="{/red/offset_mm}"``). Parts whose
subtrees read the same with their own ports share one definition (the four cubes: one, four
SubTrees); a part whose subtree would not read back exactly as it is stays inline.

The ``TreeNodesModel`` lists the non-builtin nodes the file uses, sorted by tag, with the ports
the file writes (``model="full"``: every port, with descriptions, for an editor's palette), and
the SubTrees' ports with their defaults (the thresholds, written once there).

The Groot2 publisher (``bt_arrange.groot2``) asks for two more things: ``uids`` writes each node's
``_uid`` (BehaviorTree.CPP's ``WriteTreeToXML`` metadata, which Groot2 matches with the status
buffer), and ``generic=True`` writes a node of no registered model under its class name with no
ports (a user's Python tree can be watched even where it cannot be saved as XML).
"""

from __future__ import annotations

import dataclasses
import re
import reprlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any
from xml.sax.saxutils import escape, quoteattr

import py_trees

from bt_arrange.behaviours import keys
from bt_arrange.errors import PortValueError, XmlTreeError
from bt_arrange.geometry import PlanarPose
from bt_arrange.ports import ENTRY, KEY, LIMIT, OFF_DOUBLE, PLANAR_POSE, STRING, Port
from bt_arrange.xmltree.registry import NodeModel, generic_model, model_of

#: Values in messages: a few items, each cut short (``reprlib.Repr`` takes keywords from Python 3.12 only).
_SHORT = reprlib.Repr()
_SHORT.maxlist, _SHORT.maxother, _SHORT.maxstring = 2, 40, 40

FORMAT_VERSION = "4"

#: The entries a part's SubTree remaps to its own blackboard namespace: the results the report reads.
PART_RESULTS = (
    keys.OFFSET_MM,
    keys.YAW_ERROR_DEG,
    keys.PLACED_OFFSET_MM,
    keys.PLACED_YAW_ERROR_DEG,
    keys.CORRECTIONS,
)
#: A part's SubTree ports that hold values, in the order written; the thresholds are the model's defaults.
PART_VALUES = ("obj", "colour", "target_pose", "threshold_mm", "yaw_threshold_deg")
_SHARED_DEFAULTS = ("threshold_mm", "yaw_threshold_deg")


def substitute(text: str, literals: Mapping[str, str]) -> str:
    """``text`` with each ``{port}`` of ``literals`` replaced by its text (other braces left as they are)."""
    return re.sub(r"\{(\w+)\}", lambda match: literals.get(match.group(1), match.group(0)), text)


@dataclass(frozen=True)
class SubTreePart:
    """A part read from a ``<SubTree>`` (its ports), marked on the subtree's root: written again as a SubTree."""

    obj: str
    colour: str
    x_m: float
    y_m: float
    yaw_rad: float
    tree_id: str


@dataclass
class _Element:
    """One element to write: its tag, its attributes (name, text, port or None) and its children."""

    tag: str
    attributes: list[tuple[str, str, Port | None]]
    children: list[_Element] = field(default_factory=list)
    node: Any = None
    category: str = ""

    def signature(self) -> tuple[Any, ...]:
        """What the element says, but for the ``_uid`` the Groot2 view numbers it with."""
        return (
            self.tag,
            tuple((name, text) for name, text, _ in self.attributes if name != "_uid"),
            tuple(child.signature() for child in self.children),
        )


def to_xml(
    root: py_trees.behaviour.Behaviour,
    tree_id: str = "MainTree",
    *,
    comment: str | None = None,
    uids: Mapping[py_trees.behaviour.Behaviour, int] | None = None,
    generic: bool = False,
    subtrees: bool = True,
    model: str = "used",
    subtree_uids: Mapping[py_trees.behaviour.Behaviour, int] | None = None,
) -> str:
    """The tree as a BehaviorTree.CPP v4 document, with the ``TreeNodesModel`` of the non-builtin nodes it uses.

    ``uids`` (node to number) adds each node's ``_uid`` attribute; ``generic`` writes an unregistered
    node under its class name instead of refusing it. ``subtrees`` (default True) writes each part
    as a ``<SubTree>``; ``model="full"`` lists every port of each node in the ``TreeNodesModel``
    (default ``"used"``: the ports the file writes).

    With ``uids`` the parts are written as BehaviorTree.CPP's publisher serves its SubTrees to Groot2:
    each ``<SubTree>`` has its own ``_uid`` (``subtree_uids``, by the part's top node, as
    ``subtree_roots`` finds them) and its own ``<BehaviorTree ID=... _fullpath="ID::UID">`` with the
    part's nodes as they are (their own names and values, each with its ``_uid``).
    """
    if model not in ("used", "full"):
        raise XmlTreeError(f"model={model!r} is not 'used' or 'full'")
    used: dict[str, NodeModel] = {}
    options = _Options(uids or {}, generic)
    main = _element(root, used, options)
    # The Groot2 view: a part is a SubTree only where its SubTree has a UID (none given: all inline).
    parts = _Parts(root, dict(subtree_uids or {}) if uids else None)
    if subtrees:
        parts.extract(main)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    if comment:
        lines.append(f"<!-- {comment.replace('--', '- -')} -->")
    lines.append(f'<root BTCPP_format="{FORMAT_VERSION}" main_tree_to_execute={quoteattr(tree_id)}>')
    served = ' _fullpath=""' if uids else ""
    for identity, fullpath, top in [(tree_id, None, main), *parts.trees]:
        shown = served if fullpath is None else f" _fullpath={quoteattr(fullpath)}"
        lines.append(f"  <BehaviorTree ID={quoteattr(identity)}{shown}>")
        _write(top, lines, 2)
        lines.append("  </BehaviorTree>")
    written = _written_ports(main, [top for _, _, top in parts.trees])
    subtree_ports = parts.ports
    lines.append("  <TreeNodesModel>")
    for tag in sorted(used):
        node_model = used[tag]
        if node_model.builtin:
            continue
        ports = [p for p in node_model.ports if model == "full" or p.name in written.get(tag, ())]
        if not ports and model != "full":
            lines.append(f"    <{node_model.category} ID={quoteattr(node_model.tag)}/>")
            continue
        lines.append(f"    <{node_model.category} ID={quoteattr(node_model.tag)}>")
        for port in ports:
            lines.append("      " + _port_model(port, described=model == "full"))
        if node_model.description and model == "full":
            lines.append(
                f"      <MetadataFields><Metadata description={quoteattr(node_model.description)}/></MetadataFields>"
            )
        lines.append(f"    </{node_model.category}>")
    for identity, declared in subtree_ports.items():
        lines.append(f"    <SubTree ID={quoteattr(identity)}>")
        for name, direction, default in declared:
            shown = "" if default is None else f" default={quoteattr(default)}"
            lines.append(f"      <{direction}_port name={quoteattr(name)}{shown}/>")
        lines.append("    </SubTree>")
    lines.append("  </TreeNodesModel>")
    lines.append("</root>")
    return "\n".join(lines) + "\n"


def _port_model(port: Port, described: bool) -> str:
    if port.entry:
        default = f" default={quoteattr('{' + port.name + '}')}"
    elif port.required:
        default = ""
    else:
        default = f" default={quoteattr(port.type.format(port.default))}"
    tag = f"{port.direction}_port"
    opening = f"<{tag} name={quoteattr(port.name)} type={quoteattr(port.type.name)}{default}"
    if not described:
        return opening + "/>"
    return f"{opening}>{escape(port.description)}</{tag}>"


def _written_ports(main: _Element, definitions: Any) -> dict[str, set[str]]:
    written: dict[str, set[str]] = {}
    stack = [main, *definitions]
    while stack:
        element = stack.pop()
        stack.extend(element.children)
        written.setdefault(element.tag, set()).update(name for name, _, port in element.attributes if port is not None)
    return written


class _Options:
    def __init__(self, uids: Mapping[py_trees.behaviour.Behaviour, int], generic: bool) -> None:
        self.uids = uids
        self.generic = generic


def _element(node: py_trees.behaviour.Behaviour, used: dict[str, NodeModel], options: _Options) -> _Element:
    try:
        model = model_of(node)
    except XmlTreeError:
        if not options.generic:
            raise
        model = generic_model(type(node))
    if node.children and model.children == "none":
        if not options.generic:
            # A leaf that builds its children as it runs (ArrangeSolved): a file holds the leaf, never what it built.
            node_children: list[py_trees.behaviour.Behaviour] = []
        else:
            # The Groot2 view shows what it built, so the model is a control node's (a leaf has no children).
            model = dataclasses.replace(model, category="Control")
            node_children = list(node.children)
    else:
        node_children = list(node.children)
    used[model.tag] = model
    attributes: list[tuple[str, str, Port | None]] = [("name", node.name, None)]
    if node in options.uids:
        attributes.append(("_uid", str(options.uids[node]), None))
    for port, text in _port_texts(node, model):
        if not port.required and text == port.type.format(port.default):
            continue
        attributes.append((port.name, text, port))
    children = [_element(child, used, options) for child in node_children]
    return _Element(model.tag, attributes, children, node, model.category)


def _write(element: _Element, lines: list[str], depth: int) -> None:
    indent = "  " * depth
    shown = " ".join(f"{name}={quoteattr(text)}" for name, text, _ in element.attributes)
    opening = f"{indent}<{element.tag}{' ' + shown if shown else ''}"
    if not element.children:
        lines.append(opening + "/>")
        return
    lines.append(opening + ">")
    for child in element.children:
        _write(child, lines, depth + 1)
    lines.append(f"{indent}</{element.tag}>")


class _Parts:
    """Turns each part's subtree into a ``<SubTree>`` of a shared ``<BehaviorTree>`` (see the module)."""

    def __init__(
        self, root: py_trees.behaviour.Behaviour, served: Mapping[py_trees.behaviour.Behaviour, int] | None = None
    ) -> None:
        plan = getattr(root, "plan", None)
        tolerance = getattr(plan, "tolerance", None)
        self.thresholds = (
            {}
            if tolerance is None
            else {
                "threshold_mm": LIMIT.format(tolerance.threshold_mm),
                "yaw_threshold_deg": OFF_DOUBLE.format(tolerance.yaw_threshold_deg),
            }
        )
        #: The SubTrees' uids by their parts' top nodes: the Groot2 view (each part's own tree, as it is).
        self.served = served
        #: The BehaviorTrees besides the main one: ID, ``_fullpath`` (the Groot2 view only), root element.
        self.trees: list[tuple[str, str | None, _Element]] = []
        self.definitions: dict[str, _Element] = {}
        #: Each definition's SubTree ports: name, direction, default.
        self.ports: dict[str, list[tuple[str, str, str | None]]] = {}
        #: The top node of each part written as a SubTree.
        self.tops: list[py_trees.behaviour.Behaviour] = []
        #: Per definition: its template's signature, and the values of each instance.
        self.signatures: dict[tuple[Any, ...], str] = {}
        self.instances: dict[str, list[_Element]] = {}

    def extract(self, main: _Element) -> None:
        """Replace each part's subtree under ``main`` by its ``<SubTree>``, in the tree's order."""
        self._replace(main)
        self._finish()

    def _replace(self, element: _Element) -> None:
        for index, child in enumerate(element.children):
            part = _part_below(child)
            instance = self._instance(child, part) if part is not None else None
            if instance is None:
                self._replace(child)
            else:
                element.children[index] = instance

    def _instance(self, element: _Element, part: Any) -> _Element | None:
        values = {
            "obj": str(part.obj),
            "colour": str(part.colour),
            "target_pose": PLANAR_POSE.format(PlanarPose(part.x_m, part.y_m, part.yaw_rad)),
            **self.thresholds,
        }
        template, used = _template(element, values)
        if self.served is not None and element.node not in self.served:
            return None
        if _expand(template, {name: values[name] for name in used}, values["obj"]).signature() != element.signature():
            return None  # it would not read back as it is: inline
        signature = template.signature()
        identity = self.signatures.get(signature)
        if identity is None:
            identity = _identity(part, self.definitions)
            self.signatures[signature] = identity
            self.definitions[identity] = template
            if self.served is None:
                self.trees.append((identity, None, template))
            self.ports[identity] = [(name, "input", None) for name in PART_VALUES if name in used]
            self.ports[identity] += [(name, "output", None) for name in PART_RESULTS]
            self.instances[identity] = []
        attributes: list[tuple[str, str, Port | None]] = [("ID", identity, None)]
        self.tops.append(element.node)
        if self.served is not None:
            uid = self.served.get(element.node)
            fullpath = f"{identity}::{uid}"
            attributes += [("_fullpath", fullpath, None), ("_uid", str(uid), None)]
            self.trees.append((identity, fullpath, element))
        attributes += [(name, values[name], None) for name in PART_VALUES if name in used]
        attributes += [(name, "{" + keys.key(values["obj"], name) + "}", None) for name in PART_RESULTS]
        instance = _Element("SubTree", attributes)
        self.instances[identity].append(instance)
        return instance

    def _finish(self) -> None:
        """Each threshold all of a definition's instances share is its SubTree port's default, written once."""
        for identity, instances in self.instances.items():
            declared = self.ports[identity]
            for shared in _SHARED_DEFAULTS:
                texts = {text for instance in instances for name, text, _ in instance.attributes if name == shared}
                if len(texts) != 1:
                    continue
                (text,) = texts
                self.ports[identity] = declared = [
                    (name, direction, text if name == shared else default) for name, direction, default in declared
                ]
                for instance in instances:
                    instance.attributes = [item for item in instance.attributes if item[0] != shared]


def subtree_roots(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    """The top nodes of the parts ``to_xml`` writes as SubTrees, in the tree's order (for the Groot2 view's uids)."""
    parts = _Parts(root)
    parts.extract(_element(root, {}, _Options({}, True)))
    return parts.tops


def _part_below(element: _Element) -> Any:
    """The part whose subtree ``element`` is (its marked root, or decorators of one child right above it)."""
    while True:
        part = getattr(element.node, "part", None)
        if part is not None and hasattr(part, "obj"):
            return part
        if element.category != "Decorator" or len(element.children) != 1:
            return None
        element = element.children[0]


def _identity(part: Any, taken: Mapping[str, Any]) -> str:
    stem = getattr(part, "tree_id", None)
    if not stem:
        kind = getattr(getattr(part, "object_type", None), "name", "") or "part"
        stem = "arrange_" + re.sub(r"\W+", "_", kind).strip("_")
    identity, number = stem, 1
    while identity in taken:
        number += 1
        identity = f"{stem}_{number}"
    return identity


def _template(element: _Element, values: Mapping[str, str]) -> tuple[_Element, set[str]]:
    """``element`` with the part's values as ``{port}`` references and its own keys as relative entries."""
    obj = values["obj"]
    used: set[str] = set()
    own = re.compile(rf"(?<![\w{{}}]){re.escape(obj)}(?![\w{{}}])")

    def build(source: _Element) -> _Element:
        node_obj = next((text for name, text, _ in source.attributes if name == "obj"), None)
        attributes: list[tuple[str, str, Port | None]] = []
        for name, text, port in source.attributes:
            if name == "_uid":
                continue
            if port is None:
                if name == "name" and "{" not in text and "}" not in text and own.search(text):
                    text = own.sub("{obj}", text)
                    used.add("obj")
                attributes.append((name, text, port))
                continue
            if port.type in (KEY, ENTRY):
                prefix = "{/" + obj + "/"
                if text.startswith(prefix) and "/" not in text[len(prefix) : -1] and text.endswith("}"):
                    if port.type is KEY or node_obj == obj:
                        text = "{" + text[len(prefix) :]
                        if port.entry and text == "{" + port.name + "}":
                            continue  # the entry's default: the part's own
                attributes.append((name, text, port))
                continue
            for reference in PART_VALUES:
                value = values.get(reference)
                if value is None or text != value:
                    continue
                if reference == "obj" and port.type is not STRING:
                    continue
                if reference == "colour" and name != "colour":
                    continue
                if reference == "target_pose" and port.type is not PLANAR_POSE:
                    continue
                if reference in _SHARED_DEFAULTS and name != reference:
                    continue
                text = "{" + reference + "}"
                used.add(reference)
                break
            attributes.append((name, text, port))
        return _Element(source.tag, attributes, [build(child) for child in source.children], None, source.category)

    return build(element), used


def _expand(template: _Element, literals: Mapping[str, str], obj: str) -> _Element:
    """What the reader makes of ``template`` with these ports: ``_template`` undone (the check that it reads back)."""
    attributes: list[tuple[str, str, Port | None]] = []
    for name, text, port in template.attributes:
        if port is None:
            if name == "name" and literals and "{" in text:
                text = substitute(text, literals)
        elif port.type in (KEY, ENTRY):
            if text.startswith("{") and not text.startswith("{/"):
                text = "{" + keys.key(obj, text[1:-1]) + "}"
        elif text.startswith("{") and text.endswith("}") and text[1:-1] in literals:
            text = literals[text[1:-1]]
        attributes.append((name, text, port))
    return _Element(
        template.tag,
        attributes,
        [_expand(child, literals, obj) for child in template.children],
        None,
        template.category,
    )


def _port_texts(node: py_trees.behaviour.Behaviour, model: NodeModel) -> list[tuple[Port, str]]:
    """Each port of ``node`` with its value's text; a value its type cannot write names the node and the port."""
    try:
        values = model.ports_of(node)
    except AttributeError as error:
        raise XmlTreeError(
            f"cannot write {node.name!r} as XML: <{model.tag}> has no attribute for a port: {error}"
        ) from error
    texts = []
    for port in model.ports:
        if port.name not in values:
            raise XmlTreeError(f"cannot write {node.name!r} as XML: <{model.tag}> gave no value for port {port.name!r}")
        try:
            texts.append((port, port.type.format(values[port.name])))
        except PortValueError as error:
            # A value's repr can run to thousands of characters (a plan's targets): the reason names it.
            raise XmlTreeError(
                f"cannot write {node.name!r} as XML: <{model.tag}> {port.name}={_SHORT.repr(values[port.name])} "
                f"is not a {port.type.name}: {error.reason}"
            ) from error
    return texts
