"""The XML writer: a tree as a BehaviorTree.CPP v4 document with the ``TreeNodesModel`` Groot2 needs.

Every node is written from its registered model (``registry.model_of``): its tag, its ``name``
and each port's text. An ``optional`` port whose text is its default's is left out (files
written before it existed stay as they were). The ``TreeNodesModel`` lists the ports, types,
defaults and descriptions of the non-builtin nodes the tree uses, sorted by tag.

The Groot2 publisher (``bt_arrange.groot2``) asks for two more things: ``uids`` writes each node's
``_uid`` (BehaviorTree.CPP's ``WriteTreeToXML`` metadata, which Groot2 matches with the status
buffer), and ``generic=True`` writes a node of no registered model under its class name with no
ports (a user's Python tree can be watched even where it cannot be saved as XML).
"""

from __future__ import annotations

import dataclasses
import reprlib
from collections.abc import Mapping
from xml.sax.saxutils import escape, quoteattr

import py_trees

from bt_arrange.errors import PortValueError, XmlTreeError
from bt_arrange.ports import Port
from bt_arrange.xmltree.registry import NodeModel, generic_model, model_of

#: Values in messages: a few items, each cut short (``reprlib.Repr`` takes keywords from Python 3.12 only).
_SHORT = reprlib.Repr()
_SHORT.maxlist, _SHORT.maxother, _SHORT.maxstring = 2, 40, 40

FORMAT_VERSION = "4"


def to_xml(
    root: py_trees.behaviour.Behaviour,
    tree_id: str = "MainTree",
    *,
    comment: str | None = None,
    uids: Mapping[py_trees.behaviour.Behaviour, int] | None = None,
    generic: bool = False,
) -> str:
    """The tree as a BehaviorTree.CPP v4 document, with the ``TreeNodesModel`` of the non-builtin nodes it uses.

    ``uids`` (node to number) adds each node's ``_uid`` attribute; ``generic`` writes an unregistered
    node under its class name instead of refusing it.
    """
    used: dict[str, NodeModel] = {}
    options = _Options(uids or {}, generic)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    if comment:
        lines.append(f"<!-- {comment.replace('--', '- -')} -->")
    lines.append(f'<root BTCPP_format="{FORMAT_VERSION}" main_tree_to_execute={quoteattr(tree_id)}>')
    lines.append(f"  <BehaviorTree ID={quoteattr(tree_id)}>")
    _write_node(root, lines, depth=2, used=used, options=options)
    lines.append("  </BehaviorTree>")
    lines.append("  <TreeNodesModel>")
    for tag in sorted(used):
        model = used[tag]
        if model.builtin:
            continue
        lines.append(f"    <{model.category} ID={quoteattr(model.tag)}>")
        for port in model.ports:
            default = "" if port.required else f" default={quoteattr(port.type.format(port.default))}"
            lines.append(
                f"      <input_port name={quoteattr(port.name)} type={quoteattr(port.type.name)}{default}>"
                f"{escape(port.description)}</input_port>"
            )
        if model.description:
            lines.append(
                f"      <MetadataFields><Metadata description={quoteattr(model.description)}/></MetadataFields>"
            )
        lines.append(f"    </{model.category}>")
    lines.append("  </TreeNodesModel>")
    lines.append("</root>")
    return "\n".join(lines) + "\n"


class _Options:
    def __init__(self, uids: Mapping[py_trees.behaviour.Behaviour, int], generic: bool) -> None:
        self.uids = uids
        self.generic = generic


def _write_node(
    node: py_trees.behaviour.Behaviour, lines: list[str], depth: int, used: dict[str, NodeModel], options: _Options
) -> None:
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
    attributes = [f"name={quoteattr(node.name)}"]
    if node in options.uids:
        attributes.append(f'_uid="{options.uids[node]}"')
    for port, text in _port_texts(node, model):
        if port.optional and text == port.type.format(port.default):
            continue
        attributes.append(f"{port.name}={quoteattr(text)}")
    indent = "  " * depth
    opening = f"{indent}<{model.tag} {' '.join(attributes)}"
    if not node_children:
        lines.append(opening + "/>")
        return
    lines.append(opening + ">")
    for child in node_children:
        _write_node(child, lines, depth + 1, used, options)
    lines.append(f"{indent}</{model.tag}>")


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
