"""Run an arrangement tree against a world and report per object: the same for every backend.

A backend supplies a ``World`` (the robot interfaces, a clock it steps, the parts placed where
they start, a camera frame for recorded images and, for evaluation only, ground truth where it
has one); a ``Session`` does the rest:

- the plan check (``check_plan`` / ``check_scene`` / ``check_colours_apart``), the time limit,
  the recording folder, all before the world is built (``open_world`` is called only then);
- the ``Runner`` on the world's clock, with the transition log (``transitions.jsonl``), the
  paper's Fig. 5 images and the replay page (``replay.html``) when recording;
- the report, per object (``ObjectOutcome``): what the camera measured beside the world's ground
  truth, labelled as such; a world without ground truth gives a camera-only report (every
  ``*_truth_*`` field None, ``SessionReport.ground_truth`` False).

``bt_arrange`` never imports a simulator: ``bt_arrange_sim.pybullet.runs.SimWorld`` is the pybullet cell as
a ``World``, and ``bt_arrange_sim.pybullet.runs.SimulatedRun`` a ``Session`` on it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import gc
import math
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Access, Status

from bt_arrange import files
from bt_arrange.behaviours import (
    Context,
    Detect,
    EstimateGraspFromDepth,
    GraspGuard,
    Inspect,
    Pick,
    Place,
    Push,
    PushAside,
    Recheck,
    Separate,
    keys,
)
from bt_arrange.behaviours.puzzle import SolvePuzzle, SurveyPieces
from bt_arrange.calibration.camera import CalibratedCamera
from bt_arrange.calibration.file import CameraCalibration, check_image_size
from bt_arrange.checks import positive_number
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.errors import PlanError, RecordError
from bt_arrange.foxglove import streams as foxglove_streams
from bt_arrange.geometry import PlanarPose
from bt_arrange.keycheck import check_keys
from bt_arrange.motion.safety import MotionSafety
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourTable, PartDetector
from bt_arrange.plan.check import CameraView, check_plan, check_puzzles, check_scene
from bt_arrange.plan.compiled import ArrangementPlan
from bt_arrange.plan.targets import Target
from bt_arrange.puzzle.evaluation import PuzzleTruth
from bt_arrange.replay import ReplayRecorder
from bt_arrange.report import ObjectOutcome, Placement, PlacementLog, SessionReport
from bt_arrange.runner import Runner, Transition, TransitionLog, object_of
from bt_arrange.session_checks import check_colours_apart, check_puzzles_in_view, prepare_record_dir
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import yaw_error_rad
from bt_arrange.trees import plan_of
from bt_arrange.trees.puzzle import ArrangeSolved
from bt_arrange.uncertainty import CAMERA_MARGIN_KEY, camera_margin_mm
from bt_arrange.world import GroundTruth, World

#: The longest the scene settles before the tree starts (parts put on the table come to rest), seconds.
SETTLE_S = 0.3

#: Behaviours whose failure explains why an object was not finished (each knows its ``obj``).
REASON_TYPES: tuple[type[py_trees.behaviour.Behaviour], ...] = (
    Detect,  # and Inspect, a Detect
    EstimateGraspFromDepth,
    Pick,
    Place,
    Push,
    RepeatUntilWithin,
    GraspGuard,
    SurveyPieces,  # a puzzle's (its obj: the puzzle's name)
    SolvePuzzle,
    ArrangeSolved,
)


class Session:
    """One tree in one world, built by ``open_world()`` once everything a user can get wrong is checked.

    ``starts`` are where the parts start (checked with the plan), or None where nobody knows before the
    camera looks (a real cell: its parts lie where they lie; the plan is checked without a scene).

    ``view`` is the top camera's view for the plan check (known without a world: from the backend's
    configuration or a calibration); without one the view is not checked. ``calibration`` (a
    ``bt_arrange.calibration.CameraCalibration``, e.g. ``read_calibration("camera.toml")``) makes the
    camera report its intrinsics, distortion and pose, so the detector uses them (and the plan check
    its view); without it, the world's camera as it reports itself. ``transition_hooks`` are
    called with every status change (e.g. to inject an error at the moment the paper names),
    ``tick_hooks`` after every tick, ``runner_hooks`` with the runner before its first tick,
    ``report_hooks`` with the report before it is recorded (e.g. to list the injected errors).
    ``mcap_path`` records the Foxglove streams to that file alone, without a record folder (a
    campaign's trial, ``experiment --record``): written whole at the end, or a fault.

    ``motion_safety`` (``bt_arrange.motion.safety.MotionSafety``: a speed fraction, the cell's workspace box)
    applies to every motion the tree plans; a ``SafetyStop`` (the robot stopped, a motion outside the
    box) ends the run with a FAILURE and its reason in the report (``safety_stop``).

    ``plan`` is what the tree carries out (``bt_arrange.plan.compiled.ArrangementPlan``: targets,
    tolerance, settings, colours, puzzles): the plan check, the report and "within" come from it. By
    default the tree's own (``trees.plan_of(root)``, a rendered arrangement's); a tree without a plan
    is run and its scene checked, and reports no parts.
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any] | None,
        open_world: Callable[[], World],
        *,
        view: CameraView | None = None,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
        settle_s: float = SETTLE_S,
        settings: ManipulationSettings | None = None,
        calibration: CameraCalibration | None = None,
        mcap_path: Path | None = None,
        plan: ArrangementPlan | None = None,
        motion_safety: MotionSafety | None = None,
    ) -> None:
        if not isinstance(root, py_trees.behaviour.Behaviour):
            raise PlanError(f"the root must be a py_trees behaviour, got {type(root).__name__}")
        positive_number("time limit", time_limit_s, "s", style="unit")
        #: The plan the tree carries out, or None (a tree composed without one: no parts to report).
        self.plan: ArrangementPlan | None = plan if plan is not None else plan_of(root)
        # One settings value for the plan check and the context: the plan's own (what it was checked
        # and built with), unless the caller hands one in.
        if settings is None:
            settings = self.plan.settings if self.plan is not None else ManipulationSettings()
        #: The handling settings of the run.
        self.settings = settings
        # Everything a user can get wrong is checked here, before the world is built.
        # None: where the parts start is not known before the camera looks (a real cell): not checked.
        scene = list(starts) if starts is not None else None
        #: The camera calibration the run uses, or None (the camera as it reports itself).
        self.calibration = calibration
        if calibration is not None:
            if view is not None:
                # Before the plan check, whose view would otherwise be wrong for a reason it cannot name.
                check_image_size(calibration, view.intrinsics.width_px, view.intrinsics.height_px)
            view = calibration.view()
        #: The colour table of the plan: the world paints with it and the camera's detector reads it.
        self.colours: ColourTable = self.plan.colours if self.plan is not None else DEFAULT_COLOUR_TABLE
        if self.plan is not None:
            checked = self.plan
            try:
                if checked.targets or not checked.puzzles:
                    check_plan(
                        list(checked.targets),
                        threshold_mm=checked.tolerance.threshold_mm,
                        starts=scene,
                        view=view,
                        colours=self.colours,
                        settings=settings,
                    )
                elif scene is not None:  # a puzzle's targets come from its solve: its scene and place are checked
                    check_scene(scene, view=view, colours=self.colours, settings=settings)
                check_puzzles(checked.puzzles, checked.targets, checked.tolerance.threshold_mm, settings)
                check_puzzles_in_view(list(checked.puzzles), view)
                check_colours_apart(list(checked.targets), self.colours)
            except PlanError as error:
                # A plan file's errors name its file and entries ([[targets]] 3, [colours.teal]).
                if checked.source is None:
                    raise
                raise checked.source.locate(error) from error
        elif scene is not None:
            check_scene(scene, view=view, colours=self.colours, settings=settings)
        check_keys(root)
        self.record_dir = prepare_record_dir(record_dir) if record_dir is not None else None
        #: The one MCAP file recorded without a record folder (a campaign's trial), or None.
        self.mcap_path = Path(mcap_path) if mcap_path is not None else None
        self.root = root
        #: Every node of the tree by its id (as text): transitions name their node by it.
        self.nodes: dict[str, py_trees.behaviour.Behaviour] = {str(node.id): node for node in root.iterate()}
        self.world: World = open_world()
        self.world.place(scene or [], self.colours)
        self.world.settle(settle_s)
        #: Ground truth of the world (evaluation only), or None: the report is then camera only.
        self.truth: GroundTruth | None = self.world.truth
        #: A puzzle's truth (evaluation only): each named piece's part of the world and true home.
        self.puzzle_truth = PuzzleTruth(list(self.plan.puzzles) if self.plan is not None else [], self.truth)
        #: World time when the tree starts: the report and the live view count from here.
        self.start_s = self.world.clock.now()
        robot = self.world.robot
        if calibration is not None:
            robot = dataclasses.replace(robot, camera=CalibratedCamera(robot.camera, calibration))
        #: The speed fraction and workspace box every motion of the tree is planned under (``motion.safety``).
        self.motion_safety = motion_safety if motion_safety is not None else MotionSafety()
        self.context = Context.create(
            robot, detector=PartDetector(self.colours), settings=settings, safety=self.motion_safety
        )
        self.time_limit_s = time_limit_s
        self.transition_hooks: list[Callable[[Transition], None]] = []
        self.tick_hooks: list[Callable[[py_trees.behaviour.Behaviour], None]] = []
        #: Called with the runner once it is built, before the first tick (e.g. to time its ticks).
        self.runner_hooks: list[Callable[[Runner], None]] = []
        #: Called with the report once it is made, before it is recorded or returned (e.g. to add what was injected).
        self.report_hooks: list[Callable[[SessionReport], None]] = []
        #: Each part's first placing, its regrasps and its last placing again, for the report.
        self.placements = PlacementLog()
        #: Ground truth (evaluation only) of each object when last looked at, and the most it moved between looks.
        self._looked_truth_xy: dict[str, tuple[float, float]] = {}
        self._moved_truth_mm: dict[str, float] = {}
        #: A tree that looks at placed parts again (a dense one): only then is the truth tracked per look.
        self._rechecks = any(isinstance(node, Recheck) for node in root.iterate())
        #: What the replay page shows (recorded runs only), and its heading.
        self.replay: ReplayRecorder | None = None
        self.title = title or root.name
        #: The recorded files that could not be written (a full disk, the folder gone); the run goes on.
        self.faults = files.Faults()
        #: The camera's own error (mm) a measured offset must leave under the threshold, and whence.
        self.camera_margin_mm, self.camera_margin_source = camera_margin_mm(calibration, self.world)
        #: Per part, its set-downs (to look again and pick centred) and its placings at the target.
        self._set_downs: dict[str, int] = {}
        #: Pushes aside of touching parts before each part's pick (``Separate``), by part.
        self._separations: dict[str, int] = {}
        self._moved_aside: dict[str, list[str]] = {}
        self._placings: dict[str, int] = {}
        #: The subtree that places every part before any is corrected (the paper's Fig. 5), or None.
        self._place_all = getattr(root, "place_all", None)
        #: A live Foxglove server (``bt_arrange.foxglove.streams.LiveServer``, ``--foxglove``) to stream to, or None.
        self.foxglove_live: Any = None

    def elapsed_s(self) -> float:
        """World time since the tree started (the settling of the scene excluded), as the report counts it."""
        return self.world.clock.now() - self.start_s

    def run(self) -> SessionReport:
        """Tick the tree to the end; returns the report. The world stays open for inspection.

        A recorded file that cannot be written (a full disk, the folder removed or read-only) does
        not stop the run: each file is whole or absent, and at the end a ``RecordError`` carries the
        report (``result``) and names the file and the cause ("the run finished, its record did not").
        """
        py_trees.blackboard.Blackboard.clear()
        # The camera's own error, for every decorator that judges "within" (bt_arrange.uncertainty).
        py_trees.blackboard.Blackboard.set(CAMERA_MARGIN_KEY, self.camera_margin_mm)
        log = TransitionLog(self.record_dir / "transitions.jsonl" if self.record_dir else None)
        if self.record_dir is not None:
            self.replay = ReplayRecorder(self.root)
            self._save_image("before_picking")
        # run.mcap and the live Foxglove view: an observer on the hooks below (None without either).
        streams = foxglove_streams.start(self)
        runner = Runner(
            self.root,
            self.context,
            self.world.step,
            time_limit_s=self.time_limit_s,
            log=log,
            on_transition=self._on_transition,
            on_tick=self._on_tick,
        )
        for hook in self.runner_hooks:
            hook(runner)
        result = runner.run()
        if self.record_dir is not None:
            self._save_image("after_pushing")
            assert self.replay is not None
            self.replay.observe(self.world.clock.now())  # a stop at the time limit comes after the last tick
        report = SessionReport(
            objects=self._outcomes(
                result.transitions, result.feedback if result.timed_out or result.safety_stop else ""
            ),
            tree_status=result.status.value,
            threshold_mm=self.plan.tolerance.threshold_mm if self.plan is not None else None,
            yaw_threshold_deg=self.plan.tolerance.yaw_threshold_deg if self.plan is not None else None,
            sim_seconds=result.sim_seconds,
            wall_seconds=result.wall_seconds,
            timed_out=result.timed_out,
            transitions=result.transitions,
            ground_truth=self.truth is not None,
            camera_margin_mm=self.camera_margin_mm,
            camera_margin_source=self.camera_margin_source,
            safety_stop=result.safety_stop,
        )
        for report_hook in self.report_hooks:
            report_hook(report)
        if streams is not None:
            streams.finish(report)
            if self.mcap_path is not None and streams.records:
                with self.faults.guard(self.mcap_path):
                    files.write_bytes(self.mcap_path, streams.mcap_bytes())
        if self.record_dir is not None:
            self._finish_log(log, result.transitions)
            replay = self.replay
            assert replay is not None
            ends: dict[str, Callable[[Path], object]] = {
                "report.json": lambda path: files.write_json(path, report.to_dict()),
                "replay.html": lambda path: replay.write(path, title=self.title, summary=report.to_dict()),
            }
            if streams is not None and streams.records:
                recorded = streams
                ends[foxglove_streams.MCAP_NAME] = lambda path: files.write_bytes(path, recorded.mcap_bytes())
            for name, write in ends.items():
                path = self.record_dir / name
                with self.faults.guard(path):
                    if not self.record_dir.is_dir():  # removed while running: not made again behind the user's back
                        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(path))
                    write(path)
        if self.faults:
            raise RecordError(
                f"{self.faults.message()}; the run finished, its record did not",
                faults=self.faults.faults,
                result=report,
            )
        return report

    def _finish_log(self, log: TransitionLog, transitions: list[Transition]) -> None:
        """A transition log a fault stopped is written again whole; if that fails too, it is removed."""
        if log.fault is None or log.path is None:
            return
        try:
            files.write_text(log.path, "".join(t.to_json() + "\n" for t in transitions))
        except OSError as error:
            self.faults.add(log.path, error)
            with contextlib.suppress(OSError):
                log.path.unlink()  # complete or absent: never a log that ends where the disk filled

    def close(self) -> None:
        """Close the world, empty the blackboard (read it before), give the kinematics model back, collect cycles."""
        self.world.close()
        py_trees.blackboard.Blackboard.clear()
        # The tree and its context form cycles: the kinematics' placo model goes back now, not when collected.
        self.context.planner.kinematics.release()
        # What runs left in cycles (2,000 objects a run, their native buffers) goes now: left to the
        # collector's full passes (every ~35 runs) it grew 100 four-cube runs by 16 MB. About 20 ms.
        gc.collect()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def node(self, transition: Transition) -> py_trees.behaviour.Behaviour | None:
        """The behaviour of the tree a transition is about (by its ``node_id``), or None."""
        if transition.node_id not in self.nodes:  # a node built while the tree runs (a solved puzzle's)
            self.nodes = {str(node.id): node for node in self.root.iterate()}
        return self.nodes.get(transition.node_id)

    def part_of(self, target: Target) -> str:
        """The part of the world that is ``target``'s (ground truth; without it, the target's name).

        The one of its name, or, for identical parts, the one of its kind nearest the target.
        """
        if target.obj in self.puzzle_truth.parts:
            return self.puzzle_truth.parts[target.obj]
        siblings = [t for t in self._targets() if t.colour == target.colour and t.object_type == target.object_type]
        if len(siblings) <= 1 or self.truth is None:
            return target.obj
        truth = self.truth
        names = {t.obj for t in siblings}
        candidates = [name for name in truth.part_names() if name in names]

        def distance(name: str) -> float:
            x, y, _ = truth.planar_pose(name)
            return math.hypot(x - target.x_m, y - target.y_m)

        return min(candidates, key=distance) if candidates else target.obj

    # -- while the tree runs -------------------------------------------------------------------

    def _on_transition(self, transition: Transition) -> None:
        for hook in self.transition_hooks:
            hook(transition)
        node = self.node(transition)
        if isinstance(node, Pick) and transition.old != Status.RUNNING.value and transition.new != Status.INVALID.value:
            self.placements.pick_started(node.obj)  # a Pick starts: after a placing, a regrasp
        if isinstance(node, ArrangeSolved) and node.arranged and self.plan is not None:
            self.plan = self.plan.joined(node.arranged)  # a puzzle's pieces join the plan once it built them
        if transition.new != Status.SUCCESS.value:
            return
        if isinstance(node, Place) and node.obj is not None:
            counts = self._set_downs if node.where == "pick" else self._placings
            counts[node.obj] = counts.get(node.obj, 0) + 1
        if isinstance(node, Separate):
            self._separations[node.obj] = self._separations.get(node.obj, 0) + 1
        if isinstance(node, PushAside) and node.for_obj:
            self._moved_aside.setdefault(node.for_obj, []).append(node.obj)
        if isinstance(node, SurveyPieces):
            self.puzzle_truth.surveyed(node.spec, node.pieces)
        if self._rechecks and isinstance(node, Inspect):
            self._track_truth(node)
        # The Inspects after placing, by their own flag rather than their names; a regrasp's next look.
        stem = None
        if isinstance(node, Inspect) and self.plan is not None:
            obj = node.obj
            stem = self.placements.inspected(obj, node.after_placing, lambda first: self._placement(obj, first))
        if self.record_dir is None:
            return
        if stem is not None:
            self._save_image(stem)
        elif node is not None and node is self._place_all:
            self._save_image("after_placing")

    def _placement(self, obj: str, first: bool) -> Placement:
        """The camera's figures of ``obj`` now (those after placing, for the first placing) and the ground truth's."""
        board = py_trees.blackboard.Client(name="report")
        placed = (keys.PLACED_OFFSET_MM, keys.PLACED_YAW_ERROR_DEG)
        offset, yaw = placed if first else (keys.OFFSET_MM, keys.YAW_ERROR_DEG)
        target = next((t for t in self._targets() if t.obj == obj), None)
        truth = self._truth_offset_mm(target) if target is not None else None
        return Placement(_get(board, keys.key(obj, offset)), _get(board, keys.key(obj, yaw)), truth)

    def _track_truth(self, node: Inspect) -> None:
        """Ground truth at each look at an object; at a ``Recheck``, how far it moved since the last look.

        With identical parts the part looked at is the one of its kind nearest its target (``part_of``).
        """
        if self.truth is None:
            return
        target = next((t for t in self._targets() if t.obj == node.obj), None)
        x, y, _ = self.truth.planar_pose(self.part_of(target) if target is not None else node.obj)
        before = self._looked_truth_xy.get(node.obj)
        if isinstance(node, Recheck) and before is not None:
            moved = math.hypot(x - before[0], y - before[1]) * 1000
            self._moved_truth_mm[node.obj] = max(self._moved_truth_mm.get(node.obj, 0.0), moved)
        self._looked_truth_xy[node.obj] = (x, y)

    def _on_tick(self, root: py_trees.behaviour.Behaviour) -> None:
        if self.replay is not None:
            self.replay.observe(self.world.clock.now())
        for hook in self.tick_hooks:
            hook(root)

    def _save_image(self, stem: str) -> None:
        import cv2

        assert self.record_dir is not None
        frame = self.world.capture_image()
        path = self.record_dir / f"{stem}.png"
        encoded, png = cv2.imencode(".png", cv2.cvtColor(frame.rgb, cv2.COLOR_RGB2BGR))
        data = png.tobytes() if encoded else None
        if data is not None:
            with self.faults.guard(path):
                files.write_bytes(path, data)
        if self.replay is not None and data is not None:
            self.replay.add_image(self.world.clock.now(), stem.replace("_", " "), path, data)

    # -- the report ----------------------------------------------------------------------------

    def _outcomes(self, transitions: list[Transition], stopped: str = "") -> list[ObjectOutcome]:
        if self.plan is None:
            return []
        report = py_trees.blackboard.Client(name="report")
        outcomes = []
        for target in self._targets():
            first = self.placements.first.get(target.obj)
            again = self.placements.again.get(target.obj, Placement(None, None, None))
            # The first placing's figures, kept by the log (a regrasp's look after placing writes the keys again).
            placed = first.offset_mm if first else _get(report, keys.key(target.obj, keys.PLACED_OFFSET_MM))
            placed_yaw = first.yaw_error_deg if first else _get(report, keys.key(target.obj, keys.PLACED_YAW_ERROR_DEG))
            final = _get(report, keys.key(target.obj, keys.OFFSET_MM))
            final_yaw = _get(report, keys.key(target.obj, keys.YAW_ERROR_DEG))
            status = self._status(final, final_yaw, _get(report, keys.key(target.obj, keys.MEASURED_ON)))
            outcomes.append(
                ObjectOutcome(
                    name=target.obj,
                    target=(target.x_m, target.y_m, target.yaw_rad),
                    placed_offset_mm=_rounded(placed),
                    final_offset_mm=_rounded(final),
                    final_offset_truth_mm=_rounded(self._truth_offset_mm(target)),
                    placed_offset_truth_mm=_rounded(first.offset_truth_mm if first else None),
                    pushes=int(_get(report, keys.key(target.obj, keys.CORRECTIONS)) or 0),
                    status=status,
                    reason="" if status == "within" else (self._last_failure(transitions, target.obj) or stopped),
                    placed_yaw_error_deg=_rounded(placed_yaw),
                    final_yaw_error_deg=_rounded(final_yaw),
                    final_yaw_error_truth_deg=_rounded(self._truth_yaw_error_deg(target)),
                    object_type=target.object_type.name,
                    size_mm=tuple(round(v * 1000, 3) for v in target.object_type.size_m),  # type: ignore[arg-type]
                    moved_by_later_mm=_rounded(_get(report, keys.key(target.obj, keys.MAX_MOVED_MM))),
                    moved_by_later_truth_mm=_rounded(self._moved_truth_mm.get(target.obj)),
                    regrasps_after_placing=self.placements.regrasps.get(target.obj, 0),
                    placed_again_offset_mm=_rounded(again.offset_mm),
                    placed_again_offset_truth_mm=_rounded(again.offset_truth_mm),
                    placed_again_yaw_error_deg=_rounded(again.yaw_error_deg),
                    truth_home_mm=self._truth_home_mm(target),
                    set_downs=self._set_downs.get(target.obj, 0),
                    separations=self._separations.get(target.obj, 0),
                    moved_aside=list(self._moved_aside.get(target.obj, [])),
                    placed_again=max(0, self._placings.get(target.obj, 0) - 1),
                    # A part that keeps the set-down (a box among neighbours, a part on others) has no look to say so.
                    held_look=str(_get(report, keys.key(target.obj, keys.HELD_LOOK)) or "")
                    or (keys.SET_DOWN if self._set_downs.get(target.obj, 0) else ""),
                )
            )
        return outcomes + self._unsolved_pieces(transitions, stopped)

    def _targets(self) -> list[Target]:
        """The plan's targets (a puzzle's pieces among them once built), none without a plan."""
        return list(self.plan.targets) if self.plan is not None else []

    def _truth_home_mm(self, target: Target) -> tuple[float, float, float] | None:
        """A puzzle piece's true home (x mm, y mm, yaw deg; evaluation only), None for other targets."""
        home = self.puzzle_truth.home(target, self._targets())
        return (
            None
            if home is None
            else (round(home[0] * 1000, 3), round(home[1] * 1000, 3), round(math.degrees(home[2]), 3))
        )

    def _unsolved_pieces(self, transitions: list[Transition], stopped: str) -> list[ObjectOutcome]:
        """A failed outcome for each piece of a puzzle that was never solved, with the puzzle's reason."""
        named = {t.obj for t in self._targets()}
        outcomes = []
        for spec in self.plan.puzzles if self.plan is not None else ():
            reason = self._last_failure(transitions, spec.name) or stopped or "the puzzle was not solved"
            for name in spec.piece_names:
                if name not in named:
                    outcomes.append(
                        ObjectOutcome(
                            name, (spec.x_m, spec.y_m, spec.yaw_rad), None, None, None, None, 0, "failed", reason
                        )
                    )
        return outcomes

    def _last_failure(self, transitions: list[Transition], obj: str) -> str:
        """Why ``obj`` was not finished: the first real cause, not the last symptom.

        Among the behaviours of ``obj`` (``REASON_TYPES``), the first failure after the last success:
        a Place that found no target, not the Detect that then looked for a part still in the pads.
        """
        ended = []
        for transition in transitions:
            node = self.node(transition)
            if transition.new in (Status.SUCCESS.value, Status.FAILURE.value) and isinstance(node, REASON_TYPES):
                if object_of(node) == obj:
                    ended.append(transition)
        last_success = max((i for i, t in enumerate(ended) if t.new == Status.SUCCESS.value), default=-1)
        failures = [t for t in ended[last_success + 1 :] if t.new == Status.FAILURE.value]
        if failures:
            return failures[0].feedback
        earlier = [t for t in ended if t.new == Status.FAILURE.value]
        return earlier[-1].feedback if earlier else ""

    def _status(
        self, final_offset_mm: float | None, final_yaw_error_deg: float | None = None, measured_on: Any = None
    ) -> str:
        """Within only when the offset with the camera's margin, and the yaw error, are under their thresholds.

        ``unconfirmed`` when they are but the last look measured the part on its free edges only
        (``keys.FREE_EDGES``: a measurement the camera's margin does not cover), or did not find it
        (``keys.NOT_MEASURED``: the offset is from an earlier look).
        """
        if final_offset_mm is None or self.plan is None:
            return "failed"
        within = self.plan.tolerance.within(final_offset_mm, final_yaw_error_deg, self.camera_margin_mm)
        if within and measured_on in (keys.FREE_EDGES, keys.NOT_MEASURED):
            return "unconfirmed"
        return "within" if within else "outside"

    def _truth_offset_mm(self, target: Target) -> float | None:
        """From the part to its target; a puzzle's piece, to its true home (``truth_home_mm``)."""
        if self.truth is None:
            return None
        x, y, _ = self.truth.planar_pose(self.part_of(target))
        target = self.puzzle_truth.home_target(target, self._targets())
        return PlanarPose(x, y).distance_to(target.planar) * 1000

    def _truth_yaw_error_deg(self, target: Target) -> float | None:
        if self.truth is None:
            return None
        _, _, yaw = self.truth.planar_pose(self.part_of(target))
        target = self.puzzle_truth.home_target(target, self._targets())
        return math.degrees(yaw_error_rad(target.object_type.shape, yaw, target.yaw_rad))


def _rounded(value: float | None) -> float | None:
    return None if value is None else round(float(value), 4)


def _get(client: py_trees.blackboard.Client, key: str) -> Any:
    """A value through a report's client (registered to read ``key``), or None when nothing wrote it."""
    client.register_key(key, access=Access.READ)
    return client.get(key) if client.exists(key) else None
