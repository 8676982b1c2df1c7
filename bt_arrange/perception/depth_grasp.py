"""A grasp pose from the depth image alone: a SUBSTITUTE for Berscheid et al.'s learned estimator.

The paper's Table 1, row 4, replaced the object pose estimation before picking (Algorithm 1,
line 6) with the learned 6-DoF grasp pose estimator of Berscheid et al. (2021), whose weights
are not available. This module is what a user can have instead: a plain geometric estimator on
the depth image, with the errors such an estimator really has. It is not that network and does
not claim its numbers; every outcome says so in its ``reason``
(:data:`SOURCE`: "depth-only grasp estimator (substitute for Berscheid et al.)").

What it does with ``frame.depth_m`` (never ``frame.rgb``)::

    depth (H x W, metres along the optical axis)
      -> resampled to the L515's depth width (1024 px), keeping the frame's aspect and field of view
      -> seeded depth noise (sigma 1.5 mm at 0.70 m, growing with depth) and 0.25 mm depth units
      -> back-projected to world points with the (scaled) intrinsics and T_W_C
      -> pixels standing more than 2.5 cm above the table -> connected blobs of a part's size
      -> the object's blob: nearest a hint position, else the largest
      -> cv2.minAreaRect of the blob's top points in world x, y: centre, yaw folded to 90 deg
      -> Detection(pose_world = part centre at z = table + edge / 2)

It is colour-blind by design: a learned grasp estimator proposes grasps on whatever object
stands on the table, and so does this one. With several parts in view it cannot tell the red
one from the blue one; pass ``near_xy_m`` (a colour-blind hint: where the object was put, or a
rough earlier estimate) or it takes the largest blob, which among equal parts is arbitrary.

Where its errors come from: the resampling's area averaging mixes the top face and the table
behind it into "flying pixels" along the part's far edges (real depth cameras show the same at
depth discontinuities); back-projected, they land outside the part, the farther out the more
obliquely the camera sees the part, and ``minAreaRect``, an extremal fit, follows them. Depth
noise moves points along their rays. The error is mostly a pull of the centre away from the
point below the camera, growing towards the edge of the view.

Measured with the defaults on 160 cubes of 40 scenes rendered by the pybullet cell (1920 x 1080,
``bt_arrange_sim.scenes.scatter``), against the simulator's ground truth: centre error mean
0.91 mm, sd 0.37, p95 1.50, max 1.86 mm; yaw error mean 0.26 deg, p95 0.71, max 1.98 deg. The
band of top points sets most of it: 5 mm gave a mean of 0.17 mm, 20 mm 2.85 mm; without
resampling (1920 px) 0.18 mm. In a one-cube tree (30 runs), the grasp's self-centring between
the pads leaves a placed offset of mean 0.58 mm, sd 0.33, max 1.58 mm (the colour detector:
0.13 mm): smaller than the paper's row 4 (5.18 +- 3.83 mm in simulation). See
``tests/integration/test_depth_grasp_cell.py``.

Outcomes are values, like :class:`~bt_arrange.perception.detection.PartDetector`'s:
FOUND, NOT_FOUND, AMBIGUOUS (a blob as large as several parts, or two blobs equally near the
hint) and PARTIAL (cut by the image border, not standing like a resting part, not of its size).
Only configuration mistakes raise :class:`~bt_arrange.errors.PerceptionError`: a frame without
depth, a depth image that does not match its intrinsics, noise without a random generator.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PerceptionError
from bt_arrange.geometry import FloatArray, Pose, fold_yaw
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.detection import Detection, DetectionStatus
from bt_arrange.robot import Camera, CameraFrame, CameraIntrinsics, PixelWindow

#: Every outcome's reason starts with this label: the estimator is a stand-in, not the paper's.
SOURCE = "depth-only grasp estimator (substitute for Berscheid et al.)"

#: The Intel RealSense L515's depth stream: 1024 x 768 px, about 70 x 55 degrees.
L515_DEPTH_WIDTH_PX = 1024


@dataclass(frozen=True)
class DepthGraspConfig:
    """What the estimator assumes about the sensor, the table and the parts (metres, pixels).

    ``part`` is the type it looks for (the paper's 5 cm cube by default): a box, the shape whose
    top face ``cv2.minAreaRect`` fits (``Shape.rectangular``); its height and top face set what a
    blob must measure.

    Sensor model: the depth image is resampled (area averaging) to ``depth_width_px`` columns,
    keeping the frame's aspect ratio and field of view (a 1920 x 1080 frame becomes
    1024 x 576 px: the L515's 1024 px width, not its 4:3 field of view), then each pixel gets
    Gaussian noise of ``noise_sigma_m * depth / noise_reference_depth_m`` and is rounded to
    ``depth_unit_m``. ``noise_sigma_m = 0`` and ``depth_unit_m = 0`` give the clean resampled depth.
    """

    part: ObjectType = CUBE
    #: World z of the table top.
    table_z_m: float = 0.0
    #: Columns of the sensor's depth image (the L515's 1024); frames narrower are not upsampled.
    depth_width_px: int = L515_DEPTH_WIDTH_PX
    #: Depth noise, one standard deviation, at ``noise_reference_depth_m`` (L515: a few mm at 0.7 m).
    noise_sigma_m: float = 0.0015
    noise_reference_depth_m: float = 0.70
    #: Depth quantisation: the L515's default depth unit is 0.25 mm.
    depth_unit_m: float = 0.00025
    #: Points standing higher than this above the table belong to objects (half a cube).
    min_height_m: float = 0.025
    #: The blob's top points: within this of its top height (a fifth of an edge, about 7 noise sigmas).
    top_band_m: float = 0.010
    #: A blob's top must stand this close to one edge above the table: a part resting on it.
    top_height_tolerance_m: float = 0.010
    #: Blobs smaller than this fraction of a face's area are specks, not parts, and are ignored.
    min_area_fraction: float = 0.25
    #: A blob this many faces large holds several parts (touching): AMBIGUOUS.
    ambiguous_area_fraction: float = 1.6
    #: Each side of the fitted rectangle, relative to the edge, for a whole part.
    side_fraction_range: tuple[float, float] = (0.8, 1.35)
    #: With a hint, only blobs whose centre lies within this distance of it are candidates.
    max_hint_distance_m: float = 0.10
    #: With a hint, two blobs whose distances to it differ by less than this are AMBIGUOUS.
    hint_margin_m: float = 0.01

    def __post_init__(self) -> None:
        if self.depth_width_px < 16:
            raise PerceptionError(f"depth_width_px={self.depth_width_px} is too small for a depth image")
        for name in ("noise_sigma_m", "depth_unit_m"):
            if not getattr(self, name) >= 0.0:
                raise PerceptionError(f"{name}={getattr(self, name)!r} must be 0 or more")
        shape = self.part.shape
        if not shape.rectangular:
            raise PerceptionError(
                f"the depth-only estimator fits rectangles, so it finds boxes only, not {self.part.name} "
                f"({shape.describe()})"
            )
        if not 0.0 < self.min_height_m < self.part_height_m:
            raise PerceptionError(f"min_height_m={self.min_height_m} must lie between 0 and the part's height")

    @property
    def part_height_m(self) -> float:
        """The height of the part's top face above the table."""
        return self.part.shape.height_m

    @property
    def noisy(self) -> bool:
        """True when depth noise is added (then ``estimate`` needs a random generator)."""
        return self.noise_sigma_m > 0.0

    @property
    def face_area_m2(self) -> float:
        """Area of one top face in square metres."""
        return self.part.shape.area_m2


#: Binning of the depth frame that searches the whole view for what stands on the table (4 mm per pixel).
SEARCH_BINNING = 8
#: Room around the standing pixels for the window that measures them, in search pixels (16 px, 8 mm).
SEARCH_MARGIN_BINS = 2
#: Sensor blocks wider than this (an image and a sensor of awkward sizes) are not windowed.
MAX_BLOCK_PX = 64


@dataclass(frozen=True)
class SensorGrid:
    """How a depth sensor's pixels lie on the camera's full image.

    ``width_px x height_px`` sensor pixels cover the ``image_width_px x image_height_px`` image;
    ``block_px`` image pixels span exactly ``block_sensor_px`` sensor pixels along either axis
    (1920 px onto 1024: 15 onto 8). A window whose edges lie on whole blocks resamples to exactly
    the sensor pixels the full image has there. Where the two axes scale differently the block
    is the whole image.
    """

    image_width_px: int
    image_height_px: int
    width_px: int
    height_px: int

    @property
    def resamples(self) -> bool:
        """True when the sensor's pixels are not the image's."""
        return (self.width_px, self.height_px) != (self.image_width_px, self.image_height_px)

    @property
    def _scale(self) -> Fraction | None:
        across = Fraction(self.image_width_px, self.width_px)
        return across if across == Fraction(self.image_height_px, self.height_px) else None

    @property
    def block_px(self) -> int:
        """Image pixels of one block along either axis."""
        scale = self._scale
        return max(self.image_width_px, self.image_height_px) if scale is None else scale.numerator

    @property
    def block_sensor_px(self) -> int:
        """Sensor pixels of one block along either axis."""
        scale = self._scale
        return max(self.width_px, self.height_px) if scale is None else scale.denominator

    @property
    def whole(self) -> PixelWindow:
        """The whole image at full resolution."""
        return PixelWindow(0, 0, self.image_width_px, self.image_height_px)

    def holds(self, window: PixelWindow) -> bool:
        """True for a full-resolution window inside the image with its edges on whole blocks."""
        b = self.block_px
        return window == self.whole or (
            window.binning == 1
            and all(v % b == 0 for v in (window.x_px, window.y_px, window.width_px, window.height_px))
            and window.x_px + window.width_px <= self.image_width_px
            and window.y_px + window.height_px <= self.image_height_px
        )

    def sensor_pixels(self, window: PixelWindow) -> tuple[int, int, int, int]:
        """The window's first sensor column and row, and its width and height in sensor pixels."""
        if window == self.whole:
            return 0, 0, self.width_px, self.height_px
        b, s = self.block_px, self.block_sensor_px
        return window.x_px // b * s, window.y_px // b * s, window.width_px // b * s, window.height_px // b * s

    def window_covering(self, u0_px: int, v0_px: int, u1_px: int, v1_px: int) -> PixelWindow:
        """The smallest window on whole blocks holding columns ``u0..u1-1`` and rows ``v0..v1-1``, in the image."""
        b = self.block_px
        x0, y0 = max(0, u0_px // b * b), max(0, v0_px // b * b)
        x1 = min(self.image_width_px, -(-u1_px // b) * b)
        y1 = min(self.image_height_px, -(-v1_px // b) * b)
        return PixelWindow(x0, y0, max(1, x1 - x0), max(1, y1 - y0))


@dataclass(frozen=True)
class DepthView:
    """The depth image as the simulated sensor delivers it, and its points in the world.

    ``depth_m`` and ``height_m`` are ``h x w`` at the sensor's resolution (NaN where invalid);
    ``points_world`` is ``h x w x 3``; ``intrinsics`` are scaled to that resolution.
    """

    depth_m: NDArray[np.float64]
    intrinsics: CameraIntrinsics
    points_world: NDArray[np.float64]
    height_m: NDArray[np.float64]


@dataclass(frozen=True)
class _Blob:
    """One connected set of pixels standing above the table."""

    label: int
    pixels: NDArray[np.intp]  # (n, 2) rows, cols
    area_m2: float
    centre_xy_m: tuple[float, float]
    touches_border: bool


def scaled_intrinsics(intrinsics: CameraIntrinsics, width_px: int, height_px: int) -> CameraIntrinsics:
    """The intrinsics of the same camera resampled to ``width_px x height_px`` (pixel-centre convention)."""
    sx, sy = width_px / intrinsics.width_px, height_px / intrinsics.height_px
    return CameraIntrinsics(
        width_px,
        height_px,
        intrinsics.fx_px * sx,
        intrinsics.fy_px * sy,
        (intrinsics.cx_px + 0.5) * sx - 0.5,
        (intrinsics.cy_px + 0.5) * sy - 0.5,
        intrinsics.distortion,
    )


class DepthGraspEstimator:
    """Grasp poses of resting parts from a depth image alone; a substitute for Berscheid et al.

    ``estimate(frame, near_xy_m=None, rng=generator)`` returns a
    :class:`~bt_arrange.perception.detection.Detection` whose ``pose_world`` is the part's
    centre (where a parallel gripper grasps it, pads square to its faces). The estimator keeps
    no state: the random generator for the depth noise is passed in, so runs are reproducible
    from its seed.
    """

    def __init__(self, config: DepthGraspConfig | None = None) -> None:
        self.config = config or DepthGraspConfig()

    # -- sensor ------------------------------------------------------------------------------

    def sensor_grid(self, image: CameraIntrinsics) -> SensorGrid:
        """How the configured sensor's pixels lie on an image of ``image``'s size."""
        width_px, height_px = image.width_px, image.height_px
        if width_px <= self.config.depth_width_px:
            return SensorGrid(width_px, height_px, width_px, height_px)
        small_w = self.config.depth_width_px
        return SensorGrid(width_px, height_px, small_w, max(1, round(height_px * small_w / width_px)))

    def sensor_view(
        self,
        frame: CameraFrame,
        rng: np.random.Generator | None = None,
        *,
        window: PixelWindow | None = None,
        image: CameraIntrinsics | None = None,
    ) -> DepthView:
        """Resample, disturb and back-project ``frame.depth_m`` as the configured sensor would.

        ``frame`` is the full image, or the ``window`` of an image of ``image``'s intrinsics
        (full resolution, its edges on whole blocks of :meth:`SensorGrid.block_px`): then the view
        is that part of the full image's, pixel for pixel, noise included (drawn for the whole
        sensor from ``rng``, as for a full frame, and cut to the window).
        """
        config = self.config
        depth = frame.depth_m
        intrinsics = frame.intrinsics
        if depth is None:
            raise PerceptionError("the frame has no depth image: capture it with camera.capture(with_depth=True)")
        if depth.ndim != 2 or depth.shape != (intrinsics.height_px, intrinsics.width_px):
            raise PerceptionError(
                f"depth image is {depth.shape[1] if depth.ndim == 2 else '?'}x{depth.shape[0]} px but the "
                f"intrinsics say {intrinsics.width_px}x{intrinsics.height_px} px"
            )
        if config.noisy and rng is None:
            raise PerceptionError(
                "depth noise is on: pass rng=np.random.default_rng(seed), or set noise_sigma_m=0 for clean depth"
            )
        grid = self.sensor_grid(intrinsics if image is None else image)
        if window is None:
            window = grid.whole
        elif image is None or not grid.holds(window) or depth.shape != (window.height_px, window.width_px):
            raise PerceptionError(
                f"depth window {window} is not a full-resolution window on whole {grid.block_px} px blocks "
                f"of the image it names ({image})"
            )
        x0, y0, small_w, small_h = grid.sensor_pixels(window)
        raw = np.asarray(depth, dtype=np.float32)
        clean: NDArray[np.float32] = np.where(np.isfinite(raw) & (raw > 0.0), raw, np.nan).astype(np.float32)
        if grid.resamples:
            # Area averaging: a sensor pixel integrates what it sees, so across an edge it reads a
            # depth between the two surfaces (a "flying pixel"). An invalid pixel spoils its cell.
            clean = np.asarray(cv2.resize(clean, (small_w, small_h), interpolation=cv2.INTER_AREA), dtype=np.float32)
            intrinsics = scaled_intrinsics(intrinsics, small_w, small_h)
        measured = clean.astype(np.float64)
        if config.noisy:
            assert rng is not None
            sigma = config.noise_sigma_m * measured / config.noise_reference_depth_m
            noise = rng.standard_normal((grid.height_px, grid.width_px))[y0 : y0 + small_h, x0 : x0 + small_w]
            measured = measured + noise * np.nan_to_num(sigma)
        if config.depth_unit_m > 0.0:
            measured = np.round(measured / config.depth_unit_m) * config.depth_unit_m
        measured[~(measured > 0.0)] = np.nan
        points = _back_project(measured, intrinsics, frame.camera_pose_world)
        return DepthView(measured, intrinsics, points, points[..., 2] - config.table_z_m)

    # -- estimate ----------------------------------------------------------------------------

    def estimate(
        self,
        frame: CameraFrame,
        near_xy_m: tuple[float, float] | None = None,
        rng: np.random.Generator | None = None,
        name: str = "part",
    ) -> Detection:
        """The grasp pose of one part, from the depth image of ``frame`` only.

        ``near_xy_m`` (world metres) picks, among several blobs, the one nearest to it (within
        ``max_hint_distance_m``); without it the largest blob is taken. ``rng`` draws the depth
        noise (required while it is on). ``name`` labels the outcome: the returned
        ``Detection.colour`` holds it, since the estimator sees no colour.
        """
        view = self.sensor_view(frame, rng)
        return self.estimate_view(view, near_xy_m, name)

    def estimate_from(
        self,
        camera: Camera,
        near_xy_m: tuple[float, float] | None = None,
        rng: np.random.Generator | None = None,
        name: str = "part",
    ) -> Detection:
        """:meth:`estimate` of the camera's full frame, rendering only where something stands.

        A binned depth frame of the whole view (``SEARCH_BINNING``, clean) finds every pixel
        standing above the table; one full-resolution window around all of them, its edges on
        whole sensor blocks, is then captured and estimated as the part of the full frame it is
        (:meth:`sensor_view` with the window). The outcome is the full frame's: the same pixels,
        resampling and noise. Nothing standing, a sensor that does not tile the image, or a blob
        running into the window's edge inside the image: the full frame is captured instead.
        The colour detector looks the same way (``bt_arrange.behaviours.looking``); rendering
        the whole 1920 x 1080 frame with depth cost 0.3 s, the two captures a few milliseconds.
        """
        image = camera.intrinsics
        grid = self.sensor_grid(image)
        window = self._window_around_standing(camera, grid) if grid.block_px <= MAX_BLOCK_PX else None
        if window is not None:
            frame = camera.capture(with_depth=True, window=window)
            view = self.sensor_view(frame, rng, window=window, image=image)
            if not self._runs_into_window_edge(view, window, image):
                return self.estimate_view(view, near_xy_m, name)
        return self.estimate(camera.capture(with_depth=True), near_xy_m, rng, name)

    def _window_around_standing(self, camera: Camera, grid: SensorGrid) -> PixelWindow | None:
        image = camera.intrinsics
        search = camera.capture(with_depth=True, window=PixelWindow.full(image, SEARCH_BINNING))
        if search.depth_m is None:
            return None
        depth = np.asarray(search.depth_m, dtype=np.float64)
        depth[~(depth > 0.0)] = np.nan
        heights = _back_project(depth, search.intrinsics, search.camera_pose_world)[..., 2] - self.config.table_z_m
        # Half the blob height: a binned pixel samples one point of its bin, so an edge may hide in it.
        rows, cols = np.nonzero(np.nan_to_num(heights, nan=-1.0) > self.config.min_height_m / 2.0)
        if rows.size == 0:
            return None
        margin_px = SEARCH_MARGIN_BINS * SEARCH_BINNING
        return grid.window_covering(
            int(cols.min()) * SEARCH_BINNING - margin_px,
            int(rows.min()) * SEARCH_BINNING - margin_px,
            (int(cols.max()) + 1) * SEARCH_BINNING + margin_px,
            (int(rows.max()) + 1) * SEARCH_BINNING + margin_px,
        )

    def _runs_into_window_edge(self, view: DepthView, window: PixelWindow, image: CameraIntrinsics) -> bool:
        standing = np.nan_to_num(view.height_m, nan=-1.0) > self.config.min_height_m / 2.0
        edges = (
            (standing[:, 0].any() and window.x_px > 0),
            (standing[0, :].any() and window.y_px > 0),
            (standing[:, -1].any() and window.x_px + window.width_px < image.width_px),
            (standing[-1, :].any() and window.y_px + window.height_px < image.height_px),
        )
        return any(edges)

    def estimate_view(
        self, view: DepthView, near_xy_m: tuple[float, float] | None = None, name: str = "part"
    ) -> Detection:
        """:meth:`estimate` on a prepared :class:`DepthView` (e.g. to estimate several objects from one)."""
        config = self.config
        blobs = self._blobs(view)
        min_area = config.min_area_fraction * config.face_area_m2
        candidates = [blob for blob in blobs if blob.area_m2 >= min_area]
        xy = tuple(blob.centre_xy_m for blob in candidates)

        def outcome(status: DetectionStatus, reason: str, **fields: object) -> Detection:
            return Detection(name, status, f"{SOURCE}: {reason}", candidates_xy_m=xy, **fields)  # type: ignore[arg-type]

        if not candidates:
            return outcome(
                DetectionStatus.NOT_FOUND,
                f"nothing standing {config.min_height_m * 1000:.0f} mm above the table with at least "
                f"{config.min_area_fraction:.0%} of a face's area",
            )
        if near_xy_m is not None:
            hx, hy = float(near_xy_m[0]), float(near_xy_m[1])
            ranked = sorted(candidates, key=lambda b: math.hypot(b.centre_xy_m[0] - hx, b.centre_xy_m[1] - hy))
            distances = [math.hypot(b.centre_xy_m[0] - hx, b.centre_xy_m[1] - hy) for b in ranked]
            if distances[0] > config.max_hint_distance_m:
                return outcome(
                    DetectionStatus.NOT_FOUND,
                    f"{len(candidates)} blob(s), at {_format_xy(xy)} m, none within "
                    f"{config.max_hint_distance_m * 1000:.0f} mm of the hint ({hx:.3f}, {hy:.3f}) m",
                )
            if len(ranked) > 1 and distances[1] - distances[0] < config.hint_margin_m:
                return outcome(
                    DetectionStatus.AMBIGUOUS,
                    f"two blobs about equally near the hint ({hx:.3f}, {hy:.3f}) m: "
                    f"{distances[0] * 1000:.0f} and {distances[1] * 1000:.0f} mm away",
                )
            chosen = ranked[0]
            how = f"the blob nearest the hint ({distances[0] * 1000:.0f} mm away) of {len(candidates)}"
        else:
            chosen = max(candidates, key=lambda b: b.area_m2)
            how = "the only blob" if len(candidates) == 1 else f"the largest of {len(candidates)} blobs (colour-blind)"
        return self._measure(view, chosen, how, outcome)

    # -- stages ------------------------------------------------------------------------------

    def _blobs(self, view: DepthView) -> list[_Blob]:
        config = self.config
        standing = np.nan_to_num(view.height_m, nan=-1.0) > config.min_height_m
        count, labels = cv2.connectedComponents(standing.astype(np.uint8), connectivity=8)
        if count <= 1:
            return []
        height_px, width_px = standing.shape
        rows, cols = np.nonzero(labels)
        order = np.argsort(labels[rows, cols], kind="stable")
        rows, cols = rows[order], cols[order]
        bounds = np.searchsorted(labels[rows, cols], np.arange(1, count + 1))
        intrinsics = view.intrinsics
        blobs = []
        for label in range(1, count):
            r, c = rows[bounds[label - 1] : bounds[label]], cols[bounds[label - 1] : bounds[label]]
            depth = view.depth_m[r, c]
            # Each pixel's footprint on a plane facing the camera at its depth.
            area_m2 = float(np.sum(depth * depth) / (intrinsics.fx_px * intrinsics.fy_px))
            points = view.points_world[r, c]
            touches = bool(r.min() == 0 or c.min() == 0 or r.max() == height_px - 1 or c.max() == width_px - 1)
            centre = (float(points[:, 0].mean()), float(points[:, 1].mean()))
            blobs.append(_Blob(label, np.stack([r, c], axis=1), area_m2, centre, touches))
        return blobs

    def _measure(self, view: DepthView, blob: _Blob, how: str, outcome: Callable[..., Detection]) -> Detection:
        config = self.config
        intrinsics = view.intrinsics
        r, c = blob.pixels[:, 0], blob.pixels[:, 1]
        heights = view.height_m[r, c]
        # Most of a part's blob is its top face; the upper quartile is its height, robust to the
        # sides and to the flying pixels along its edges.
        top_m = float(np.percentile(heights, 75))
        top = heights >= top_m - config.top_band_m
        points = view.points_world[r, c][top]
        depth_top = float(np.median(view.depth_m[r, c][top]))
        expected_px = config.face_area_m2 * intrinsics.fx_px * intrinsics.fy_px / depth_top**2
        faces = blob.area_m2 / config.face_area_m2
        measured = {"area_px": float(len(r)), "expected_area_px": expected_px}
        where = f"{how}, at ({blob.centre_xy_m[0]:.3f}, {blob.centre_xy_m[1]:.3f}) m"
        if blob.touches_border:
            return outcome(DetectionStatus.PARTIAL, f"{where}: cut by the image border", **measured)
        if faces > config.ambiguous_area_fraction:
            return outcome(
                DetectionStatus.AMBIGUOUS, f"{where}: as large as {faces:.1f} faces, touching parts?", **measured
            )
        shape = config.part.shape
        if abs(top_m - config.part_height_m) > config.top_height_tolerance_m:
            return outcome(
                DetectionStatus.PARTIAL,
                f"{where}: its top stands {top_m * 1000:.0f} mm above the table, not "
                f"{config.part_height_m * 1000:.0f} mm: not a {config.part.name} resting on the table (lifted, "
                "stacked)?",
                **measured,
            )
        if len(points) < 5:
            return outcome(DetectionStatus.PARTIAL, f"{where}: only {len(points)} top points", **measured)
        (cx_mm, cy_mm), (w_mm, h_mm), angle_deg = cv2.minAreaRect((points[:, :2] * 1000.0).astype(np.float32))
        sides_m = (w_mm / 1000.0, h_mm / 1000.0)
        edge_m = (sides_m[0] + sides_m[1]) / 2.0
        low, high = config.side_fraction_range
        x_m, y_m = shape.extent_m
        if not (low * min(x_m, y_m) <= min(sides_m) and max(sides_m) <= high * max(x_m, y_m)):
            return outcome(
                DetectionStatus.PARTIAL,
                f"{where}: its top measures {sides_m[0] * 1000:.0f} x {sides_m[1] * 1000:.0f} mm, not "
                f"{shape.describe()}: covered, tipped, or not a {config.part.name}?",
                edge_m=edge_m,
                **measured,
            )
        yaw_rad = math.radians(angle_deg)
        if not shape.square_top and abs(sides_m[0] - y_m) < abs(sides_m[0] - x_m):
            yaw_rad += math.pi / 2  # the rectangle's first side is the part's y edge
        yaw = fold_yaw(yaw_rad, shape.symmetry_rad)
        pose = Pose.from_planar(cx_mm / 1000.0, cy_mm / 1000.0, yaw, config.table_z_m + config.part_height_m / 2.0)
        return outcome(
            DetectionStatus.FOUND,
            f"grasp at x={pose.x_m:.4f} m, y={pose.y_m:.4f} m, yaw={math.degrees(yaw):.2f} deg from {how}",
            pose_world=pose,
            edge_m=edge_m,
            **measured,
        )


def _back_project(depth_m: NDArray[np.float64], intrinsics: CameraIntrinsics, T_W_C: Pose) -> FloatArray:
    """World points (h x w x 3) of a depth image along the optical axis; NaN where the depth is."""
    height_px, width_px = depth_m.shape
    u, v = np.meshgrid(np.arange(width_px, dtype=np.float64), np.arange(height_px, dtype=np.float64))
    if any(abs(k) > 0 for k in intrinsics.distortion):
        pixels = np.stack([u.ravel(), v.ravel()], axis=1).reshape(-1, 1, 2)
        normalised = cv2.undistortPoints(pixels, intrinsics.matrix, np.asarray(intrinsics.distortion, dtype=float))
        xn = normalised[:, 0, 0].reshape(height_px, width_px)
        yn = normalised[:, 0, 1].reshape(height_px, width_px)
    else:
        xn = (u - intrinsics.cx_px) / intrinsics.fx_px
        yn = (v - intrinsics.cy_px) / intrinsics.fy_px
    camera = np.stack([xn * depth_m, yn * depth_m, depth_m], axis=-1)
    return camera @ T_W_C.rotation.T + T_W_C.position_m


def _format_xy(points: tuple[tuple[float, float], ...]) -> str:
    return ", ".join(f"({x:.3f}, {y:.3f})" for x, y in points)
