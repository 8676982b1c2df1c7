"""The project's nodes in XML trees: each class declares its ports, and this is its one registration.

A new behaviour is its class (with ``provided_ports()``, and ``node_description``) and one line
here. The tag is the class name, except where a file format already fixed another.
"""

from __future__ import annotations

from bt_arrange.behaviours import (
    CheckStanding,
    Detect,
    GraspGuard,
    Inspect,
    LookAtHeld,
    MoveHome,
    Pick,
    Place,
    Push,
    PushAside,
    PutBack,
    Recheck,
    Separate,
)
from bt_arrange.behaviours.puzzle import SolvePuzzle, SurveyPieces
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.trees import Arrangement
from bt_arrange.trees.puzzle import ArrangeSolved
from bt_arrange.xmltree.registry import register_node

for _node in (
    Detect,
    Inspect,
    Pick,
    Place,
    Push,
    PushAside,
    PutBack,
    Recheck,
    Separate,
    MoveHome,
    GraspGuard,
    CheckStanding,
    RepeatUntilWithin,
    LookAtHeld,
):
    register_node(_node)
register_node(Arrangement)
# A puzzle: its survey, its solve, and the arrangement its solve decides.
for _puzzle_node in (SurveyPieces, SolvePuzzle, ArrangeSolved):
    register_node(_puzzle_node)
