"""Error injection: one injector per manipulation error of the paper's Sec. 3, at the moment it names.

Every injector acts on the simulated world only: a cube's true pose (``WorkCell.displace_part``
or pybullet's reset), the pads' friction, the camera's physical pose (``SimCamera.set_render_offset``)
or an execution parameter of the robot (the release height). It reaches the world through the cell's
methods named in ``framework.InjectableCell``, which the pybullet cell and the MuJoCo cell
(``bt_arrange_sim.mujoco``) both have: every injector runs in either engine. The robot learns of an error only
through its camera; nothing the tree reports is touched, and no cube is ever fixed to the gripper.

| name | error (paper, Fig. 2) | when | magnitude (default) |
|---|---|---|---|
| ``perception_offset`` | a) pose estimation | detection before the pick | ``max_m`` = 0.010 m camera shift |
| ``pick_translation`` | b) translation | after that detection | ``max_m`` = 0.025 m: up to 2.5 cm, any direction |
| ``pick_translation_xy`` | b) translation, read per axis | after that detection | ``max_m`` = 0.025 m in x and in y |
| ``pick_rotation`` | c) orientation | after that detection | ``max_deg`` = 40 deg |
| ``surface_shift`` | d) surface | "close on the part" | ``max_m`` = 0.003 m along the pads |
| ``transport_slip`` | e) grip | "carry above the target" | ``duration_s`` = 0.05 s, ``friction_scale`` = 0 |
| ``release_stick`` | f) friction | "release the part" | ``max_m`` = 0.003 m toward one finger |
| ``release_height`` | g) release | the first placing | ``height_m`` = 0.005 m |
| ``release_tilt`` | h) tilting | "release the part" | ``max_deg`` = 5 deg |

Use::

    injectors = [make_injector("pick_translation:0.025"), make_injector("release_tilt")]
    attach_all(run, "red", injectors, seed=7)
    report = run.run()
    log = [injector.record() for injector in injectors]  # JSON-able: what was injected

**Once per run.** Each injector fires at the first occurrence of its moment for its object and
never again: a regrasp after a slip, a second placing, and the pushes of the correction run
without injected errors, so a trial measures the correction of one error. ``record()`` says
whether it fired (``"fired"``) and what it did, in millimetres and degrees.

**Seeds.** Each injector draws from its own ``numpy.random.Generator``; ``attach_all`` derives
one per injector from the seed and the injector's name (not its position), so an injector draws
the same values whatever else is attached. The draws of the picking injectors are resampled only
when the pads could not close on the cube (``grasp_fits``: the limit binds across the closing axis),
which depends on where the camera saw the cube, so the same seed reproduces a record for the same
scene.

An injector finds the behaviours it waits for by their type and object (the ``Detect``, ``Pick``
and ``Place`` of ``obj`` that ``bt_arrange.trees.transfer`` builds), never by their names, and a
stage by the running behaviour's feedback, compared with the constants of
``bt_arrange.behaviours.stages`` the behaviours themselves use; in a tree without them an
injector never fires.

The package follows the paper's four categories: ``perception``, ``picking``, ``transport`` and
``placement``, beside ``framework`` (what every injector shares) and ``registry`` (names, specs,
``attach_all``); everything is importable from ``bt_arrange_sim.injection``.
"""

from bt_arrange_sim.injection.framework import (
    CARRY_STAGE,
    CLOSE_STAGE,
    LIFT_STAGE,
    MAX_DRAWS,
    RELEASE_STAGE,
    Injector,
    Parameter,
    _NodeFinder,
    grasp_fits,
    is_detection,
    read_blackboard,
)
from bt_arrange_sim.injection.perception import PerceptionOffset
from bt_arrange_sim.injection.picking import PickRotation, PickTranslation, PickTranslationXY, SurfaceShift
from bt_arrange_sim.injection.placement import ReleaseHeight, ReleaseStick, ReleaseTilt
from bt_arrange_sim.injection.registry import INJECTORS, attach_all, child_generator, make_injector, make_injectors
from bt_arrange_sim.injection.transport import TransportSlip

__all__ = [
    "CARRY_STAGE",
    "CLOSE_STAGE",
    "INJECTORS",
    "LIFT_STAGE",
    "MAX_DRAWS",
    "RELEASE_STAGE",
    "Injector",
    "Parameter",
    "PerceptionOffset",
    "PickRotation",
    "PickTranslation",
    "PickTranslationXY",
    "ReleaseHeight",
    "ReleaseStick",
    "ReleaseTilt",
    "SurfaceShift",
    "TransportSlip",
    "_NodeFinder",
    "attach_all",
    "child_generator",
    "grasp_fits",
    "is_detection",
    "make_injector",
    "make_injectors",
    "read_blackboard",
]
