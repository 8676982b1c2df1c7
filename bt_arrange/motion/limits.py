"""Motion limits: per-joint limits for joint-space motions, and path limits for straight TCP lines.

Both are frozen dataclasses validated on construction: a non-positive value, or one above what
the hardware allows, raises ``OutOfRangeError`` naming the value and the limit, so a typo never
reaches a trajectory generator.

Hardware caps. UR publishes a joint speed limit (about 180 deg/s, written in the URDF as 3.15 rad/s
for the big joints and 3.2 rad/s for the wrists) and a typical TCP speed of 1 m/s, but no
acceleration or jerk limit: the controller limits torque. The acceleration and jerk caps below
are sanity caps, chosen so that a value typed in degrees or millimetres is caught.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from bt_arrange.errors import OutOfRangeError, UnreachableError
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, read_joint_limits

#: Sanity cap on joint accelerations (rad/s^2): UR publishes none; 2 rad/s^2 typed in deg is 115.
MAX_JOINT_ACCELERATION_RAD_S2 = 40.0
#: Sanity cap on joint jerks (rad/s^3): UR publishes none; 10 rad/s^3 typed in deg is 573.
MAX_JOINT_JERK_RAD_S3 = 500.0
#: UR5 datasheet: typical TCP speed 1 m/s.
MAX_TCP_SPEED_M_S = 1.0
#: Sanity cap on TCP accelerations (m/s^2); 0.5 m/s^2 typed in mm is 500.
MAX_TCP_ACCELERATION_M_S2 = 10.0
#: Sanity cap on TCP jerks (m/s^3); 4 m/s^3 typed in mm is 4000.
MAX_TCP_JERK_M_S3 = 500.0

_BUNDLED = read_joint_limits()
#: The bundled UR5's joint speed limits (rad/s, URDF order): what the hardware allows.
HARDWARE_JOINT_VELOCITY_RAD_S: tuple[float, ...] = tuple(_BUNDLED.velocity_rad_s)


def _check_positive_at_most(what: str, value: float, cap: float, unit: str) -> float:
    """Return ``value`` as a float, or raise ``OutOfRangeError`` unless ``0 < value <= cap``."""
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise OutOfRangeError(
            f"{what} {value:g} {unit} must be positive (limit: 0 < value <= {cap:g} {unit})",
            field=what,
            value=value,
            limit=cap,
            unit=unit,
        )
    if value > cap:
        raise OutOfRangeError(
            f"{what} {value:g} {unit} is above the hardware limit {cap:g} {unit}",
            field=what,
            value=value,
            limit=cap,
            unit=unit,
        )
    return value


def _per_joint(what: str, values: float | Sequence[float]) -> tuple[float, ...]:
    """Broadcast a scalar to the six arm joints, or check that a sequence has six entries."""
    if isinstance(values, (int, float)):
        return (float(values),) * len(ARM_JOINT_NAMES)
    result = tuple(float(v) for v in values)
    if len(result) != len(ARM_JOINT_NAMES):
        raise OutOfRangeError(f"{what} has {len(result)} entries, the arm has {len(ARM_JOINT_NAMES)} joints")
    return result


@dataclass(frozen=True)
class JointLimits:
    """Limits of a joint-space motion: kinematic limits per joint plus the joints' position range.

    Each kinematic limit is a scalar (the same for every joint) or six values in URDF order; after
    construction it is always a tuple of six floats.

    Defaults, and why:

    - ``velocity_rad_s = 2.0``: about two thirds of the UR5's 3.14 rad/s. Measured in the
      simulated cell (``benchmarks/throughput.py``): with 1 rad/s, 2 rad/s^2 and 10 rad/s^3 the
      four-cube tree took 11.7 s of world time per cube, with these limits (and the faster lines,
      settling and finger opening of the same change) 5.7 s, and the cubes landed as close to
      their targets.
    - ``acceleration_rad_s2 = 8.0``: reaches 2 rad/s in a quarter of a second; at the UR5's reach
      of 0.85 m that is at most about 7 m/s^2 at the TCP, far below what slides a 5 cm cube held
      with 40 N. A vertical 7.5 cm line at the Cartesian defaults needs up to about 6 rad/s^2.
    - ``jerk_rad_s3 = 100.0``: reaches 8 rad/s^2 in 0.08 s. The same lines need up to about
      65 rad/s^3: with these joint limits they plan once, without a slowdown (with 5 rad/s^2 and
      40 rad/s^3 every line of the four-cube tree was replanned 10 to 20 % slower).
    - ``lower_rad``, ``upper_rad``, ``hardware_velocity_rad_s``: read from the bundled URDF
      (``JointLimits.from_urdf`` reads another one).
    """

    velocity_rad_s: float | tuple[float, ...] = 2.0
    acceleration_rad_s2: float | tuple[float, ...] = 8.0
    jerk_rad_s3: float | tuple[float, ...] = 100.0
    lower_rad: tuple[float, ...] = field(default=_BUNDLED.lower_rad)
    upper_rad: tuple[float, ...] = field(default=_BUNDLED.upper_rad)
    hardware_velocity_rad_s: tuple[float, ...] = field(default=_BUNDLED.velocity_rad_s)

    def __post_init__(self) -> None:
        hardware = _per_joint("hardware_velocity_rad_s", self.hardware_velocity_rad_s)
        lower = _per_joint("lower_rad", self.lower_rad)
        upper = _per_joint("upper_rad", self.upper_rad)
        velocity = _per_joint("velocity_rad_s", self.velocity_rad_s)
        acceleration = _per_joint("acceleration_rad_s2", self.acceleration_rad_s2)
        jerk = _per_joint("jerk_rad_s3", self.jerk_rad_s3)
        for i, name in enumerate(ARM_JOINT_NAMES):
            if not lower[i] < upper[i]:
                raise OutOfRangeError(
                    f"{name}: lower position limit {lower[i]:g} rad is not below the upper limit {upper[i]:g} rad"
                )
            _check_positive_at_most(f"{name} velocity limit", velocity[i], hardware[i], "rad/s")
            _check_positive_at_most(
                f"{name} acceleration limit", acceleration[i], MAX_JOINT_ACCELERATION_RAD_S2, "rad/s^2"
            )
            _check_positive_at_most(f"{name} jerk limit", jerk[i], MAX_JOINT_JERK_RAD_S3, "rad/s^3")
        object.__setattr__(self, "hardware_velocity_rad_s", hardware)
        object.__setattr__(self, "lower_rad", lower)
        object.__setattr__(self, "upper_rad", upper)
        object.__setattr__(self, "velocity_rad_s", velocity)
        object.__setattr__(self, "acceleration_rad_s2", acceleration)
        object.__setattr__(self, "jerk_rad_s3", jerk)

    @classmethod
    def from_urdf(
        cls,
        urdf_path: str | Path,
        velocity_rad_s: float | Sequence[float] = 2.0,
        acceleration_rad_s2: float | Sequence[float] = 8.0,
        jerk_rad_s3: float | Sequence[float] = 100.0,
    ) -> JointLimits:
        """Limits with the position range and hardware speeds of another URDF."""
        urdf = read_joint_limits(urdf_path)
        return cls(
            velocity_rad_s=_per_joint("velocity_rad_s", velocity_rad_s),
            acceleration_rad_s2=_per_joint("acceleration_rad_s2", acceleration_rad_s2),
            jerk_rad_s3=_per_joint("jerk_rad_s3", jerk_rad_s3),
            lower_rad=urdf.lower_rad,
            upper_rad=urdf.upper_rad,
            hardware_velocity_rad_s=urdf.velocity_rad_s,
        )

    def check_positions(self, positions_rad: ArrayLike, what: str = "joint target") -> None:
        """Raise ``UnreachableError`` naming the joint, its value and its range if one is out of range."""
        values = _per_joint(what, np.asarray(positions_rad, dtype=float).reshape(-1).tolist())
        for name, value, lower, upper in zip(ARM_JOINT_NAMES, values, self.lower_rad, self.upper_rad, strict=True):
            if not math.isfinite(value) or not lower <= value <= upper:
                raise UnreachableError(
                    f"{what}: {name} = {value:.4f} rad is outside the joint limits [{lower:.4f}, {upper:.4f}] rad",
                    joint=name,
                    bound=(lower, upper),
                    value=value,
                    unit="rad",
                )


@dataclass(frozen=True)
class CartesianLimits:
    """Limits of a straight TCP line, along the path (the orientation stays constant on a line).

    Defaults (the lines that carry a part: the lift and the lowering), and why:

    - ``velocity_m_s = 0.6``: the lift and the lowering are short (7 to 8 cm); a 7.5 cm line takes
      0.43 s (0.5 s at the former 0.4 m/s). Lines with empty pads run at
      ``ManipulationSettings.free_line_limits`` (1 m/s), a push at ``push_limits`` (0.15 m/s, which
      does not make a 5 cm cube tip, bounce or slide on).
    - ``acceleration_m_s2 = 3.0``: full speed after 0.25 s; a held 5 cm wooden cube (0.1 kg) then
      needs 0.3 N of the pads' 40 N of grip, and no more than the carrying joint moves ask.
    - ``jerk_m_s3 = 30.0``: full acceleration after 0.1 s, which keeps the joint jerks of a
      typical line under the joint default (100 rad/s^3), so a line plans once, without a slowdown.
    """

    velocity_m_s: float = 0.6
    acceleration_m_s2: float = 3.0
    jerk_m_s3: float = 30.0

    def __post_init__(self) -> None:
        for name, value, cap, unit in (
            ("TCP velocity limit", self.velocity_m_s, MAX_TCP_SPEED_M_S, "m/s"),
            ("TCP acceleration limit", self.acceleration_m_s2, MAX_TCP_ACCELERATION_M_S2, "m/s^2"),
            ("TCP jerk limit", self.jerk_m_s3, MAX_TCP_JERK_M_S3, "m/s^3"),
        ):
            _check_positive_at_most(name, value, cap, unit)

    def time_scaled(self, factor: float) -> CartesianLimits:
        """The limits of the same line played ``1/factor`` times slower (``0 < factor <= 1``).

        Slowing a trajectory down in time by ``factor`` scales velocities by ``factor``,
        accelerations by ``factor**2`` and jerks by ``factor**3``: the time-optimal profile
        under the scaled limits is the stretched original, and so are its joint motions.
        """
        if not 0.0 < factor <= 1.0:
            raise OutOfRangeError(f"time scale factor {factor:g} must lie in (0, 1]")
        return CartesianLimits(
            self.velocity_m_s * factor, self.acceleration_m_s2 * factor**2, self.jerk_m_s3 * factor**3
        )
