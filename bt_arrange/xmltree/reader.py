"""The XML reader: builds a tree from a BehaviorTree.CPP v4 document, from registered nodes only.

Nothing the file names is imported or evaluated: a tag is looked up in ``REGISTRY`` and each
port's text converted by the port's declared type. Any other tag, a script attribute
(``_skipIf`` ...), a blackboard reference where a port takes a value, an ``<Include>`` or a
``<!DOCTYPE>`` is refused with a one-line ``XmlTreeError`` naming the line, the node and, for a
bad value, the port and the text.

A ``<SubTree>`` gives its tree ports, as in BehaviorTree.CPP 4: a literal (``obj="red"``), read
inside as ``{obj}`` (in a port's value, and in a name), or a remapped blackboard entry
(``offset_mm="{/red/offset_mm}"``), which a node's key or entry port inside names as
``{offset_mm}``. A blackboard entry no SubTree remaps is its object's own (``/<obj>/<entry>``).
The thresholds' defaults come from the ``TreeNodesModel``'s ``<SubTree ID=...>`` ports.
"""

from __future__ import annotations

import re
import xml.parsers.expat
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

import py_trees

from bt_arrange.behaviours import keys
from bt_arrange.errors import BtArrangeError, PortValueError, XmlTreeError
from bt_arrange.filelimits import (
    MAX_FILE_BYTES,
    MAX_OBJECT_TYPES,
    MAX_PLAN_OUTLINE_POINTS,
    MAX_TREE_DEPTH,
    MAX_TREE_NODES,
    read_limited,
    too_large,
)
from bt_arrange.ports import ENTRY, KEY, PLANAR_POSE, Port
from bt_arrange.suggest import did_you_mean
from bt_arrange.xmltree.registry import FORMER_TAGS, REGISTRY, NodeModel
from bt_arrange.xmltree.writer import FORMAT_VERSION, SubTreePart, substitute

#: Attributes BehaviorTree.CPP and Groot2 keep on any node as metadata (never code): ignored.
METADATA_ATTRIBUTES = frozenset({"_description", "_uid", "_fullpath", "_autoremap"})
#: BehaviorTree.CPP attributes whose values are scripts: code, so refused.
SCRIPT_ATTRIBUTES = frozenset(
    {"_skipIf", "_successIf", "_failureIf", "_while", "_onSuccess", "_onFailure", "_onHalted", "_post"}
)


@dataclass
class Element:
    """One XML element with the line it starts on (``xml.etree`` keeps no line numbers)."""

    tag: str
    attributes: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)


def parse_elements(text: str, source: str = "<string>") -> Element:
    """Parse XML into ``Element``s with line numbers; a ``<!DOCTYPE>`` (entities) is refused."""
    parser = xml.parsers.expat.ParserCreate()
    stack: list[Element] = []
    top: list[Element] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        if len(stack) >= MAX_TREE_DEPTH + 2:  # <root> and <BehaviorTree> above the nodes
            raise XmlTreeError(
                f"{source} line {parser.CurrentLineNumber}: elements nest more than {MAX_TREE_DEPTH} levels deep "
                "below <BehaviorTree>, the limit (bt_arrange.filelimits.MAX_TREE_DEPTH)"
            )
        element = Element(tag, dict(attributes), parser.CurrentLineNumber)
        (stack[-1].children if stack else top).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    def doctype(name: str, *args: object) -> None:
        raise XmlTreeError(f"{source} line {parser.CurrentLineNumber}: <!DOCTYPE {name}> is not allowed in an XML tree")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as error:
        raise XmlTreeError(f"{source} line {error.lineno}: not well-formed XML: {_expat_message(error)}") from error
    return top[0]


def _expat_message(error: xml.parsers.expat.ExpatError) -> str:
    return xml.parsers.expat.ErrorString(error.code) if error.code is not None else str(error)


#: An object type's text in a port's value: ``NAME=outline_mm X:Y ...`` up to the next field (``;``).
_TYPE_TEXT = re.compile(r"[^;=\s]+\s*=\s*outline_mm\b[^;]*")
#: Characters of a port's value quoted in an error (an outline's value runs to kilobytes).
_SHOWN_CHARACTERS = 120


def load_xml(path: str | Path, tree_id: str | None = None) -> py_trees.behaviour.Behaviour:
    """Build the tree of a BehaviorTree.CPP v4 file from registered nodes only."""
    path = Path(path)
    try:
        text = read_limited(path, "XML tree", XmlTreeError)
    except FileNotFoundError as error:
        raise XmlTreeError(f"cannot read XML tree {path}: {error.strerror}") from error
    return from_xml(text, source=str(path), tree_id=tree_id)


def from_xml(text: str, source: str = "<string>", tree_id: str | None = None) -> py_trees.behaviour.Behaviour:
    """Build a tree from BehaviorTree.CPP v4 XML text (see ``load_xml``), within ``bt_arrange.filelimits``."""
    size = len(text.encode("utf-8", errors="replace"))
    if size > MAX_FILE_BYTES:
        raise XmlTreeError(too_large("XML tree", source, size))
    return _Reader(parse_elements(text, source), source).build(tree_id)


class _Reader:
    def __init__(self, document: Element, source: str) -> None:
        self.source = source
        if document.tag != "root":
            self.fail(document, f'the document element is <{document.tag}>, not <root BTCPP_format="4">')
        version = document.attributes.get("BTCPP_format")
        if version != FORMAT_VERSION:
            self.fail(document, f'<root> needs BTCPP_format="4" (BehaviorTree.CPP v4), got {version!r}')
        self.document = document
        self.trees: dict[str, Element] = {}
        self.subtree_defaults: dict[str, dict[str, str]] = {}
        self.served: dict[str, Element] = {}
        for child in document.children:
            if child.tag == "BehaviorTree":
                tree_id = child.attributes.get("ID")
                if not tree_id:
                    self.fail(child, "<BehaviorTree> needs an ID")
                fullpath = child.attributes.get("_fullpath")
                if fullpath:
                    # BehaviorTree.CPP's Groot2 view: one tree per SubTree, the SubTree names it by its _fullpath.
                    self.served[fullpath] = child
                    if tree_id in self.trees:
                        continue
                elif tree_id in self.trees and "_fullpath" not in self.trees[tree_id].attributes:
                    self.fail(child, f"a second <BehaviorTree ID={tree_id!r}>")
                self.trees[tree_id] = child
            elif child.tag == "TreeNodesModel":
                # The editor's description of the nodes (the registry decides what they are), and the
                # SubTrees' ports with their defaults, which BehaviorTree.CPP 4 reads from it too.
                for model in child.children:
                    if model.tag == "SubTree" and model.attributes.get("ID"):
                        self.subtree_defaults[model.attributes["ID"]] = {
                            port.attributes["name"]: port.attributes["default"]
                            for port in model.children
                            if port.tag.endswith("_port") and "name" in port.attributes and "default" in port.attributes
                        }
            elif child.tag in ("Include", "Import"):
                self.fail(child, f"<{child.tag}> is not supported: an XML tree is one self-contained file")
            else:
                self.fail(child, f"<{child.tag}> is not allowed under <root> (BehaviorTree and TreeNodesModel are)")
        if not self.trees:
            self.fail(document, "no <BehaviorTree ID=...> in the file")

    def fail(self, element: Element, message: str) -> NoReturn:
        raise XmlTreeError(f"{self.source} line {element.line}: {message}")

    def build(self, tree_id: str | None) -> py_trees.behaviour.Behaviour:
        main = tree_id or self.document.attributes.get("main_tree_to_execute")
        if main is None:
            if len(self.trees) > 1:
                self.fail(self.document, "several <BehaviorTree>s and no main_tree_to_execute to choose one")
            main = next(iter(self.trees))
        if main not in self.trees:
            self.fail(
                self.document, f"main tree {main!r} is not one of the <BehaviorTree> IDs: {', '.join(self.trees)}"
            )
        self._check_size(main)
        self._check_object_types()
        return self._tree(self.trees[main], (), _Scope())

    def _check_object_types(self) -> None:
        """Refuse a file of more object types or outline points than a plan may hold, before any type is judged.

        Each type is judged (its grasps searched) as its port is read, so the plan's limits
        (``MAX_OBJECT_TYPES``, ``MAX_PLAN_OUTLINE_POINTS``) bound an XML tree's load too. A type is
        counted once however many ports repeat its text (``NAME=outline_mm X:Y ...``, alone or in a
        target's fields); its points are its ``X:Y`` vertices.
        """
        seen: dict[str, Element] = {}
        stack = [*self.trees.values(), *self.served.values()]
        while stack:
            element = stack.pop()
            stack.extend(element.children)
            for value in element.attributes.values():
                if "outline_mm" not in value:
                    continue
                for match in _TYPE_TEXT.finditer(value):
                    seen.setdefault(" ".join(match.group(0).split()), element)
        if len(seen) > MAX_OBJECT_TYPES:
            self.fail(
                max(seen.values(), key=lambda e: e.line),
                f"{len(seen)} object types, over the limit of {MAX_OBJECT_TYPES} "
                "(bt_arrange.filelimits.MAX_OBJECT_TYPES)",
            )
        points = sum(text.count(":") for text in seen)
        if points > MAX_PLAN_OUTLINE_POINTS:
            self.fail(
                max(seen.values(), key=lambda e: e.line),
                f"{points:,} outline points in all, over the limit of {MAX_PLAN_OUTLINE_POINTS} "
                "(bt_arrange.filelimits.MAX_PLAN_OUTLINE_POINTS)",
            )

    def _check_size(self, main: str) -> None:
        """Refuse a tree whose SubTrees expand beyond the node or depth limit, before any node is built.

        Each <BehaviorTree> is measured once (its own nodes and depth, and where it holds SubTrees),
        then the expanded sizes are summed without recursion: a file whose trees each hold two
        SubTrees of the next is refused in milliseconds, however far it would double.
        """
        local: dict[str, tuple[int, int, list[tuple[int, str, Element]]]] = {}
        # The Groot2 view's trees (one per SubTree, named by its _fullpath) are measured as trees of their own.
        trees = {**self.trees, **self.served}
        for tree_id, tree in trees.items():
            count, deepest, calls = 0, 0, []
            stack = [(child, 1) for child in tree.children]
            while stack:
                element, level = stack.pop()
                if element.tag == "SubTree":
                    fullpath = element.attributes.get("_fullpath", "")
                    called = fullpath if fullpath in self.served else element.attributes.get("ID", "")
                    calls.append((level - 1, called, element))
                    continue
                count += 1
                deepest = max(deepest, level)
                stack.extend((child, level + 1) for child in element.children)
            local[tree_id] = (count, deepest, calls)
        sizes: dict[str, tuple[int, int]] = {}
        visiting: set[str] = set()
        pending = [(main, False)]
        while pending:
            tree_id, ready = pending.pop()
            if tree_id in sizes:
                continue
            calls = [(level, called, element) for level, called, element in local[tree_id][2] if called in trees]
            if not ready:
                if tree_id in visiting:
                    return  # a cycle: _subtree names it at its line
                visiting.add(tree_id)
                pending.append((tree_id, True))
                pending.extend((called, False) for _, called, _ in calls if called not in sizes)
                continue
            if any(called not in sizes for _, called, _ in calls):
                return  # a cycle below: _subtree names it
            count, deepest, _ = local[tree_id]
            for level, called, element in calls:
                count += sizes[called][0]
                deepest = max(deepest, level + sizes[called][1])
                if count > MAX_TREE_NODES:
                    self.fail(
                        element,
                        f"<SubTree ID={called!r}>: the tree {tree_id!r} expands to more than {MAX_TREE_NODES:,} "
                        f"nodes with its SubTrees ({count:,} so far), the limit (bt_arrange.filelimits.MAX_TREE_NODES)",
                    )
                if deepest > MAX_TREE_DEPTH:
                    self.fail(
                        element,
                        f"<SubTree ID={called!r}>: the tree {tree_id!r} nests more than {MAX_TREE_DEPTH} levels deep "
                        "with its SubTrees, the limit (bt_arrange.filelimits.MAX_TREE_DEPTH)",
                    )
            if count > MAX_TREE_NODES:
                self.fail(
                    trees[tree_id],
                    f"<BehaviorTree ID={tree_id!r}> has {count:,} nodes, over the limit of {MAX_TREE_NODES:,} "
                    "(bt_arrange.filelimits.MAX_TREE_NODES)",
                )
            sizes[tree_id] = (count, deepest)
            visiting.discard(tree_id)

    def _tree(self, element: Element, entered: tuple[str, ...], scope: _Scope) -> py_trees.behaviour.Behaviour:
        if len(element.children) != 1:
            self.fail(element, f"<BehaviorTree ID={element.attributes['ID']!r}> must hold exactly one root node")
        return self._node(element.children[0], entered + (element.attributes["ID"],), scope)

    def _node(self, element: Element, entered: tuple[str, ...], scope: _Scope) -> py_trees.behaviour.Behaviour:
        if element.tag == "SubTree":
            return self._subtree(element, entered, scope)
        model = REGISTRY.get(FORMER_TAGS.get(element.tag, element.tag))
        if model is None:
            self.fail(
                element,
                f"<{element.tag}> is not a registered node{did_you_mean(element.tag, REGISTRY)} "
                f"(known: {', '.join(sorted(REGISTRY))})",
            )
        assert model is not None
        name = scope.named(element.attributes.get("name") or element.tag)
        values = self._values(element, model, name, scope)
        if model.children == "none" and element.children:
            self.fail(element, f"<{element.tag} name={name!r}> is a leaf and cannot hold children")
        if model.children == "one" and len(element.children) != 1:
            self.fail(
                element, f"<{element.tag} name={name!r}> decorates exactly one child, got {len(element.children)}"
            )
        if model.children == "many" and not element.children:
            self.fail(element, f"<{element.tag} name={name!r}> holds no children")
        children = [self._node(child, entered, scope) for child in element.children]
        try:
            return model.build(name, values, children)
        except BtArrangeError as error:
            raise XmlTreeError(f"{self.source} line {element.line}: <{element.tag} name={name!r}>: {error}") from error
        except (ValueError, TypeError, KeyError) as error:
            raise XmlTreeError(f"{self.source} line {element.line}: <{element.tag} name={name!r}>: {error}") from error

    def _values(self, element: Element, model: NodeModel, name: str, scope: _Scope) -> dict[str, Any]:
        ports = {port.name: port for port in model.ports}
        texts: dict[str, str] = {}
        for attribute, text in element.attributes.items():
            if attribute == "name" or attribute in METADATA_ATTRIBUTES:
                continue
            if attribute in SCRIPT_ATTRIBUTES:
                self.fail(element, f"<{element.tag}> {attribute}: BehaviorTree.CPP scripts are code and are not run")
            port = ports.get(attribute)
            if port is None:
                known = ", ".join(ports) or "none"
                self.fail(
                    element,
                    f"<{element.tag}> has no port {attribute!r}{did_you_mean(attribute, ports)} (its ports: {known})",
                )
            assert port is not None
            reference = _reference(text)
            if reference is not None and port.type not in (KEY, ENTRY):
                if reference not in scope.literals:
                    inside = f" (a SubTree's ports are: {', '.join(scope.literals)})" if scope.literals else ""
                    self.fail(
                        element,
                        f"<{element.tag}> {attribute}={text!r}: ports take values, not blackboard references{inside}",
                    )
                text = scope.literals[reference]
            texts[attribute] = text
        values: dict[str, Any] = {}
        for attribute, text in texts.items():
            port = ports[attribute]
            if port.type in (KEY, ENTRY):
                continue
            values[attribute] = self._parse(element, name, port, text)
        for port in model.ports:
            if port.name not in values and not port.entry and port.type is not KEY:
                if port.required:
                    self.fail(element, f"<{element.tag}> needs port {port.name!r} ({port.type.name})")
                values[port.name] = port.default
        # Blackboard keys and entries last: a relative entry ({pose}) is the node's object's (/<obj>/pose).
        namespace = values.get("obj") if "obj" in ports and isinstance(values.get("obj"), str) else None
        for port in model.ports:
            if port.type is KEY:
                given = texts.get(port.name)
                if given is None:
                    if port.required:
                        self.fail(element, f"<{element.tag}> needs port {port.name!r} ({port.type.name})")
                    values[port.name] = port.default
                    continue
                reference = _reference(given)
                values[port.name] = (
                    scope.key(reference, namespace)
                    if reference is not None
                    else self._parse(element, name, port, given)
                )
            elif port.entry:
                reference = _reference(texts.get(port.name, "")) or port.name
                key = scope.key(reference, namespace)
                values[port.name] = None if namespace is not None and key == keys.key(namespace, port.name) else key
        return values

    def _parse(self, element: Element, name: str, port: Port, text: str) -> Any:
        try:
            return port.type.parse(text)
        except PortValueError as error:  # every codec error is one (bt_arrange.ports.PortType.parse)
            shown = text if len(text) <= _SHOWN_CHARACTERS else text[: _SHOWN_CHARACTERS - 3] + "..."
            raise XmlTreeError(
                f"{self.source} line {element.line}: <{element.tag} name={name!r}> {port.name}={shown!r} "
                f"is not a {port.type.name}: {error.reason}"
            ) from error

    def _subtree(self, element: Element, entered: tuple[str, ...], scope: _Scope) -> py_trees.behaviour.Behaviour:
        """A ``<SubTree>``: its tree built with the ports the instance gives (literals, or ``{...}`` remapped keys).

        A port the instance leaves out takes its default from the file's ``<TreeNodesModel>``
        (``<SubTree ID=...>``, as BehaviorTree.CPP 4 reads it). Inside, ``{port}`` in a node's value
        or name is the port's text; a blackboard entry the SubTree does not remap is its part's own
        (``obj``: ``/<obj>/<entry>``).
        """
        subtree_id = element.attributes.get("ID", "")
        if subtree_id not in self.trees:
            self.fail(
                element,
                f"<SubTree ID={subtree_id!r}> names no <BehaviorTree> of this file"
                f"{did_you_mean(subtree_id, self.trees)}",
            )
        if subtree_id in entered:
            self.fail(element, f"<SubTree ID={subtree_id!r}> includes itself")
        given = dict(self.subtree_defaults.get(subtree_id, {}))
        for attribute, text in element.attributes.items():
            if attribute in ("ID", "name") or attribute in METADATA_ATTRIBUTES:
                continue
            if attribute in SCRIPT_ATTRIBUTES:
                self.fail(element, f"<SubTree> {attribute}: BehaviorTree.CPP scripts are code and are not run")
            if not attribute.isidentifier():
                self.fail(element, f"<SubTree ID={subtree_id!r}>: {attribute!r} is not a port name")
            given[attribute] = text
        literals: dict[str, str] = {}
        remaps: dict[str, str] = {}
        for port, text in given.items():
            reference = _reference(text)
            if reference is None:
                literals[port] = text
            elif reference in scope.literals:
                literals[port] = scope.literals[reference]
            else:
                remaps[port] = scope.key(reference, None)
        inner = _Scope(literals, remaps, literals.get("obj"))
        tree = self.served.get(element.attributes.get("_fullpath", ""), self.trees[subtree_id])
        root = self._tree(tree, entered, inner)
        if "obj" in literals and "target_pose" in literals:
            # A part's SubTree: the writer writes it as one again (``render_part`` marks a part so).
            pose = PLANAR_POSE.parse(literals["target_pose"])
            obj = literals["obj"]
            part = SubTreePart(obj, literals.get("colour", obj), pose.x_m, pose.y_m, pose.yaw_rad, subtree_id)
            root.part = part  # type: ignore[attr-defined]
        return root


def _reference(text: str) -> str | None:
    """The entry of a blackboard reference (``{pose}`` -> ``pose``), or None for a value."""
    match = re.fullmatch(r"\s*\{\s*([^{}]+?)\s*\}\s*", text)
    return match.group(1) if match else None


@dataclass(frozen=True)
class _Scope:
    """Where a node is read: the main tree (no ports) or a SubTree with its ports' texts and remapped keys.

    ``namespace`` is the part's object (the SubTree's ``obj``): a blackboard entry the SubTree does
    not remap is ``/<namespace>/<entry>``.
    """

    literals: Mapping[str, str] = field(default_factory=dict)
    remaps: Mapping[str, str] = field(default_factory=dict)
    namespace: str | None = None

    def key(self, entry: str, obj: str | None) -> str:
        """The absolute key of ``entry`` for a node of object ``obj`` (None: a node of no object) here."""
        if entry.startswith("/"):
            return entry
        if entry in self.remaps and (obj is None or obj == self.namespace):
            return self.remaps[entry]
        namespace = obj or self.namespace
        return keys.key(namespace, entry) if namespace else "/" + entry

    def named(self, name: str) -> str:
        """A node's name with the SubTree's ports (``{obj}``) put in."""
        if not self.literals or "{" not in name:
            return name
        return substitute(name, self.literals)
