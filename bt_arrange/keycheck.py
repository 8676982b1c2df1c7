"""The tree's pre-run check of its blackboard: every key a node needs is written by a node that runs before it.

A behaviour names the keys it cannot run without in ``required_reads`` (key -> who should write
it; ``StagedBehaviour.reads(..., written_by=...)`` fills it, ``RepeatUntilWithin`` names its offset
key). ``check_keys(root)`` walks the tree in the order it runs (children left to right; a
decorator or composite after its children, as a decorator judges what its child wrote) and raises
one ``PlanError`` for the first node whose key no earlier node writes: a hand-built tree that
forgets a step is refused before anything moves, instead of moving the robot and failing later
with a symptom. Writers are every node's declared blackboard keys (``register_key`` with write
access, e.g. py_trees' ``SetBlackboardVariable``), remappings followed.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

import py_trees

from bt_arrange.errors import PlanError


def required_reads(node: py_trees.behaviour.Behaviour) -> Mapping[str, str]:
    """The keys ``node`` cannot run without (key -> who should write them), stored names."""
    declared = getattr(node, "required_reads", None)
    if not isinstance(declared, Mapping):
        return {}
    remapped: dict[str, str] = {}
    for client in node.blackboards:
        remapped.update({str(k): str(v) for k, v in client.remappings.items()})
    return {remapped.get(str(key), str(key)): str(writer) for key, writer in declared.items()}


def written_keys(node: py_trees.behaviour.Behaviour) -> set[str]:
    """The keys ``node`` declares it writes (stored names, remappings followed)."""
    keys: set[str] = set()
    for client in node.blackboards:
        remappings = dict(client.remappings)
        for key in client.write | client.exclusive:
            keys.add(remappings.get(key, key))
    return keys


def run_order(root: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    """The nodes in the order they first run: leaves left to right, a parent after its children."""
    stack: list[tuple[py_trees.behaviour.Behaviour, bool]] = [(root, False)]
    while stack:  # no recursion: a deep tree (nested decorators) is walked like a shallow one
        node, expanded = stack.pop()
        if expanded or not node.children:
            yield node
            continue
        stack.append((node, True))
        stack.extend((child, False) for child in reversed(node.children))


def check_keys(root: py_trees.behaviour.Behaviour) -> None:
    """A ``PlanError`` for the first node that needs a key no node before it writes (see the module)."""
    order = list(run_order(root))
    written: set[str] = set()
    for index, node in enumerate(order):
        for key, writer in required_reads(node).items():
            if key in written:
                continue
            later = [other.name for other in order[index + 1 :] if key in written_keys(other)]
            where = f"; only {later[0]!r}, which runs after it, writes it" if later else ""
            raise PlanError(
                f"{node.name!r} needs {key} on the blackboard, written by {writer}, but no node before it "
                f"in the tree writes it{where}: put that step before {node.name!r} (checked before anything moves)",
                field=key,
            )
        written |= written_keys(node)


__all__ = ["check_keys", "required_reads", "run_order", "written_keys"]
