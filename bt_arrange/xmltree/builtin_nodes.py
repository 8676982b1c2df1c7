"""py_trees' own nodes in XML trees: adapters, since their classes are not the project's to declare ports on.

BehaviorTree.CPP's control nodes and decorators (``Sequence``, ``Fallback``, ``Parallel``,
``RetryUntilSuccessful`` ...) map to py_trees' composites and decorators (``builtin``: Groot2
knows them, so they stay out of the ``TreeNodesModel``); py_trees' blackboard behaviours
(``SetBlackboardVariable`` of a planar pose, ``CheckBlackboardVariableExists``,
``CheckBlackboardVariableValue`` of a text) are written with their ports.
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import ParallelPolicy

from bt_arrange.errors import XmlTreeError
from bt_arrange.geometry import PlanarPose
from bt_arrange.ports import BOOL, INT, KEY, OUTPUT, PLANAR_POSE, STRING, Port
from bt_arrange.xmltree.registry import Builder, Children, NodeModel, register


def _only(children: Children) -> py_trees.behaviour.Behaviour:
    return children[0]


def _with_memory(cls: type[py_trees.composites.Sequence] | type[py_trees.composites.Selector], memory: bool) -> Builder:
    return lambda name, values, children: cls(name, memory, children)


def _memory_is(memory: bool) -> Callable[[Any], bool]:
    return lambda node: node.memory is memory


def _decorating(cls: Callable[[str, py_trees.behaviour.Behaviour], py_trees.behaviour.Behaviour]) -> Builder:
    return lambda name, values, children: cls(name, _only(children))


def _named(cls: Callable[[str], py_trees.behaviour.Behaviour]) -> Builder:
    return lambda name, values, children: cls(name)


register(
    NodeModel(
        "SetBlackboardVariable",
        "Action",
        py_trees.behaviours.SetBlackboardVariable,
        (
            Port("variable_name", KEY, description="absolute blackboard key", direction=OUTPUT),
            Port("variable_value", PLANAR_POSE, description="x_m;y_m;yaw_rad"),
            Port("overwrite", BOOL, True),
        ),
        lambda name, v, _: py_trees.behaviours.SetBlackboardVariable(
            name=name, variable_name=v["variable_name"], variable_value=v["variable_value"], overwrite=v["overwrite"]
        ),
        lambda n: {
            "variable_name": n.variable_name,
            "variable_value": _planar_value(n),
            "overwrite": n.overwrite,
        },
        description="write a planar pose (a target) to the blackboard",
    )
)
register(
    NodeModel(
        "CheckBlackboardVariableExists",
        "Condition",
        py_trees.behaviours.CheckBlackboardVariableExists,
        (Port("variable_name", KEY, description="absolute blackboard key"),),
        lambda name, v, _: py_trees.behaviours.CheckBlackboardVariableExists(
            name=name, variable_name=v["variable_name"]
        ),
        lambda n: {"variable_name": n.variable_name},
    )
)


def _equals_ports(node: py_trees.behaviours.CheckBlackboardVariableValue) -> dict[str, Any]:
    check = node.check
    value = check.value_generator()
    if check.operator is not operator.eq or not isinstance(value, str):
        raise XmlTreeError(
            f"cannot write {node.name!r} as XML: CheckBlackboardVariableValue compares with {check.operator!r} "
            f"and a {type(value).__name__}, and XML trees check a text for equality only"
        )
    return {"variable_name": check.variable, "expected_value": value}


register(
    NodeModel(
        "CheckBlackboardVariableValue",
        "Condition",
        py_trees.behaviours.CheckBlackboardVariableValue,
        (
            Port("variable_name", KEY, description="absolute blackboard key"),
            Port("expected_value", STRING, description="succeed when the variable equals this text"),
        ),
        lambda name, v, _: py_trees.behaviours.CheckBlackboardVariableValue(
            name=name,
            check=py_trees.common.ComparisonExpression(v["variable_name"], v["expected_value"], operator.eq),
        ),
        _equals_ports,
    )
)


def _planar_value(node: py_trees.behaviours.SetBlackboardVariable) -> PlanarPose:
    value = node.variable_value_generator()
    if not isinstance(value, PlanarPose):
        raise XmlTreeError(
            f"cannot write {node.name!r} as XML: SetBlackboardVariable writes a {type(value).__name__}, "
            "and XML trees set planar poses only"
        )
    return value


# BehaviorTree.CPP's own control nodes and decorators, as py_trees classes.
for _tag, _memory in (("Sequence", True), ("ReactiveSequence", False)):
    register(
        NodeModel(
            _tag,
            "Control",
            py_trees.composites.Sequence,
            (),
            _with_memory(py_trees.composites.Sequence, _memory),
            matches=_memory_is(_memory),
            builtin=True,
        )
    )
for _tag, _memory in (("Fallback", True), ("ReactiveFallback", False)):
    register(
        NodeModel(
            _tag,
            "Control",
            py_trees.composites.Selector,
            (),
            _with_memory(py_trees.composites.Selector, _memory),
            matches=_memory_is(_memory),
            builtin=True,
        )
    )


def _parallel(name: str, values: dict[str, Any], children: Children) -> py_trees.behaviour.Behaviour:
    if values["failure_count"] != 1:
        raise ValueError("failure_count must be 1 (a py_trees Parallel fails when any child fails)")
    policy: py_trees.common.ParallelPolicy.Base
    if values["success_count"] == -1:
        policy = ParallelPolicy.SuccessOnAll(synchronise=True)
    elif values["success_count"] == 1:
        policy = ParallelPolicy.SuccessOnOne()
    else:
        raise ValueError("success_count must be -1 (all children) or 1 (one child)")
    return py_trees.composites.Parallel(name, policy, children)


def _parallel_ports(node: py_trees.composites.Parallel) -> dict[str, Any]:
    policy = node.policy
    if isinstance(policy, ParallelPolicy.SuccessOnAll) and policy.synchronise:
        return {"success_count": -1, "failure_count": 1}
    if isinstance(policy, ParallelPolicy.SuccessOnOne):
        return {"success_count": 1, "failure_count": 1}
    raise XmlTreeError(
        f"cannot write Parallel {node.name!r} as XML: only SuccessOnAll(synchronise=True) and SuccessOnOne map "
        "to BehaviorTree.CPP's success_count"
    )


register(
    NodeModel(
        "Parallel",
        "Control",
        py_trees.composites.Parallel,
        (Port("success_count", INT, -1), Port("failure_count", INT, 1)),
        _parallel,
        _parallel_ports,
        builtin=True,
    )
)
register(
    NodeModel(
        "RetryUntilSuccessful",
        "Decorator",
        py_trees.decorators.Retry,
        (Port("num_attempts", INT, description="attempts in all, the first one included"),),
        lambda name, v, children: py_trees.decorators.Retry(name, _only(children), v["num_attempts"]),
        lambda n: {"num_attempts": n.num_failures},
        builtin=True,
    )
)
register(
    NodeModel(
        "Repeat",
        "Decorator",
        py_trees.decorators.Repeat,
        (Port("num_cycles", INT),),
        lambda name, v, children: py_trees.decorators.Repeat(name, _only(children), v["num_cycles"]),
        lambda n: {"num_cycles": n.num_success},
        builtin=True,
    )
)
for _tag, _decorator in (
    ("ForceSuccess", py_trees.decorators.FailureIsSuccess),
    ("ForceFailure", py_trees.decorators.SuccessIsFailure),
    ("Inverter", py_trees.decorators.Inverter),
):
    register(NodeModel(_tag, "Decorator", _decorator, (), _decorating(_decorator), builtin=True))
for _tag, _leaf in (("AlwaysSuccess", py_trees.behaviours.Success), ("AlwaysFailure", py_trees.behaviours.Failure)):
    register(NodeModel(_tag, "Action", _leaf, (), _named(_leaf), builtin=True))
