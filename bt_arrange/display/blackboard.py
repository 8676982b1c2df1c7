"""Who writes and who reads each blackboard key of a tree, from the keys its behaviours declared."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import py_trees

# ----------------------------------------------------------------------------------------------
# Blackboard access, from the tree's own clients
# ----------------------------------------------------------------------------------------------


@dataclass
class KeyAccess:
    """Who touches one blackboard key, in tree order (behaviour names, each listed once)."""

    key: str
    writers: list[str] = field(default_factory=list)
    readers: list[str] = field(default_factory=list)


def _preorder(root: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    """Behaviours top-down in the order they are drawn (``Behaviour.iterate`` yields children first)."""
    yield root
    for child in root.children:
        yield from _preorder(child)


def blackboard_access(root: py_trees.behaviour.Behaviour) -> list[KeyAccess]:
    """Every blackboard key declared by the behaviours of ``root``'s tree, with its writers and readers.

    Keys come in the order the tree first mentions them. A remapped key is listed where it is
    stored, the behaviour with ``(as <its own name for it>)``. Exclusive writers count as writers.
    """
    table: dict[str, KeyAccess] = {}

    def note(key: str, who: str, remapped: dict[str, str], writes: bool) -> None:
        stored = remapped.get(key, key)
        label = who if stored == key else f"{who} (as {key})"
        entry = table.setdefault(stored, KeyAccess(stored))
        names = entry.writers if writes else entry.readers
        if label not in names:
            names.append(label)

    for behaviour in _preorder(root):
        for client in behaviour.blackboards:
            remappings = dict(client.remappings)
            for key in sorted(client.write | client.exclusive):
                note(key, behaviour.name, remappings, writes=True)
            for key in sorted(client.read):
                note(key, behaviour.name, remappings, writes=False)
    return list(table.values())


def blackboard_table(root: py_trees.behaviour.Behaviour) -> str:
    """The blackboard keys of a tree as text: per key, the behaviours that write it and those that read it."""
    access = blackboard_access(root)
    if not access:
        return "Blackboard: no behaviour of this tree declares a key\n"
    lines = ["Blackboard keys (declared with register_key)"]
    for entry in access:
        lines.append(f"  {entry.key}")
        lines.append(f"      written by  {', '.join(entry.writers) or '- (nobody in this tree)'}")
        lines.append(f"      read by     {', '.join(entry.readers) or '- (nobody in this tree)'}")
    return "\n".join(lines) + "\n"
