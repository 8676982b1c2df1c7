"""The names of the behaviours' stages: a running behaviour's ``feedback_message``.

A staged behaviour reports the stage it runs as its feedback, so a watcher (an error injector,
a test, the live view) can tell where it is: compare with these constants, which the behaviours
themselves use, never with a copy of the text.
"""

from __future__ import annotations

# Pick
OPEN_GRIPPER = "open the gripper"
MOVE_ABOVE_CUBE = "move above the cube"
WAIT_FOR_OPEN_FINGERS = "wait for the fingers to open"
DESCEND_TO_CUBE = "descend to the cube"
CLOSE_ON_CUBE = "close on the cube"
CHECK_GRASP = "check the grasp"
OPEN_TO_CLOSE_SLOWLY = "open to close again slowly"
CLOSE_SLOWLY_ON_CUBE = "close slowly on the turned cube"
CHECK_GRASP_AFTER_CLOSING_SLOWLY = "check the grasp after closing slowly"
OPEN_TO_SQUARE = "open to square a turned cube"
SWEEP_TO_SQUARE = "sweep a pad along the turned cube"
SHIFT_ALONG_PADS = "shift along the pads"
CLOSE_TO_SQUARE = "close to square the cube"
OPEN_SQUARED_CUBE = "open on the squared cube"
RECENTRE_ON_CUBE = "re-centre on the cube"
TURN_WRIST_TO_SQUARE = "turn the wrist to square the cube"
CLOSE_ON_TURNED_CUBE = "close after turning the wrist"
CHECK_TURNED_GRASP = "check the grasp after turning the wrist"
OPEN_TO_TURN_BACK = "open to turn the wrist the other way"
TURN_WRIST_OTHER_WAY = "turn the wrist the other way"
CLOSE_ON_SQUARED_CUBE = "close on the squared cube"
CHECK_SQUARED_GRASP = "check the squared grasp"
LET_GO_OF_BAD_GRASP = "let go of a bad grasp"
LIFT_CUBE = "lift the cube"
CONFIRM_GRASP = "confirm the grasp"

# Place
CARRY_ABOVE_TARGET = "carry above the target"
LOWER_CUBE = "lower the cube to the table"
RELEASE_CUBE = "release the cube"
RETREAT = "retreat"

# Push (the push itself names its distance and axis: see ``push``)
SET_PUSH_OPENING = "set the push opening"
MOVE_BEHIND_CUBE = "move behind the cube"
WAIT_FOR_FINGERS = "wait for the fingers"
LOWER_FINGERS = "lower the fingers"
BACK_OFF = "back off"
LIFT_FINGERS = "lift the fingers"
CHOOSE_PUSH_SIDE = "choose a free side to push from"

# Detect, Inspect, EstimateGraspFromDepth, MoveHome
PARK = "move out of the camera's view"
MOVE_HOME = "move home"

# Feedback of any staged behaviour between its stages
WAITING_FOR_BRAKE = "waiting for the arm to stop"
INTERRUPTED = "interrupted"


def push(distance_m: float, axis: str) -> str:
    """The push stage: ``push 3.20 mm along x`` (the distance's size; the direction is in the plan)."""
    return f"push {abs(distance_m) * 1000:.2f} mm along {axis}"


def look_for(colour: str) -> str:
    """Detect's and Inspect's look: ``look for red``."""
    return f"look for {colour}"


def estimate_from_depth(obj: str) -> str:
    """EstimateGraspFromDepth's look: ``estimate the grasp of red from depth``."""
    return f"estimate the grasp of {obj} from depth"
