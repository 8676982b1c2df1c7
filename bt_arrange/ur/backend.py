"""The real UR5 cell as a ``bt_arrange.backends.Backend`` (entry point ``ur``; the ``ur`` extra installs ur-rtde).

``bt-arrange run TREE --backend ur --robot HOST [--camera SPEC] [--calibration camera.toml]
[--speed-fraction F] [--dry-run]``: the arm through ur_rtde, the 2F-85 through the Robotiq URCap's
socket, the top camera through ``bt_arrange.ur.camera``. A tree file needs only ``create_root``: the
real parts lie where they lie, so this backend scatters nothing (it is no ``ScatteringBackend``).
Every motion runs at a speed fraction (``REAL_CELL_SPEED_FRACTION`` unless raised) inside the cell's
workspace box (``bt_arrange.paper_cell.WORKSPACE``). docs/real-cell.md says how to wire a cell.

Imports nothing heavy at module level: the command line loads every backend to build its help.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import py_trees

from bt_arrange import paper_cell
from bt_arrange.errors import BackendError
from bt_arrange.motion.safety import REAL_CELL_SPEED_FRACTION, SafetyStop, WorkspaceBox

if TYPE_CHECKING:
    from bt_arrange.session import Session

#: The camera a cell serves beside its controller when ``--camera`` is not given (a network camera).
DEFAULT_CAMERA_PORT = 8081

#: What a dry run cannot plan as a run would, for its summary.
DRY_RUN_LIMITS = (
    "the corrections: a push is planned from what the camera measures after a place, and a dry run places "
    "nothing (its looks after placing see each part where it lay); each grasp is assumed to take, at the "
    "width of the plan's part"
)


class UrBackend:
    """A real UR5 + Robotiq 2F-85 + top camera, reached over the network (``connect_to`` first)."""

    name = "ur"
    #: Without ``--speed-fraction`` a real cell's motions run at half the speed the simulator's do.
    default_speed_fraction = REAL_CELL_SPEED_FRACTION
    #: The box the TCP must stay in, checked for every planned motion: the paper's cell's (a lab's own cell
    #: subclasses the backend with its box, docs/real-cell.md).
    workspace: WorkspaceBox = paper_cell.WORKSPACE
    dry_run_limits = DRY_RUN_LIMITS

    def __init__(self) -> None:
        self.robot_host: str | None = None
        self.camera_spec: str | None = None

    def connect_to(self, robot_host: str | None, camera_spec: str | None) -> None:
        """Where the controller (``--robot``) and the camera (``--camera``) are; nothing is opened yet."""
        self.robot_host = robot_host
        self.camera_spec = camera_spec

    # -- what a command opens ------------------------------------------------------------------

    def _host(self) -> str:
        if not self.robot_host:
            raise BackendError("backend 'ur' needs --robot HOST: the robot controller's address (docs/real-cell.md)")
        return self.robot_host

    def _camera(self, calibration: Any = None) -> Any:
        """The camera driver of ``--camera`` (default: the cell's network camera beside the controller)."""
        from bt_arrange import paper_cell
        from bt_arrange.ur.camera import open_camera

        spec = self.camera_spec or f"http://{self._host()}:{DEFAULT_CAMERA_PORT}/"
        intrinsics = calibration.intrinsics if calibration is not None else None
        return open_camera(spec, paper_cell.camera_pose_world(), intrinsics)

    def open_run(
        self,
        root: py_trees.behaviour.Behaviour,
        starts: Iterable[Any] = (),
        *,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        title: str | None = None,
        calibration: str | Path | None = None,
        speed_fraction: float | None = None,
        dry_run: bool = False,
        **options: Any,
    ) -> Session:
        """A run on the real cell (``dry_run``: on its shadow): plan checked, robot connected, not yet ticked.

        ``starts`` is ignored (a real cell's parts lie where they lie). ``calibration`` is a
        ``camera.toml`` (``bt-arrange calibrate --backend ur``); without it, the camera's factory
        intrinsics at the cell's nominal mount. Options of the simulators (``cell``, ``inject``) are
        refused in one line.
        """
        from bt_arrange.calibration.file import read_calibration_option
        from bt_arrange.motion.safety import MotionSafety
        from bt_arrange.plan.camera_view import CameraView

        self._refuse(options, gui)
        host = self._host()
        calibrated = read_calibration_option(calibration) if calibration is not None else None
        camera = self._camera(calibrated)
        safety = MotionSafety(
            speed_fraction=self.default_speed_fraction if speed_fraction is None else speed_fraction,
            workspace=self.workspace,
        )
        held_width_m = _held_width_m(root)

        def open_world() -> Any:
            return open_world_of(host, camera, dry_run=dry_run, held_width_m=held_width_m)

        return ur_session(
            root,
            open_world,
            view=CameraView(camera.intrinsics, camera.pose_world),
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            title=title,
            calibration=calibrated,
            motion_safety=safety,
            dry_run=dry_run,
        )

    def _refuse(self, options: dict[str, Any], gui: bool) -> None:
        if gui:
            raise BackendError("backend 'ur' has no window: --gui is the simulators' (watch the robot, or --live)")
        if options:
            names = ", ".join("--" + name.replace("_", "-") for name in options if name != "run_seed")
            raise BackendError(f"backend 'ur' takes no {names}: a real cell's errors are its own (docs/real-cell.md)")

    def open_calibration(
        self,
        *,
        views: int = 20,
        gui: bool = False,
        record_dir: Path | None = None,
        time_limit_s: float = 1800.0,
        speed_fraction: float | None = None,
        **options: Any,
    ) -> Any:
        """The ChArUco procedure on the real cell: the board bolted to the flange (``BoardMount``), not yet ticked.

        The poses are planned on the camera's factory intrinsics at the nominal mount, as in the simulator;
        the printed table sheet is looked for first (the procedure goes on without it).
        """
        from bt_arrange.calibration import BoardMount, CharucoBoard, board_poses
        from bt_arrange.calibration.board import TABLE_SHEET
        from bt_arrange.calibration.procedure import working_plane_poses
        from bt_arrange.calibration_run import CalibrationRun
        from bt_arrange.motion.safety import MotionSafety
        from bt_arrange.plan.camera_view import CameraView

        self._refuse(options, gui)
        host = self._host()
        camera = self._camera()
        view = CameraView(camera.intrinsics, camera.pose_world)
        board, mount = CharucoBoard(), BoardMount()
        poses = board_poses(view, board, mount, count=views - views // 2)
        plane_poses = working_plane_poses(view, board, mount, count=views // 2)

        def open_world() -> Any:
            return open_world_of(host, camera, dry_run=False, held_width_m=0.0)

        return CalibrationRun(
            open_world,
            poses,
            view=view,
            board=board,
            cell="ur",
            record_dir=record_dir,
            time_limit_s=time_limit_s,
            plane_poses=plane_poses,
            sheet=TABLE_SHEET,
            motion_safety=MotionSafety(
                self.default_speed_fraction if speed_fraction is None else speed_fraction, self.workspace
            ),
        )

    def check(self) -> Iterator[str]:
        """Lines for ``bt-arrange info``: the controller, the gripper and the camera answer (nothing moves)."""
        import math

        from bt_arrange.ur.robotiq import RobotiqSocket
        from bt_arrange.ur.rtde import connect_receive, fault_reason

        host = self._host()
        receive = connect_receive(host)
        try:
            q_deg = ", ".join(f"{math.degrees(v):.1f}" for v in receive.getActualQ())
            state = fault_reason(host, receive, None) or "no stop"
            time_s = receive.getTimestamp()
            yield f"robot {host}: RTDE ok, controller time {time_s:.1f} s, joints ({q_deg}) deg, {state}"
        finally:
            receive.disconnect()
        link = RobotiqSocket(host)
        try:
            yield f"gripper {link.address}: STA {link.get('STA')}, POS {link.get('POS')}, FLT {link.get('FLT')}"
        finally:
            link.close()
        camera = self._camera()
        k = camera.intrinsics
        try:
            frame = camera.capture()
        except SafetyStop as stop:
            raise BackendError(stop.reason) from None
        yield (
            f"camera {self.camera_spec or 'default'}: {camera.model}, {k.width_px}x{k.height_px} px, "
            f"fx {k.fx_px:.1f} px; one frame {frame.rgb.shape[1]}x{frame.rgb.shape[0]} px"
        )

    def prepare_out(self, path: Path) -> Path:
        """``bt_arrange.session.prepare_record_dir``."""
        from bt_arrange.session import prepare_record_dir

        return prepare_record_dir(path)

    @property
    def experiment(self) -> None:
        """A real cell runs no campaign of seeded trials."""
        return None


def open_world_of(host: str, camera: Any, *, dry_run: bool, held_width_m: float) -> Any:
    """The real cell's world (or, ``dry_run``, its shadow): connected, the gripper activated, checked."""
    from bt_arrange.ur.robotiq import RobotiqGripper, RobotiqSocket
    from bt_arrange.ur.rtde import connect_control, connect_receive
    from bt_arrange.ur.world import DryRunWorld, UrWorld

    receive = connect_receive(host)
    if dry_run:
        from bt_arrange.robot import GRIPPER_MAX_WIDTH_M

        world: Any = DryRunWorld(host, receive, camera, GRIPPER_MAX_WIDTH_M, held_width_m)
    else:
        try:
            control = connect_control(host)
            gripper = RobotiqGripper(RobotiqSocket(host))
            gripper.activate()
        except BaseException:
            receive.disconnect()
            raise
        world = UrWorld(host, receive, control, gripper, camera)
    if hasattr(camera, "use_clock"):
        camera.use_clock(world.clock.now)
    return world


def _held_width_m(root: py_trees.behaviour.Behaviour) -> float:
    """The width a dry run's shadow pads close to: the plan's first part's grasped side (0 without a plan)."""
    from bt_arrange.settings import ManipulationSettings
    from bt_arrange.shapes import preferred_grasp
    from bt_arrange.trees import plan_of

    plan = plan_of(root)
    if plan is None or not plan.targets:
        return 0.0
    settings = plan.settings or ManipulationSettings()
    return float(preferred_grasp(plan.targets[0].object_type.shape, settings.gripper).width_m)


def ur_session(root: Any, open_world: Callable[[], Any], *, dry_run: bool = False, **options: Any) -> Session:
    """A ``bt_arrange.session.Session`` on the real cell; a dry run's adds its summary to the report (``dry_run``)."""
    from bt_arrange.session import Session

    session = Session(root, None, open_world, **options)
    if dry_run:
        _attach_dry_run(session)
    return session


def _attach_dry_run(session: Any) -> None:
    """Count the motions the planner makes, and add the dry run's summary to the report."""
    import math

    motions: list[float] = []
    session.context.planner.planned_hooks.append(lambda motion, what: motions.append(motion.duration_s))
    world = session.world
    fraction = session.motion_safety.speed_fraction

    def summarise(report: Any) -> None:
        start = ", ".join(f"{math.degrees(v):.1f}" for v in world.start_q)
        refused = 1 if report.safety_stop else 0
        # Nothing was placed: the offsets are of the parts where they lie, not a verdict on the plan.
        for outcome in report.objects:
            outcome.status = "dry run"
            outcome.reason = "nothing was placed: the looks after placing saw the part where it lay"
        outcome = f"refused: {report.safety_stop}" if refused else f"the tree ended {report.tree_status}"
        report.dry_run = {
            "motions": len(motions),
            "motion_s": round(sum(motions), 3),
            "speed_fraction": fraction,
            "start_q_deg": [round(math.degrees(v), 3) for v in world.start_q],
            "refused": refused,
            "summary": (
                f"planned {len(motions)} motions ({sum(motions):.1f} s of motion at speed fraction {fraction:g}) "
                f"from the robot's joints ({start}) deg; {outcome}; nothing was sent to the robot (its control "
                f"interface was never opened). Not planned as a run would: {DRY_RUN_LIMITS}"
            ),
        }

    session.report_hooks.append(summarise)
