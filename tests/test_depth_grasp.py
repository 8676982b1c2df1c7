"""The depth-only grasp estimator (substitute for Berscheid et al.) on synthetic depth images, and its behaviour.

Depth images are ray-cast with numpy from the intrinsics: a flat table at z = 0 seen from 0.70 m
and boxes (5 cm cubes unless told) at known poses, sampled at pixel centres.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from bt_arrange.behaviours import GraspGuard, Pick, keys
from bt_arrange.behaviours.grasp_estimation import EstimateGraspFromDepth
from bt_arrange.errors import PerceptionError, PlanError
from bt_arrange.geometry import Pose, fold_yaw
from bt_arrange.motion import DEFAULT_HOME_Q
from bt_arrange.objects import ObjectType
from bt_arrange.perception import Detection, DetectionStatus
from bt_arrange.perception.depth_grasp import (
    SEARCH_BINNING,
    SOURCE,
    DepthGraspConfig,
    DepthGraspEstimator,
    SensorGrid,
    scaled_intrinsics,
)
from bt_arrange.perception.synthetic import sim_intrinsics, top_down_camera_pose
from bt_arrange.plan import compile_plan
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow
from bt_arrange.shapes import Prism
from bt_arrange.testing import fake_arm, make_context, tick_until_done
from bt_arrange.trees import Target, by_depth, transfer

#: Rendered wider than the sensor's 1024 px, so the estimator resamples like it does the cell's frames.
WIDTH_PX, HEIGHT_PX = 1280, 720
INTRINSICS = sim_intrinsics(WIDTH_PX, HEIGHT_PX)
CAMERA = top_down_camera_pose()  # 0.70 m above (0.5, 0), looking down
CLEAN = DepthGraspConfig(noise_sigma_m=0.0, depth_unit_m=0.0)


@dataclass(frozen=True)
class Box:
    """A box on the table: centre (x, y), yaw, footprint and height in metres; ``z0_m`` lifts it."""

    x_m: float
    y_m: float
    yaw_rad: float = 0.0
    size_m: tuple[float, float] = (0.05, 0.05)
    height_m: float = 0.05
    z0_m: float = 0.0


def render_depth(boxes: list[Box], intrinsics: CameraIntrinsics = INTRINSICS, camera: Pose = CAMERA) -> np.ndarray:
    """Depth along the optical axis (float32 metres) of the table and the boxes, at pixel centres."""
    u, v = np.meshgrid(np.arange(intrinsics.width_px, dtype=float), np.arange(intrinsics.height_px, dtype=float))
    rays_c = np.stack(
        [(u - intrinsics.cx_px) / intrinsics.fx_px, (v - intrinsics.cy_px) / intrinsics.fy_px, np.ones_like(u)], -1
    )
    directions = rays_c @ camera.rotation.T  # P = origin + t * direction, t = depth along the optical axis
    origin = camera.position_m
    depth = -origin[2] / directions[..., 2]  # the table plane z = 0
    with np.errstate(divide="ignore", invalid="ignore"):
        for box in boxes:
            c, s = math.cos(box.yaw_rad), math.sin(box.yaw_rad)
            to_box = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
            o = to_box @ (origin - np.array([box.x_m, box.y_m, box.z0_m]))
            d = directions @ to_box.T
            low = np.array([-box.size_m[0] / 2, -box.size_m[1] / 2, 0.0])
            high = np.array([box.size_m[0] / 2, box.size_m[1] / 2, box.height_m])
            t1, t2 = (low - o) / d, (high - o) / d
            t_near = np.nanmax(np.minimum(t1, t2), axis=-1)
            t_far = np.nanmin(np.maximum(t1, t2), axis=-1)
            hit = (t_near <= t_far) & (t_near > 0)
            depth = np.where(hit & (t_near < depth), t_near, depth)
    return depth.astype(np.float32)


def frame_of(boxes: list[Box], intrinsics: CameraIntrinsics = INTRINSICS, camera: Pose = CAMERA) -> CameraFrame:
    """A frame with the depth of ``boxes`` and a black colour image: the estimator must not need colour."""
    rgb = np.zeros((intrinsics.height_px, intrinsics.width_px, 3), dtype=np.uint8)
    return CameraFrame(rgb, render_depth(boxes, intrinsics, camera), intrinsics, camera, 0.0)


def error_mm(detection: Detection, box: Box) -> float:
    assert detection.pose_world is not None, detection.reason
    return math.hypot(detection.pose_world.x_m - box.x_m, detection.pose_world.y_m - box.y_m) * 1000


def yaw_error_deg(detection: Detection, box: Box) -> float:
    assert detection.pose_world is not None, detection.reason
    return abs(math.degrees(fold_yaw(detection.pose_world.yaw_rad - box.yaw_rad)))


# -- the estimator, without noise ---------------------------------------------------------


def test_a_cube_below_the_camera_is_found_within_a_millimetre_and_half_a_degree():
    box = Box(0.5, 0.0, math.radians(20.0))
    detection = DepthGraspEstimator(CLEAN).estimate(frame_of([box]), name="red")
    assert detection.status is DetectionStatus.FOUND, detection.reason
    assert detection.colour == "red"
    assert error_mm(detection, box) < 1.0
    assert yaw_error_deg(detection, box) < 0.5
    assert detection.pose_world is not None and detection.pose_world.z_m == pytest.approx(0.025)
    assert detection.edge_m == pytest.approx(0.05, abs=0.003)


@pytest.mark.parametrize(
    "box",
    [
        Box(0.36, 0.25, math.radians(-33.0)),
        Box(0.64, -0.30, math.radians(7.0)),
        Box(0.60, 0.33, math.radians(44.0)),
        Box(0.40, -0.10, 0.0),
    ],
    ids=["near-left", "far-right", "far-left-44deg", "square"],
)
def test_cubes_off_the_centre_are_found_within_a_few_millimetres(box):
    """Seen obliquely, flying pixels along the far edges pull the centre outwards by millimetres."""
    detection = DepthGraspEstimator(CLEAN).estimate(frame_of([box]))
    assert detection.found, detection.reason
    assert error_mm(detection, box) < 3.5
    assert yaw_error_deg(detection, box) < 1.0


def test_yaw_follows_the_world_sense_of_rotation_and_is_folded_to_90_degrees():
    for yaw_deg, expected_deg in ((25.0, 25.0), (-25.0, -25.0), (70.0, -20.0), (120.0, 30.0)):
        box = Box(0.5, 0.05, math.radians(yaw_deg))
        detection = DepthGraspEstimator(CLEAN).estimate(frame_of([box]))
        assert detection.planar is not None
        assert math.degrees(detection.planar.yaw_rad) == pytest.approx(expected_deg, abs=0.7)


def test_an_empty_table_is_not_found_with_a_labelled_reason():
    detection = DepthGraspEstimator(CLEAN).estimate(frame_of([]))
    assert detection.status is DetectionStatus.NOT_FOUND
    assert detection.reason.startswith(SOURCE)
    assert "substitute for Berscheid et al." in detection.reason
    assert detection.pose_world is None


def test_a_flat_object_lower_than_the_threshold_is_not_a_cube():
    detection = DepthGraspEstimator(CLEAN).estimate(frame_of([Box(0.5, 0.0, size_m=(0.08, 0.08), height_m=0.02)]))
    assert detection.status is DetectionStatus.NOT_FOUND


def test_the_hint_selects_the_nearest_blob_and_without_it_the_largest():
    small, large = Box(0.42, -0.15, 0.3), Box(0.58, 0.18, -0.2, size_m=(0.06, 0.06))
    estimator = DepthGraspEstimator(CLEAN)
    frame = frame_of([small, large])
    near_small = estimator.estimate(frame, near_xy_m=(0.44, -0.12))
    assert near_small.found and error_mm(near_small, small) < 3.0
    assert "nearest the hint" in near_small.reason
    assert len(near_small.candidates_xy_m) == 2
    near_large = estimator.estimate(frame, near_xy_m=(0.55, 0.2))
    assert near_large.found and error_mm(near_large, large) < 3.0
    largest = estimator.estimate(frame)
    assert largest.found and error_mm(largest, large) < 3.0
    assert "largest of 2 blobs (colour-blind)" in largest.reason


def test_a_hint_far_from_every_blob_is_not_found_and_an_equidistant_one_is_ambiguous():
    estimator = DepthGraspEstimator(CLEAN)
    frame = frame_of([Box(0.5, -0.1), Box(0.5, 0.1)])
    far = estimator.estimate(frame, near_xy_m=(0.35, 0.35))
    assert far.status is DetectionStatus.NOT_FOUND
    assert "none within 100 mm of the hint" in far.reason
    between = estimator.estimate(frame, near_xy_m=(0.5, 0.0))
    assert between.status is DetectionStatus.AMBIGUOUS
    assert "equally near" in between.reason


def test_touching_cubes_are_ambiguous():
    detection = DepthGraspEstimator(CLEAN).estimate(frame_of([Box(0.5, 0.0), Box(0.5, 0.05)]))
    assert detection.status is DetectionStatus.AMBIGUOUS
    assert "faces" in detection.reason


def test_a_lifted_cube_and_a_cube_cut_by_the_image_border_are_partial():
    estimator = DepthGraspEstimator(CLEAN)
    lifted = estimator.estimate(frame_of([Box(0.5, 0.0, z0_m=0.06)]))
    assert lifted.status is DetectionStatus.PARTIAL
    assert "not a cube resting on the table" in lifted.reason
    # The 1280 x 720 image spans about y = -0.46..0.46 m at the table.
    cut = estimator.estimate(frame_of([Box(0.5, 0.45)]))
    assert cut.status is DetectionStatus.PARTIAL
    assert "border" in cut.reason


def test_a_box_that_is_not_a_cube_is_partial():
    detection = DepthGraspEstimator(CLEAN).estimate(frame_of([Box(0.5, 0.0, size_m=(0.05, 0.075))]))
    assert detection.status is DetectionStatus.PARTIAL
    assert "not 50 x 50 x 50 mm" in detection.reason


@pytest.mark.parametrize("yaw_deg", [0.0, 30.0, 75.0, -60.0])
def test_a_box_is_found_by_its_own_size_and_its_long_edge_along_x(yaw_deg):
    # Any box, not only the cube: the estimator asks the shape (rectangular) and reads its extent and height.
    bar = ObjectType("bar", (0.08, 0.04, 0.04))
    box = Box(0.5, 0.02, math.radians(yaw_deg), size_m=(0.08, 0.04), height_m=0.04)
    detection = DepthGraspEstimator(dataclasses.replace(CLEAN, part=bar)).estimate(frame_of([box]))
    assert detection.status is DetectionStatus.FOUND, detection.reason
    assert error_mm(detection, box) < 1.5
    assert abs(math.degrees(fold_yaw(detection.pose_world.yaw_rad - box.yaw_rad, math.pi))) < 1.0
    assert detection.pose_world.position_m[2] == pytest.approx(0.02)


def test_an_outline_that_is_no_box_is_refused_in_one_line():
    ell = ObjectType(
        "ell", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], 0.02)
    )
    with pytest.raises(PerceptionError, match="finds boxes only, not ell"):
        DepthGraspConfig(part=ell)


# -- the sensor model ---------------------------------------------------------------------


def test_the_depth_is_resampled_to_the_l515_width_with_scaled_intrinsics():
    view = DepthGraspEstimator(CLEAN).sensor_view(frame_of([Box(0.5, 0.0)]))
    assert view.depth_m.shape == (576, 1024)
    assert view.intrinsics.fx_px == pytest.approx(INTRINSICS.fx_px * 0.8)
    assert view.intrinsics.cx_px == pytest.approx((INTRINSICS.cx_px + 0.5) * 0.8 - 0.5)
    # The table reads z = 0 everywhere, the cube's top 5 cm.
    assert np.nanmax(np.abs(view.height_m[:50])) < 1e-4
    assert np.nanmax(view.height_m) == pytest.approx(0.05, abs=1e-4)


def test_scaled_intrinsics_keep_the_optical_centre_on_the_same_point():
    full = CameraIntrinsics.from_fov(1920, 1080, 70.0)
    small = scaled_intrinsics(full, 1024, 576)
    assert small.fx_px == pytest.approx(full.fx_px * 1024 / 1920)
    assert small.cx_px == pytest.approx(511.5)
    assert small.cy_px == pytest.approx(287.5)


def test_noise_is_reproducible_from_the_seed():
    estimator = DepthGraspEstimator()  # noise on by default
    frame = frame_of([Box(0.45, 0.2, 0.4)])
    first = estimator.estimate(frame, rng=np.random.default_rng(7))
    again = estimator.estimate(frame, rng=np.random.default_rng(7))
    other = estimator.estimate(frame, rng=np.random.default_rng(8))
    assert first.found and again.found and other.found
    assert first.pose_world is not None and again.pose_world is not None and other.pose_world is not None
    np.testing.assert_array_equal(first.pose_world.position_m, again.pose_world.position_m)
    assert not np.array_equal(first.pose_world.position_m, other.pose_world.position_m)
    view = estimator.sensor_view(frame, np.random.default_rng(7))
    table = view.depth_m[:60, :200]  # table only, 0.70 m away
    assert np.nanstd(table - np.nanmedian(table)) == pytest.approx(0.0015, rel=0.1)


def test_noise_leaves_the_error_in_millimetres():
    box = Box(0.62, -0.25, math.radians(12.0))
    detection = DepthGraspEstimator().estimate(frame_of([box]), rng=np.random.default_rng(0))
    assert detection.found, detection.reason
    assert error_mm(detection, box) < 4.0
    assert yaw_error_deg(detection, box) < 2.0


def test_configuration_mistakes_raise():
    estimator = DepthGraspEstimator()
    frame = frame_of([Box(0.5, 0.0)])
    with pytest.raises(PerceptionError, match="rng="):
        estimator.estimate(frame)
    with pytest.raises(PerceptionError, match="with_depth=True"):
        estimator.estimate(dataclasses.replace(frame, depth_m=None), rng=np.random.default_rng(0))
    with pytest.raises(PerceptionError, match="intrinsics say"):
        estimator.estimate(dataclasses.replace(frame, depth_m=frame.depth_m[:, :-1]), rng=np.random.default_rng(0))
    with pytest.raises(PerceptionError, match="min_height_m"):
        DepthGraspConfig(min_height_m=0.06)
    with pytest.raises(PerceptionError, match="noise_sigma_m"):
        DepthGraspConfig(noise_sigma_m=-0.001)


# -- looking only where something stands ----------------------------------------------------


def test_the_sensor_grid_tiles_the_image_in_blocks_that_resample_to_whole_sensor_pixels():
    grid = DepthGraspEstimator().sensor_grid(CameraIntrinsics.from_fov(1920, 1080, 70.0))
    assert (grid.width_px, grid.height_px, grid.block_px, grid.block_sensor_px) == (1024, 576, 15, 8)
    window = grid.window_covering(101, -20, 140, 44)
    assert window == PixelWindow(90, 0, 60, 45)
    assert grid.holds(window) and grid.sensor_pixels(window) == (48, 0, 32, 24)
    assert not grid.holds(PixelWindow(91, 0, 60, 45)) and not grid.holds(PixelWindow(0, 0, 60, 60, 15))
    narrow = DepthGraspEstimator().sensor_grid(sim_intrinsics(960, 540))
    assert not narrow.resamples and narrow.block_px == 1
    odd = SensorGrid(1000, 999, 500, 500)  # the axes scale differently: only the whole image tiles
    assert odd.block_px == 1000 and odd.window_covering(10, 10, 20, 20) == PixelWindow(0, 0, 1000, 999)


def test_a_window_off_the_sensor_blocks_is_refused():
    estimator = DepthGraspEstimator(CLEAN)
    window = PixelWindow(3, 0, 100, 100)
    frame = frame_of([Box(0.5, 0.0)], INTRINSICS.windowed(window))
    with pytest.raises(PerceptionError, match="whole 5 px blocks"):
        estimator.sensor_view(frame, window=window, image=INTRINSICS)


@pytest.mark.parametrize(
    ("boxes", "hint"),
    [
        ([Box(0.62, -0.25, math.radians(12.0))], None),
        ([Box(0.36, 0.25, math.radians(-33.0))], None),
        ([Box(0.42, -0.15), Box(0.58, 0.18, 0.3)], (0.6, 0.2)),
        ([Box(0.5, 0.0, 0.2, size_m=(0.05, 0.05), z0_m=0.03)], None),  # lifted: PARTIAL either way
    ],
    ids=["one", "near-left", "two-with-hint", "lifted"],
)
def test_looking_where_something_stands_gives_the_full_frames_estimate(boxes, hint):
    """Resampled (1280 px onto 1024) and noisy: the windowed estimate is the full frame's, noise and all."""
    estimator = DepthGraspEstimator()
    camera = DepthCamera(boxes, INTRINSICS)
    windowed = estimator.estimate_from(camera, hint, np.random.default_rng(11), name="red")
    full = estimator.estimate(frame_of(boxes), hint, np.random.default_rng(11), name="red")
    assert windowed.status is full.status and windowed.reason == full.reason
    if full.pose_world is not None:
        assert windowed.pose_world is not None
        np.testing.assert_allclose(windowed.pose_world.position_m, full.pose_world.position_m, atol=1e-9)
        assert windowed.pose_world.yaw_rad == pytest.approx(full.pose_world.yaw_rad, abs=1e-9)
    search, measure = camera.windows
    assert search is not None and search.binning == SEARCH_BINNING
    assert measure is not None and measure.binning == 1
    if len(boxes) == 1:
        assert camera.rendered_px < 0.08 * INTRINSICS.width_px * INTRINSICS.height_px


def test_an_empty_table_or_a_search_that_misses_looks_at_the_full_frame():
    estimator = DepthGraspEstimator(CLEAN)
    empty = DepthCamera([], INTRINSICS)
    outcome = estimator.estimate_from(empty)
    assert outcome.status is DetectionStatus.NOT_FOUND
    assert empty.windows[-1] is None, "nothing stands in the search view: the full frame says so"
    box = Box(0.55, 0.05, 0.4)
    misled = DepthCamera([box], INTRINSICS, search_shift_m=(0.03, 0.0))  # the window cuts the cube
    outcome = estimator.estimate_from(misled)
    assert [w is None for w in misled.windows] == [False, False, True]
    full = estimator.estimate(frame_of([box]))
    assert outcome.pose_world is not None and full.pose_world is not None
    np.testing.assert_allclose(outcome.pose_world.position_m, full.pose_world.position_m, atol=1e-9)


# -- the behaviour and the tree builder, with fake devices -----------------------------------


class DepthCamera:
    """A fake top camera that renders synthetic depth of ``boxes`` (960 x 540 px), or a window of it.

    ``search_shift_m`` moves the boxes in binned frames only: a search view that misplaces what stands.
    """

    def __init__(
        self,
        boxes: list[Box],
        intrinsics: CameraIntrinsics | None = None,
        search_shift_m: tuple[float, float] = (0.0, 0.0),
    ) -> None:
        self.boxes = boxes
        self._intrinsics = intrinsics or sim_intrinsics(960, 540)
        self.search_shift_m = search_shift_m
        self.with_depth: list[bool] = []
        self.windows: list[PixelWindow | None] = []

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self._intrinsics

    def capture(self, with_depth: bool = False, window: PixelWindow | None = None) -> CameraFrame:
        self.with_depth.append(with_depth)
        self.windows.append(window)
        boxes = self.boxes
        if window is not None and window.binning > 1:
            dx, dy = self.search_shift_m
            boxes = [dataclasses.replace(box, x_m=box.x_m + dx, y_m=box.y_m + dy) for box in boxes]
        intrinsics = self._intrinsics if window is None else self._intrinsics.windowed(window)
        frame = frame_of(boxes, intrinsics)
        return frame if with_depth else dataclasses.replace(frame, depth_m=None)

    @property
    def rendered_px(self) -> int:
        """Pixels rendered so far, every capture counted."""
        full = self._intrinsics.width_px * self._intrinsics.height_px
        return sum(full if w is None else w.out_width_px * w.out_height_px for w in self.windows)


def depth_context(boxes: list[Box], q: np.ndarray = DEFAULT_HOME_Q):
    context = make_context(q=q)
    camera = DepthCamera(boxes)
    context.robot = dataclasses.replace(context.robot, camera=camera)
    return context, camera


def setup(behaviour: py_trees.behaviour.Behaviour, context) -> py_trees.behaviour.Behaviour:
    for node in behaviour.iterate():
        node.setup(context=context)
    return behaviour


def test_the_behaviour_writes_the_estimated_pose_for_pick():
    box = Box(0.45, 0.1, 0.3)
    context, camera = depth_context([box])
    behaviour = setup(EstimateGraspFromDepth("estimate red", "red", "red", seed=3), context)
    run = tick_until_done(behaviour, context)
    assert run.status == Status.SUCCESS, run.feedback
    assert camera.with_depth == [True, True], "the search view, then the window around what stands"
    pose = py_trees.blackboard.Blackboard.get(keys.key("red", keys.POSE))
    assert math.hypot(pose.x_m - box.x_m, pose.y_m - box.y_m) < 4e-3
    assert "substitute for Berscheid et al." in run.feedback


def test_the_behaviour_fails_with_the_reason_when_nothing_stands_on_the_table():
    context, _ = depth_context([])
    run = tick_until_done(setup(EstimateGraspFromDepth("estimate red", "red"), context), context)
    assert run.status == Status.FAILURE
    assert run.feedback.startswith("red not_found: " + SOURCE)
    assert not py_trees.blackboard.Blackboard.exists(keys.key("red", keys.POSE))


def test_the_behaviour_parks_the_arm_before_looking():
    q = DEFAULT_HOME_Q + np.array([0.3, -0.1, 0.1, 0.0, 0.0, 0.2])
    context, camera = depth_context([Box(0.5, 0.0)], q=q)
    run = tick_until_done(setup(EstimateGraspFromDepth("estimate red", "red"), context), context)
    assert run.status == Status.SUCCESS, run.feedback
    assert len(run.running) > 10  # the move home
    assert np.max(np.abs(fake_arm(context).joint_positions() - DEFAULT_HOME_Q)) < 0.01
    assert camera.with_depth == [True, True]


def test_the_hint_is_used_and_the_seed_restarts_at_setup():
    first, second = Box(0.42, -0.15), Box(0.58, 0.18)
    context, _ = depth_context([first, second])
    behaviour = setup(EstimateGraspFromDepth("estimate blue", "blue", near_xy_m=(0.6, 0.2), seed=5), context)
    assert tick_until_done(behaviour, context).status == Status.SUCCESS
    pose = py_trees.blackboard.Blackboard.get(keys.key("blue", keys.POSE))
    assert math.hypot(pose.x_m - second.x_m, pose.y_m - second.y_m) < 4e-3
    setup(behaviour, context)
    assert tick_until_done(behaviour, context).status == Status.SUCCESS
    again = py_trees.blackboard.Blackboard.get(keys.key("blue", keys.POSE))
    np.testing.assert_array_equal(pose.position_m, again.position_m)
    with pytest.raises(PlanError, match="near_xy_m"):
        EstimateGraspFromDepth("bad", "blue", near_xy_m=(0.5,))  # type: ignore[arg-type]


def test_transfer_located_by_depth_mirrors_transfer():
    plan = compile_plan([Target("red", 0.5, 0.1)], max_regrasps=2)
    tree = transfer(plan.steps[0], plan, locate=by_depth(seed=4))
    assert isinstance(tree, py_trees.decorators.Retry)
    assert tree.num_failures == 3
    estimate, pick, guard = tree.decorated.children
    assert isinstance(estimate, EstimateGraspFromDepth) and estimate.seed == 4 and estimate.obj == "red"
    assert isinstance(pick, Pick) and isinstance(guard, GraspGuard)
    with pytest.raises(PlanError, match="max_regrasps"):
        compile_plan([Target("red", 0.5, 0.1)], max_regrasps=-1)


def test_the_estimator_behaviour_does_not_import_the_tree_builders():  # No import circle
    import subprocess
    import sys

    code = "import sys, bt_arrange.behaviours.grasp_estimation\nprint('bt_arrange.trees' in sys.modules)\n"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert result.stdout.strip() == "False"
    source = (Path(__file__).resolve().parents[1] / "bt_arrange" / "behaviours" / "grasp_estimation.py").read_text()
    assert "bt_arrange.trees import" not in source


def test_by_depth_looks_for_its_configured_box_type_and_names_it_when_a_target_is_another():
    bar = ObjectType("bar", (0.08, 0.04, 0.04))
    with pytest.raises(PlanError, match=r"looks for a cube \(50 x 50 x 50 mm\), not a bar"):
        by_depth()(Target("red", 0.5, 0.1, object_type=bar))
    estimator = DepthGraspEstimator(dataclasses.replace(CLEAN, part=bar))
    node = by_depth(estimator=estimator)(Target("red", 0.5, 0.1, object_type=bar))
    assert isinstance(node, EstimateGraspFromDepth)
