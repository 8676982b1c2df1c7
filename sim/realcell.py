"""An error model of a real work cell: what a real UR5 + 2F-85 + L515 cell gets wrong.

Every term is a frozen dataclass, off unless ``enabled``; each field says the figure it stands for
and where that figure comes from (a datasheet, the calibration literature, ``FACTS.md``), and calls
an estimate an estimate. Where a figure was *fitted* to the paper's real "after placing" column
(Table 1 b, rows 1 to 3) it says so: docs/experiments.md lists those fits.

Two seeds: ``cell_seed`` is which robot, camera and table this is (the arm's link lengths, the
camera's calibration error, the table's friction: fixed for the cell, the same in every trial);
``run_seed`` is what changes from run to run (joint noise, image noise, the cube's tolerance).

The simulated world is built from the *true* values (a perturbed URDF, the true camera with its
lens and pose), while the robot's software keeps the *nominal* ones: the planner loads the nominal
URDF, and each camera frame reports the nominal intrinsics and pose, as a new real cell's software
has them. ``bt-arrange calibrate`` measures the camera (docs/calibration.md), and a run with
``--calibration`` sees it through what was measured: no camera residual is assumed.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PlanError
from bt_arrange.filelimits import read_limited
from bt_arrange.suggest import did_you_mean

#: Where the hand-eye fit samples the arm's error: the trials' target area and the scatter area.
WORKSPACE_X_M = (0.30, 0.66)
WORKSPACE_Y_M = (-0.28, 0.28)


@dataclass(frozen=True)
class KinematicError:
    """Arm kinematic calibration error: the simulated arm's link lengths and joint zeros are off.

    The simulated arm loads a perturbed URDF (each of the six joint origins' translations longer or
    shorter by a draw of ``link_length_sigma_mm``, each joint's zero turned by a draw of
    ``joint_offset_sigma_mrad``); the planner keeps the nominal URDF, so the TCP lands millimetres
    off in a way that varies over the workspace. Figures: Universal Robots writes that two
    uncalibrated cobots can differ in length by "multiple millimeters" (universal-robots.com,
    "Kinematic Robot Calibration"); uncalibrated 6-DoF arms are reported at 1 to 15 mm mean
    position error (robot-calibration literature, e.g. the SCALAR paper). 1 mm and 1 mrad are an
    estimate in that range.

    ``hand_eye_absorbs_mean``: the camera-to-robot (hand-eye) calibration of a real cell is made
    with this arm, so it absorbs the arm's *mean* error over the workspace (a rigid fit in x, y, z
    and yaw); what remains is the error's *variation* over the workspace. The cell mounts the
    simulated arm where that fit puts it.
    """

    enabled: bool = False
    link_length_sigma_mm: float = 0.0
    joint_offset_sigma_mrad: float = 0.0
    hand_eye_absorbs_mean: bool = True


@dataclass(frozen=True)
class JointRepeatability:
    """Joint tracking and repeatability: each motion ends a little off where it was sent.

    A fresh joint error of ``joint_sigma_mrad`` per joint is drawn whenever the arm comes to rest
    at a new setpoint (the encoders read the setpoint; the arm stands off it). 0.04 mrad per joint
    gives a TCP standard deviation of about 0.03 mm, so ±0.1 mm is three sigma: the UR5's
    datasheet repeatability of ±0.1 mm.
    """

    enabled: bool = False
    joint_sigma_mrad: float = 0.0


@dataclass(frozen=True)
class CameraCalibrationError:
    """The true camera: its lens, and where it really sits; what a calibration must find.

    The image is rendered from the *true* camera (``SimCamera``): the pinhole of the true focal
    lengths and principal point, then warped by the true lens distortion (OpenCV's model,
    ``k1 k2 p1 p2``), seen from the true pose. Frames report the *nominal* camera (the datasheet's
    field of view, the centred principal point, no distortion, the drawing's pose), as a new cell's
    software would have it before calibration; ``bt-arrange calibrate`` finds the true one, and a run
    with ``--calibration`` uses what it found. No residual is assumed: the camera error a run sees is
    what the calibration left (docs/calibration.md).

    - ``focal_sigma_percent``: the true fx, fy off the nominal by a draw of this (1 %: a lens's focal
      length tolerance and the sensor's pixel pitch; estimate);
    - ``principal_point_sigma_px``: the true cx, cy off the image centre by this (8 px: the lens
      centred on the sensor within about 25 um; estimate);
    - ``k1``, ``k2``, ``p1``, ``p2``: the lens's distortion, fixed (not drawn): k1 = -0.12 lies in the
      -0.1 to -0.3 that FACTS.md gives for a 6-8 mm machine-vision lens, k2 = +0.06 the usual
      partial compensation, tangential 8e-4 and -5e-4 a slightly decentred element (estimates). On
      this 70-degree camera that is 4 px of displacement where the cubes lie (0.25 of the image
      radius) and about 65 px in the image corners (FACTS.md's "a few pixels" cannot hold at this
      field of view with that k1);
    - ``position_sigma_mm``, ``rotation_sigma_deg``: the camera's true pose off the drawing's by a
      draw of 15 mm per axis and 1 degree per axis (a bracket set by hand; estimate), so an
      uncalibrated camera puts a cube centimetres off.
    """

    enabled: bool = False
    focal_sigma_percent: float = 0.0
    principal_point_sigma_px: float = 0.0
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    position_sigma_mm: float = 0.0
    rotation_sigma_deg: float = 0.0


@dataclass(frozen=True)
class ImagingError:
    """Exposure, sensor noise and lighting that change from frame to frame.

    ``sensor_sigma`` grey levels of Gaussian noise (2 of 255: an L515 RGB frame under a ring light;
    estimate), ``exposure_jitter`` a uniform gain change of ±5 % per frame (auto exposure;
    estimate), ``blur_sigma_px`` a slight defocus (0.5 px; estimate), ``light_jitter_deg`` the
    light's direction turned by up to this per frame (people and daylight around the ring light;
    estimate).
    """

    enabled: bool = False
    sensor_sigma: float = 0.0
    exposure_jitter: float = 0.0
    blur_sigma_px: float = 0.0
    light_jitter_deg: float = 0.0


@dataclass(frozen=True)
class GripperError:
    """Gripper finger asymmetry and pad compliance.

    - ``finger_offset_sigma_mm``: the two pads' centre stands off the TCP along the closing axis
      (one finger mounted or worn thicker: "a fraction of a millimetre is plausible", FACTS.md,
      estimate); the planner's TCP stays in the middle.
    - ``grasp_offset_sigma_mm``: each grasp, the pads settle off the TCP along the closing axis by a
      fresh draw (run seed) of this standard deviation: the one finger that meets the cube first
      pushes it across the table until the other arrives, and the gear constraint holds the fingers
      that far off the centre (``relativePositionTarget``) until the next grasp, so the cube is
      carried and set down that far off. It stands for the linkage's play, the silicone pads'
      uneven give and the cube settling in the pads: the part of the real cell's placement error
      no datasheet figure explains. FITTED to the paper's real after-placing column
      (docs/experiments.md); no figure for it is published.
    - ``coupling_erp``: how stiffly the two fingers are kept on that (the gear constraint's error
      reduction). 0.8, the ideal cell's, is stiff: softer couplings (0.03 in an earlier fit) let
      the carried cube go in a few trials of ten, which the paper does not report.
    - ``pad_stiffness_n_m``, ``pad_damping_n_s_m``: the silicone pads' contact stiffness and damping
      (0: pybullet's rigid contact). 1e5 N/m lets a 40 N grip sink 0.4 mm into a pad (estimate;
      3000 N/m, 13 mm, lost every cube).
    """

    enabled: bool = False
    finger_offset_sigma_mm: float = 0.0
    grasp_offset_sigma_mm: float = 0.0
    coupling_erp: float = 0.8
    pad_stiffness_n_m: float = 0.0
    pad_damping_n_s_m: float = 0.0


@dataclass(frozen=True)
class ObjectTolerance:
    """Cube size tolerance: each cube's edge is off by a draw of ``edge_sigma_mm``.

    Wooden or 3D-printed cubes hold ±0.1 to 0.3 mm on the edge (FACTS.md, estimate); the perception
    assumes 50 mm. Rounded edges (0.5 to 1 mm, estimate) are not modelled: a primitive box has sharp
    edges, and a rounding that is the same on all four sides shrinks the coloured face about its
    centre without moving the centre.
    """

    enabled: bool = False
    edge_sigma_mm: float = 0.0


@dataclass(frozen=True)
class FrictionField:
    """Friction that varies over the table: ``1 + spread * f(x, y)`` times the nominal cube-table friction.

    ``f`` is a smooth field in -1..1 (two sines of ``wavelength_m`` with phases from the cell seed);
    ±20 % over a worn table top is an estimate. Applied to a cube wherever it lies, each control
    period (pybullet keeps a contact's friction while it lasts, so it takes effect where a cube is
    set down).
    """

    enabled: bool = False
    spread: float = 0.0
    wavelength_m: float = 0.3


#: Fields that may be negative (the lens's distortion coefficients).
_SIGNED = {"k1", "k2", "p1", "p2"}

_TERMS: dict[str, type] = {
    "kinematics": KinematicError,
    "joints": JointRepeatability,
    "camera": CameraCalibrationError,
    "imaging": ImagingError,
    "gripper": GripperError,
    "objects": ObjectTolerance,
    "friction": FrictionField,
}


@dataclass(frozen=True)
class RealCellErrors:
    """All the error terms of a real cell, each switchable, with the cell's two seeds."""

    cell_seed: int = 0
    run_seed: int = 0
    kinematics: KinematicError = field(default_factory=KinematicError)
    joints: JointRepeatability = field(default_factory=JointRepeatability)
    camera: CameraCalibrationError = field(default_factory=CameraCalibrationError)
    imaging: ImagingError = field(default_factory=ImagingError)
    gripper: GripperError = field(default_factory=GripperError)
    objects: ObjectTolerance = field(default_factory=ObjectTolerance)
    friction: FrictionField = field(default_factory=FrictionField)

    @property
    def enabled(self) -> bool:
        """True when any term is on."""
        return any(getattr(self, name).enabled for name in _TERMS)

    def with_run_seed(self, run_seed: int) -> RealCellErrors:
        """The same cell, another run."""
        return dataclasses.replace(self, run_seed=int(run_seed))

    def rng(self, term: str, per_run: bool) -> np.random.Generator:
        """The random stream of one term: from the cell seed (fixed draws) or the run seed."""
        index = list(_TERMS).index(term)
        return np.random.default_rng([self.cell_seed, index, self.run_seed if per_run else 2**31 - 1, int(per_run)])

    # -- draws -------------------------------------------------------------------------------

    def arm_draw(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(link length errors in m, joint zero errors in rad), one per arm joint; fixed for the cell."""
        k = self.kinematics
        if not k.enabled:
            return np.zeros(6), np.zeros(6)
        rng = self.rng("kinematics", per_run=False)
        return rng.normal(0.0, k.link_length_sigma_mm / 1000, 6), rng.normal(0.0, k.joint_offset_sigma_mrad / 1000, 6)

    def finger_offset_m(self) -> float:
        """Where the pads' centre stands off the TCP along the closing axis; fixed for the cell."""
        g = self.gripper
        if not g.enabled:
            return 0.0
        return float(self.rng("gripper", per_run=False).normal(0.0, g.finger_offset_sigma_mm / 1000))

    def grasp_offset_rng(self) -> np.random.Generator | None:
        """The stream of per-grasp offsets (run seed), or None when the term is off."""
        g = self.gripper
        if not g.enabled or g.grasp_offset_sigma_mm <= 0:
            return None
        return np.random.default_rng([self.cell_seed, list(_TERMS).index("gripper"), self.run_seed, 2])

    def cube_edge_error_m(self) -> float:
        """The edge error of the first cube a run puts on the table (the cell draws the next ones on)."""
        o = self.objects
        if not o.enabled:
            return 0.0
        return float(self.rng("objects", per_run=True).normal(0.0, o.edge_sigma_mm / 1000))

    def camera_draw(self) -> dict[str, float]:
        """The true camera's deviation from the nominal one and its lens; fixed for the cell.

        ``dfx``, ``dfy`` relative focal errors, ``dcx``, ``dcy`` principal point (px), ``k1 k2 p1 p2``
        the lens, ``dx dy dz`` (m) and ``rx ry rz`` (rad, about the optical frame's axes) the pose.
        """
        c = self.camera
        if not c.enabled:
            return {"dfx": 0.0, "dfy": 0.0, "dcx": 0.0, "dcy": 0.0, "k1": 0.0, "k2": 0.0, "p1": 0.0, "p2": 0.0,
                    "dx": 0.0, "dy": 0.0, "dz": 0.0, "rx": 0.0, "ry": 0.0, "rz": 0.0}  # fmt: skip
        rng = self.rng("camera", per_run=False)
        f = rng.normal(0.0, c.focal_sigma_percent / 100, 2)
        pp = rng.normal(0.0, c.principal_point_sigma_px, 2)
        pos = rng.normal(0.0, c.position_sigma_mm / 1000, 3)
        rot = rng.normal(0.0, math.radians(c.rotation_sigma_deg), 3)
        return {"dfx": float(f[0]), "dfy": float(f[1]), "dcx": float(pp[0]), "dcy": float(pp[1]),
                "k1": float(c.k1), "k2": float(c.k2), "p1": float(c.p1), "p2": float(c.p2),
                "dx": float(pos[0]), "dy": float(pos[1]), "dz": float(pos[2]),
                "rx": float(rot[0]), "ry": float(rot[1]), "rz": float(rot[2])}  # fmt: skip

    def friction_phases(self) -> tuple[float, float]:
        """The friction field's two phases; fixed for the cell (it is the table)."""
        rng = self.rng("friction", per_run=False)
        return float(rng.uniform(0, 2 * math.pi)), float(rng.uniform(0, 2 * math.pi))

    def friction_scale(self, x_m: float, y_m: float) -> float:
        """Factor on the nominal cube-table friction at (x, y)."""
        f = self.friction
        if not f.enabled:
            return 1.0
        px, py = self.friction_phases()
        k = 2 * math.pi / f.wavelength_m
        return 1.0 + f.spread * 0.5 * (math.sin(k * x_m + px) + math.sin(k * y_m + py))


# -- presets -----------------------------------------------------------------------------------

#: The fitted grasp offset of the real cell (GripperError.grasp_offset_sigma_mm; docs/experiments.md).
GRASP_OFFSET_SIGMA_MM = 3.5


def ideal() -> RealCellErrors:
    """Today's simulated cell: no error term on."""
    return RealCellErrors()


def real(cell_seed: int = 0) -> RealCellErrors:
    """The paper's real cell, as far as public figures and the fit to its Table 1 b go (see each term)."""
    return RealCellErrors(
        cell_seed=cell_seed,
        kinematics=KinematicError(True, link_length_sigma_mm=1.0, joint_offset_sigma_mrad=1.0),
        joints=JointRepeatability(True, joint_sigma_mrad=0.04),
        camera=REAL_CAMERA,
        imaging=ImagingError(True, sensor_sigma=2.0, exposure_jitter=0.05, blur_sigma_px=0.5, light_jitter_deg=10.0),
        gripper=REAL_GRIPPER,
        objects=ObjectTolerance(True, edge_sigma_mm=0.1),
        friction=FrictionField(True, spread=0.2, wavelength_m=0.3),
    )


#: The real cell's true camera (``CameraCalibrationError``): a lens and a pose that only a calibration finds.
REAL_CAMERA = CameraCalibrationError(
    True,
    focal_sigma_percent=1.0,
    principal_point_sigma_px=8.0,
    k1=-0.12,
    k2=0.06,
    p1=8e-4,
    p2=-5e-4,
    position_sigma_mm=15.0,
    rotation_sigma_deg=1.0,
)

#: The real cell's gripper; ``grasp_offset_sigma_mm`` is the fitted figure (docs/experiments.md).
REAL_GRIPPER = GripperError(
    True,
    finger_offset_sigma_mm=0.3,
    grasp_offset_sigma_mm=GRASP_OFFSET_SIGMA_MM,
    coupling_erp=0.8,
    pad_stiffness_n_m=1.0e5,
    pad_damping_n_s_m=500.0,
)

PRESETS = {"ideal": ideal, "real": real}


# -- the user's own values: TOML ---------------------------------------------------------------


def _toml_module() -> Any:
    if sys.version_info >= (3, 11):
        import tomllib

        return tomllib
    import tomli  # the tomli backport on 3.10 (a dependency there)

    return tomli


def from_mapping(data: Mapping[str, Any], where: str = "cell file") -> RealCellErrors:
    """Errors from a mapping like the TOML file's: ``preset`` to start from, seeds, one table per term.

    A ``PlanError`` names an unknown key or a bad value.
    """
    known_top = {"preset", "cell_seed", "run_seed", *_TERMS}
    for key in data:
        if key not in known_top:
            raise PlanError(
                f"{where}: unknown key {key!r}{did_you_mean(key, known_top)}; "
                f"the keys are {', '.join(sorted(known_top))}"
            )
    preset = data.get("preset", "ideal")
    if not isinstance(preset, str) or preset not in PRESETS:
        raise PlanError(f"{where}: preset {preset!r} is not one of {', '.join(PRESETS)}{did_you_mean(preset, PRESETS)}")
    errors = PRESETS[preset]()
    changes: dict[str, Any] = {}
    for key in ("cell_seed", "run_seed"):
        if key in data:
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise PlanError(f"{where}: {key} = {value!r} must be a whole number, 0 or more")
            changes[key] = value
    for term, cls in _TERMS.items():
        if term not in data:
            continue
        table = data[term]
        if not isinstance(table, Mapping):
            raise PlanError(f"{where}: [{term}] must be a table of values, got {table!r}")
        current = getattr(errors, term)
        names = {f.name: f for f in fields(cls)}
        values: dict[str, Any] = {}
        for key, value in table.items():
            if key not in names:
                raise PlanError(
                    f"{where}: unknown key {term}.{key}{did_you_mean(key, names)}; [{term}] takes {', '.join(names)}"
                )
            default = getattr(current, key)
            if isinstance(default, bool):
                if not isinstance(value, bool):
                    raise PlanError(f"{where}: {term}.{key} = {value!r} must be true or false")
            else:
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                    raise PlanError(f"{where}: {term}.{key} = {value!r} must be a finite number")
                if value < 0 and key not in _SIGNED:
                    raise PlanError(f"{where}: {term}.{key} = {value!r} must not be negative")
                value = float(value)
            values[key] = value
        if term == "gripper" and not 0.0 < values.get("coupling_erp", current.coupling_erp) <= 1.0:
            raise PlanError(f"{where}: gripper.coupling_erp must lie in (0, 1]")
        changes[term] = dataclasses.replace(current, **values)
    return dataclasses.replace(errors, **changes)


def load_toml(path: Path | str) -> RealCellErrors:
    """Errors from a TOML file; a ``PlanError`` for a missing, unreadable or malformed one."""
    path = Path(path)
    try:
        text = read_limited(path, "cell file", PlanError)
    except FileNotFoundError as error:
        raise PlanError(f"cannot read cell file {path}: {error.strerror or error}") from error
    try:
        data = _toml_module().loads(text)
    except RecursionError:
        raise PlanError(f"cell file {path} is not TOML a cell file can hold: it nests too deep") from None
    except Exception as error:  # tomllib.TOMLDecodeError; one line, whatever the parser says
        raise PlanError(f"cell file {path} is not valid TOML: {error}") from error
    return from_mapping(data, where=f"cell file {path}")


def parse_cell(text: str) -> RealCellErrors:
    """``ideal``, ``real`` or a path to a ``.toml`` file; a ``PlanError`` otherwise."""
    name = text.strip()
    if name in PRESETS:
        return PRESETS[name]()
    if name.endswith(".toml"):
        return load_toml(name)
    raise PlanError(
        f"unknown cell {name!r}{did_you_mean(name, PRESETS)}: choose {' or '.join(PRESETS)}, or give a .toml file"
    )


def parse_cells(text: str) -> list[tuple[str, RealCellErrors]]:
    """A comma-separated list of cells (``ideal,real``): (name, errors) each, checked."""
    names = [part.strip() for part in text.split(",") if part.strip()]
    if not names:
        raise PlanError(f"--cell is empty; choose from {', '.join(PRESETS)}, or give a .toml file")
    return [(name, parse_cell(name)) for name in names]
