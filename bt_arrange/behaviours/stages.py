"""The names of the behaviours' stages: a running behaviour's ``feedback_message``.

A staged behaviour reports the stage it runs as its feedback, so a watcher (an error injector,
a test, the live view) can tell where it is: compare with these constants, which the behaviours
themselves use, never with a copy of the text.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_arrange.deprecation import renamed_attributes

# Pick
OPEN_GRIPPER = "open the gripper"
MOVE_ABOVE_PART = "move above the part"
WAIT_FOR_OPEN_FINGERS = "wait for the fingers to open"
DESCEND_TO_PART = "descend to the part"
CLOSE_ON_PART = "close on the part"
CHECK_GRASP = "check the grasp"
OPEN_TO_CLOSE_SLOWLY = "open to close again slowly"
CLOSE_SLOWLY_ON_PART = "close slowly on the turned part"
CHECK_GRASP_AFTER_CLOSING_SLOWLY = "check the grasp after closing slowly"
OPEN_TO_SQUARE = "open to square a turned part"
SWEEP_TO_SQUARE = "sweep a pad along the turned part"
SHIFT_ALONG_PADS = "shift along the pads"
CLOSE_TO_SQUARE = "close to square the part"
OPEN_SQUARED_PART = "open on the squared part"
RECENTRE_ON_PART = "re-centre on the part"
TURN_WRIST_TO_SQUARE = "turn the wrist to square the part"
CLOSE_ON_TURNED_PART = "close after turning the wrist"
CHECK_TURNED_GRASP = "check the grasp after turning the wrist"
OPEN_TO_TURN_BACK = "open to turn the wrist the other way"
TURN_WRIST_OTHER_WAY = "turn the wrist the other way"
CLOSE_ON_SQUARED_PART = "close on the squared part"
CHECK_SQUARED_GRASP = "check the squared grasp"
LET_GO_OF_BAD_GRASP = "let go of a bad grasp"
LIFT_PART = "lift the part"
CONFIRM_GRASP = "confirm the grasp"

# Place
CARRY_ABOVE_TARGET = "carry above the target"
LOWER_PART = "lower the part to the table"
RELEASE_PART = "release the part"
RETREAT = "retreat"
#: LookAtHeld: the held part moved where the top camera sees it beside the gripper, then measured.
MOVE_TO_HELD_LOOK = "move the held part into the camera's view"
MEASURE_HELD = "measure the part in the fingers"

# Push (the push itself names its distance and axis: see ``push``)
SET_PUSH_OPENING = "set the push opening"
MOVE_BEHIND_PART = "move behind the part"
WAIT_FOR_FINGERS = "wait for the fingers"
LOWER_FINGERS = "lower the fingers"
APPROACH_EDGE = "approach the edge"
BACK_OFF = "back off"
LIFT_FINGERS = "lift the fingers"
CHOOSE_PUSH_SIDE = "choose a free side to push from"

# Separate (the push aside runs the push's stages above around it)
LOOK_FOR_TOUCHING = "look for touching parts"
PUSH_ASIDE = "push a touching part aside"

# Detect, Inspect, EstimateGraspFromDepth, MoveHome
PARK = "move out of the camera's view"
MOVE_HOME = "move home"

# Feedback of any staged behaviour between its stages
WAITING_FOR_BRAKE = "waiting for the arm to stop"
INTERRUPTED = "interrupted"


# Deprecated: the names of the stages that said "cube" for any part, kept one release (CHANGELOG.md).
_RENAMED = {
    "MOVE_ABOVE_CUBE": "MOVE_ABOVE_PART",
    "DESCEND_TO_CUBE": "DESCEND_TO_PART",
    "CLOSE_ON_CUBE": "CLOSE_ON_PART",
    "CLOSE_SLOWLY_ON_CUBE": "CLOSE_SLOWLY_ON_PART",
    "OPEN_SQUARED_CUBE": "OPEN_SQUARED_PART",
    "RECENTRE_ON_CUBE": "RECENTRE_ON_PART",
    "CLOSE_ON_TURNED_CUBE": "CLOSE_ON_TURNED_PART",
    "CLOSE_ON_SQUARED_CUBE": "CLOSE_ON_SQUARED_PART",
    "LIFT_CUBE": "LIFT_PART",
    "LOWER_CUBE": "LOWER_PART",
    "RELEASE_CUBE": "RELEASE_PART",
    "MOVE_BEHIND_CUBE": "MOVE_BEHIND_PART",
}
if TYPE_CHECKING:
    MOVE_ABOVE_CUBE = MOVE_ABOVE_PART
    DESCEND_TO_CUBE = DESCEND_TO_PART
    CLOSE_ON_CUBE = CLOSE_ON_PART
    CLOSE_SLOWLY_ON_CUBE = CLOSE_SLOWLY_ON_PART
    OPEN_SQUARED_CUBE = OPEN_SQUARED_PART
    RECENTRE_ON_CUBE = RECENTRE_ON_PART
    CLOSE_ON_TURNED_CUBE = CLOSE_ON_TURNED_PART
    CLOSE_ON_SQUARED_CUBE = CLOSE_ON_SQUARED_PART
    LIFT_CUBE = LIFT_PART
    LOWER_CUBE = LOWER_PART
    RELEASE_CUBE = RELEASE_PART
    MOVE_BEHIND_CUBE = MOVE_BEHIND_PART
else:
    __getattr__ = renamed_attributes(__name__, _RENAMED)


def push(distance_m: float, axis: str) -> str:
    """The push stage: ``push 3.20 mm along x`` (the distance's size; the direction is in the plan)."""
    return f"push {abs(distance_m) * 1000:.2f} mm along {axis}"


def look_for(colour: str) -> str:
    """Detect's and Inspect's look: ``look for red``."""
    return f"look for {colour}"


def estimate_from_depth(obj: str) -> str:
    """EstimateGraspFromDepth's look: ``estimate the grasp of red from depth``."""
    return f"estimate the grasp of {obj} from depth"
