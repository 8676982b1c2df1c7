"""The nodes an XML tree may use: one ``NodeModel`` per tag, filled by the classes' own declarations.

A node declares its ports on its class (``provided_ports()``, as BehaviorTree.CPP's
``providedPorts``), or in the registration, and is registered with one call or class decorator, as
BehaviorTree.CPP's ``factory.registerNodeType<T>(ID)``::

    register_node(Pick)                                      # tag "Pick", category from the base class
    register_node(Arrangement, "Plan")                      # another tag

    @register_node(ports=(Port("height_m", DOUBLE, 0.05, "how high"),), description="lift the part")
    class Lift(StagedBehaviour): ...

A registered node is read and written as XML, drawn by ``bt-arrange show`` under its tag, and shown
in Groot2 with its ports (the ``TreeNodesModel``). The model is read from the class:

- the tag is the class name unless given; the category (``Action``, ``Condition``, ``Control``,
  ``Decorator``) is ``node_category`` when the class sets it, else a py_trees decorator is a
  ``Decorator``, a composite a ``Control``, anything else an ``Action``; ``node_description`` is
  the ``TreeNodesModel``'s description;
- build (the reader): ``cls.from_ports(name, values, children)`` when the class has it, else
  ``cls(name=name, **values)``, with ``child=`` (a decorator) or ``children=`` (a control node);
- read back (the writer): ``node.port_values()`` when the class has it, else
  ``getattr(node, port.name)`` for every port.

py_trees' own nodes, which are not the project's classes, are registered with adapters in
``builtin_nodes``.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any, TypeVar, overload

import py_trees

from bt_arrange.behaviours.base import entry_remaps, remap_entry
from bt_arrange.errors import XmlTreeError
from bt_arrange.ports import Port

Children = list[py_trees.behaviour.Behaviour]
Builder = Callable[[str, dict[str, Any], Children], py_trees.behaviour.Behaviour]

CATEGORIES = ("Action", "Condition", "Control", "Decorator")


@dataclass(frozen=True)
class NodeModel:
    """How one XML tag maps to one py_trees class.

    ``build(name, values, children)`` makes the behaviour from its port values; ``ports_of(node)``
    reads them back from a behaviour (the writer); ``matches(node)`` picks between models of one
    class (``Sequence`` with or without memory). ``builtin`` models are BehaviorTree.CPP's own,
    which Groot2 knows, so they are left out of the ``TreeNodesModel``.
    """

    tag: str
    category: str  # Action, Condition, Control or Decorator, as in the TreeNodesModel
    cls: type
    ports: tuple[Port, ...]
    build: Builder
    ports_of: Callable[[Any], dict[str, Any]] = lambda node: {}
    matches: Callable[[Any], bool] = lambda node: True
    builtin: bool = False
    description: str = ""

    @property
    def children(self) -> str:
        """How many children the node takes: ``none``, ``one`` or ``many``."""
        return {"Action": "none", "Condition": "none", "Decorator": "one"}.get(self.category, "many")


REGISTRY: dict[str, NodeModel] = {}


#: Tags of former releases, read as today's: a file written with one still loads (the writer writes today's).
FORMER_TAGS = {"RetryUntilThreshold": "RepeatUntilWithin"}


def register(model: NodeModel) -> NodeModel:
    """Make a node available to XML trees from its model (``register_node`` makes the model from a class)."""
    if model.category not in CATEGORIES:
        raise XmlTreeError(f"node model {model.tag}: category {model.category!r} is not a BehaviorTree.CPP one")
    names = [port.name for port in model.ports]
    for port_name in names:
        if port_name == "name" or not port_name.isidentifier() or names.count(port_name) > 1:
            raise XmlTreeError(f"node model {model.tag}: port {port_name!r} is reserved, not a name, or twice")
    REGISTRY[model.tag] = model
    return model


NodeClass = TypeVar("NodeClass", bound=type)


@overload
def register_node(
    cls: NodeClass, tag: str | None = None, *, ports: Iterable[Port] | None = None, description: str | None = None
) -> NodeClass: ...


@overload
def register_node(
    cls: str | None = None,
    tag: str | None = None,
    *,
    ports: Iterable[Port] | None = None,
    description: str | None = None,
) -> Callable[[NodeClass], NodeClass]: ...


def register_node(
    cls: Any = None, tag: str | None = None, *, ports: Iterable[Port] | None = None, description: str | None = None
) -> Any:
    """Register a node class for XML trees, ``bt-arrange show`` and Groot2, under ``tag`` (default its name).

    A call, ``register_node(Wave)``, or a class decorator: ``@register_node``, ``@register_node("Tag")``
    or ``@register_node(ports=(...), description="...")``. The ports are ``ports`` when given (the class
    then answers ``provided_ports()`` with them), else the class's own ``provided_ports()``; the
    description is ``description``, else the class's ``node_description``. Returns the class.

    Refused here, not when a file is read: a class without ports declared, a port the constructor
    does not take (and no ``from_ports`` on the class), and a tag that is already another node's.
    """
    if cls is None or isinstance(cls, str):
        named = cls if isinstance(cls, str) else tag

        def decorate(node_class: NodeClass) -> NodeClass:
            return _register_class(node_class, named, ports, description)

        return decorate
    return _register_class(cls, tag, ports, description)


def _register_class(
    cls: NodeClass, tag: str | None, ports: Iterable[Port] | None, description: str | None
) -> NodeClass:
    if not isinstance(cls, type):
        raise XmlTreeError(f"register_node takes a class, got {cls!r}")
    tag = tag or cls.__name__
    if ports is not None:
        declared = tuple(ports)
        if not all(isinstance(port, Port) for port in declared):
            raise XmlTreeError(f"node {tag}: ports= takes bt_arrange.ports.Port values, got {declared!r}")
    else:
        declare = getattr(cls, "provided_ports", None)
        if not callable(declare):
            raise XmlTreeError(
                f"node {tag}: {cls.__qualname__} declares no provided_ports() (or give register_node ports=)"
            )
        declared = tuple(declare())
    category = getattr(cls, "node_category", None) or category_of(cls)
    if not hasattr(cls, "from_ports"):
        accepted = inspect.signature(cls).parameters
        takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in accepted.values())
        missing = [port.name for port in declared if not port.entry and port.name not in accepted and not takes_any]
        if missing:
            raise XmlTreeError(
                f"node {tag}: {cls.__qualname__}() takes no {', '.join(missing)} (give the class a from_ports)"
            )
    known = REGISTRY.get(tag)
    if known is not None and known.cls is not cls and _owned(known.cls):
        raise XmlTreeError(
            f"node {tag}: the tag is {known.cls.__module__}.{known.cls.__qualname__}'s: register yours under another"
        )
    text = description if description is not None else getattr(cls, "node_description", "")
    register(
        NodeModel(
            tag,
            category,
            cls,
            declared,
            lambda name, values, children: build_node(cls, category, name, values, children),
            lambda node: port_values(node, declared),
            description=text,
        )
    )
    if ports is not None:
        # The class answers for its ports as a declared one does (the registry's readers ask it).
        cls.provided_ports = classmethod(lambda _cls: declared)  # type: ignore[attr-defined]
    if description is not None:
        cls.node_description = description  # type: ignore[attr-defined]
    return cls


def _owned(cls: type) -> bool:
    """A class of bt-arrange or of py_trees: a user's node never takes its tag."""
    return cls.__module__.split(".")[0] in ("bt_arrange", "py_trees")


def category_of(cls: type) -> str:
    """A class's category in BehaviorTree.CPP's terms, from its py_trees base class."""
    if issubclass(cls, py_trees.decorators.Decorator):
        return "Decorator"
    if issubclass(cls, py_trees.composites.Composite):
        return "Control"
    return "Action"


def build_node(
    cls: type, category: str, name: str, values: Mapping[str, Any], children: Children
) -> py_trees.behaviour.Behaviour:
    """The generic build: the class's ``from_ports``, else its constructor with the port values as keywords.

    The blackboard entry ports (``Port.entry``) are not the constructor's: an entry given a key
    (not None) is remapped on the node built (``remap_entry``).
    """
    remapped = {name: value for name, value in values.items() if name in _entry_names(cls)}
    values = {name: value for name, value in values.items() if name not in remapped}
    from_ports = getattr(cls, "from_ports", None)
    if from_ports is not None:
        node: py_trees.behaviour.Behaviour = from_ports(name, dict(values), list(children))
    elif category == "Decorator":
        node = cls(name=name, child=children[0], **values)
    elif category == "Control":
        node = cls(name=name, children=list(children), **values)
    else:
        node = cls(name=name, **values)
    for field, key in remapped.items():
        if key is not None:
            remap_entry(node, field, key)
    return node


def _entry_names(cls: type) -> frozenset[str]:
    declare = getattr(cls, "provided_ports", None)
    return frozenset(port.name for port in declare() if port.entry) if callable(declare) else frozenset()


def port_values(node: Any, ports: tuple[Port, ...]) -> dict[str, Any]:
    """The generic read-back: the node's ``port_values()``, else its attribute of each port's name."""
    own = getattr(node, "port_values", None)
    remaps = entry_remaps(node)
    if own is not None:
        values: dict[str, Any] = own()
    else:
        values = {port.name: getattr(node, port.name) for port in ports if not port.entry}
    values.update({port.name: remaps.get(port.name) for port in ports if port.entry})
    return values


def generic_model(cls: type) -> NodeModel:
    """A model of an unregistered class for the Groot2 view only: its class name, its category, no ports."""

    def cannot_build(name: str, values: dict[str, Any], children: Children) -> py_trees.behaviour.Behaviour:
        raise XmlTreeError(f"<{cls.__name__}> is not a registered node")

    return NodeModel(cls.__name__, category_of(cls), cls, (), cannot_build)


def tag_of(node: py_trees.behaviour.Behaviour) -> str:
    """The node's BehaviorTree.CPP type, as the XML names it (``ForceSuccess`` for a ``FailureIsSuccess``).

    A node of no registered model is named by its class. This is the one vocabulary of the replay
    page, ``bt-arrange show``, the live view, the transitions and the Groot2 view.
    """
    for model in REGISTRY.values():
        if type(node) is model.cls and model.matches(node):
            return model.tag
    return type(node).__name__


def type_label(node: py_trees.behaviour.Behaviour) -> str:
    """``tag_of(node)``, then the class where the two differ: ``ForceSuccess (py_trees FailureIsSuccess)``."""
    tag = tag_of(node)
    cls = type(node)
    if cls.__name__ == tag:
        return tag
    owner = "py_trees " if cls.__module__.startswith("py_trees") else ""
    return f"{tag} ({owner}{cls.__name__})"


def model_of(node: py_trees.behaviour.Behaviour) -> NodeModel:
    """The registered model that writes ``node`` (its exact class: a subclass is not the same node)."""
    for model in REGISTRY.values():
        if type(node) is model.cls and model.matches(node):
            return model
    raise XmlTreeError(
        f"cannot write {node.name!r} as XML: {type(node).__module__}.{type(node).__qualname__} is not a registered "
        "node (bt_arrange.xmltree.register_node adds one)"
    )
