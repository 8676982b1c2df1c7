"""The py_trees behaviours of an arrangement: Detect, Pick, Place, Inspect, Push, Separate.

Their blackboard keys are named in ``keys``, their stages (the feedback while they run) in ``stages``.

Each reaches the world only through the ``Context`` handed to ``setup(context=...)``, declares
its blackboard keys (see ``keys``), sets ``feedback_message`` on every branch, never blocks a
tick, and turns errors of the framework into FAILURE with the reason as feedback.
"""

from bt_arrange.behaviours import keys, stages
from bt_arrange.behaviours.base import GripperStage, InstantStage, MoveStage, Stage, StagedBehaviour
from bt_arrange.behaviours.context import ArmBrake, Context
from bt_arrange.behaviours.grasp_estimation import EstimateGraspFromDepth
from bt_arrange.behaviours.guards import GraspGuard
from bt_arrange.behaviours.held import LookAtHeld
from bt_arrange.behaviours.looking import Detect, Inspect, MoveHome, Recheck, offset_in_target_frame_mm
from bt_arrange.behaviours.moves import holding
from bt_arrange.behaviours.pick import Pick
from bt_arrange.behaviours.place import Place
from bt_arrange.behaviours.push import Push
from bt_arrange.behaviours.push_aside import PushAside, PutBack
from bt_arrange.behaviours.separate import Separate
from bt_arrange.behaviours.standing import CheckStanding

__all__ = [
    "ArmBrake",
    "CheckStanding",
    "Context",
    "Detect",
    "EstimateGraspFromDepth",
    "GraspGuard",
    "GripperStage",
    "Inspect",
    "InstantStage",
    "LookAtHeld",
    "MoveHome",
    "MoveStage",
    "Pick",
    "Place",
    "Push",
    "Recheck",
    "PushAside",
    "PutBack",
    "Separate",
    "Stage",
    "StagedBehaviour",
    "holding",
    "offset_in_target_frame_mm",
    "keys",
    "stages",
]
