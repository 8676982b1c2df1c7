"""Trees as BehaviorTree.CPP v4 XML: a writer with the ``TreeNodesModel`` Groot2 needs, and a safe reader.

An XML tree is data. ``load_xml`` builds a tree only from the nodes in ``REGISTRY`` (the
project's behaviours, which declare their ports on their classes, and py_trees' composites and
decorators under their BehaviorTree.CPP names); any other tag, a BehaviorTree.CPP script
attribute (``_skipIf``, ``_onSuccess`` ...), an ``<Include>`` of another file or a
``<!DOCTYPE>`` is refused with a one-line ``XmlTreeError`` naming the tag and the line.
Nothing the file names is imported or evaluated.

py_trees 2.6 ships an experimental reader (``py_trees.parsers.behaviour_tree_xml``) that this
module does not use, because for shared files it does too much and for this project too little:
it resolves every ``PortsMixin`` class imported anywhere (``node_registry="auto"``), reaches every
class of ``py_trees.decorators`` by tag even with an explicit registry, imports a module named in
the file for a port typed ``type`` (``ports_utils.str_to_type``), inlines ``<Include>`` files from
disk, prefixes every node name with its parents' names, and takes only ``PortsMixin`` leaves (the
project's behaviours take their parameters in ``__init__``). It has no writer.

The rooms: ``registry`` (the node models, ``register_node``), ``project_nodes`` (the one
registration of each of the project's nodes), ``builtin_nodes`` (py_trees' own nodes, by
adapters), ``writer``, ``reader`` and ``tree_module`` (an XML file as a tree file). The port
types and their codecs are ``bt_arrange.ports``, below the behaviours that declare ports.

The mapping (``docs/xml.md`` has the whole table):

================================  ======================================================
py_trees                          BehaviorTree.CPP v4
================================  ======================================================
``Sequence(memory=True)``         ``Sequence`` (resumes a RUNNING child, restarts on FAILURE)
``Sequence(memory=False)``        ``ReactiveSequence``
``Selector(memory=True/False)``   ``Fallback`` / ``ReactiveFallback``
``Parallel(SuccessOnAll/One)``    ``Parallel success_count="-1"/"1" failure_count="1"``
``Retry(num_failures=N)``         ``RetryUntilSuccessful num_attempts="N"``
``Repeat(num_success=N)``         ``Repeat num_cycles="N"``
``FailureIsSuccess``              ``ForceSuccess``
``SuccessIsFailure``              ``ForceFailure``
``Inverter``                      ``Inverter``
``Success`` / ``Failure``         ``AlwaysSuccess`` / ``AlwaysFailure``
================================  ======================================================
"""

from bt_arrange.errors import XmlTreeError
from bt_arrange.ports import (
    BOOL,
    COLOURS,
    DIRECTIONS_TYPE,
    DOUBLE,
    INT,
    OBJECT_TYPE,
    OFF_DOUBLE,
    OFF_STRING,
    PLANAR_POSE,
    POSES,
    RELEASE,
    REQUIRED,
    STRING,
    Port,
    PortType,
)
from bt_arrange.trees import TARGETS
from bt_arrange.xmltree import builtin_nodes, project_nodes  # noqa: F401  (they fill the registry)
from bt_arrange.xmltree.reader import (
    METADATA_ATTRIBUTES,
    SCRIPT_ATTRIBUTES,
    Element,
    from_xml,
    load_xml,
    parse_elements,
)
from bt_arrange.xmltree.registry import REGISTRY, NodeModel, model_of, register, register_node, tag_of, type_label
from bt_arrange.xmltree.tree_module import iter_structure, load_module
from bt_arrange.xmltree.writer import FORMAT_VERSION, subtree_roots, to_xml

__all__ = [
    "BOOL",
    "COLOURS",
    "DIRECTIONS_TYPE",
    "DOUBLE",
    "FORMAT_VERSION",
    "INT",
    "METADATA_ATTRIBUTES",
    "OBJECT_TYPE",
    "OFF_DOUBLE",
    "OFF_STRING",
    "PLANAR_POSE",
    "POSES",
    "REGISTRY",
    "RELEASE",
    "REQUIRED",
    "SCRIPT_ATTRIBUTES",
    "STRING",
    "TARGETS",
    "Element",
    "NodeModel",
    "Port",
    "PortType",
    "XmlTreeError",
    "from_xml",
    "iter_structure",
    "load_module",
    "load_xml",
    "model_of",
    "parse_elements",
    "register",
    "register_node",
    "subtree_roots",
    "tag_of",
    "to_xml",
    "type_label",
]
