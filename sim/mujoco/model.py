"""The MuJoCo model of the work cell: the bundled URDF compiled by MuJoCo, and what a URDF cannot say.

The robot is ``bt_arrange/descriptions/ur5_2f85.urdf`` itself, the file the planner reads, parsed
by MuJoCo's own URDF compiler into an ``MjSpec`` (no hand-written MJCF twin that could drift from
it: the kinematics, masses, inertias, joint limits and collision shapes are the file's). What a
URDF has no words for is added to that ``MjSpec`` in Python, before it is compiled: editing the
spec keeps one source of truth and lets the parts of each run be added as bodies with their own
meshes, pairs and exclusions, which text substitution into an MJCF file could not do safely.

Added to the spec:

- the options: the pybullet cell's time step (2 ms, four steps per 8 ms control period), gravity,
  the ``implicitfast`` integrator (the servos' damping is integrated implicitly), the friction
  cone, no-slip iterations (``MujocoPhysics``);
- the arm's six position servos (``general`` actuators: ``kp (q_ref - q) + kv (qd_ref - qd)``,
  the setpoint advanced along its velocity at every physics step), the drives' reflected inertia
  as joint ``armature`` and the controller's gravity compensation (``gravcomp`` on every robot
  body). They are not clamped at the URDF's efforts: MuJoCo integrates a clamped actuator's
  damping explicitly, which a stiff servo does not survive at 2 ms; the peak torques of a
  four-cube run are 28, 17, 9, 1.7, 1.1 and 0.5 N m, far below the URDF's 150 and 28
  (``docs/mujoco.md``);
- the fingers' two force-limited velocity servos, and the 2F-85's linkage as an ``<equality
  joint>`` (left = right, the gear constraint of the pybullet cell);
- the table, the parts (a box, or a prism's convex pieces as mesh hulls, each with its visual
  sides and a thin painted top plate), the top camera and its light.

Friction: Bullet multiplies two bodies' coefficients; MuJoCo takes the larger (or the one of
higher ``priority``). The pybullet cell's table, links and parts are 0.5 and its pads 1.2, so
every contact's coefficient here is the product Bullet uses: geoms carry ``0.5 x`` their Bullet
coefficient (parts at priority 1, so a part's own ``lateral_friction`` decides its contacts with
the table and the links), and each finger geom meets each part through an explicit ``<pair>``
of ``pad x part`` (the dynamic contacts between finger and part bodies are excluded). Two parts
meet through explicit pairs too, with their own ``solref`` (``MujocoPhysics.part_solref_time_constant_s``:
a part landing on another) and otherwise what MuJoCo's dynamic contact between them has.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bt_arrange.geometry import Pose
from bt_arrange.motion.urdf import ARM_JOINT_NAMES, FINGER_JOINT_NAMES, TCP_FRAME, default_urdf_path
from bt_arrange.objects import DEFAULT_PART_FRICTION, ObjectType
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.parts import SIDE_RGB, TABLE_RGB, TOP_PLATE_M, mass_of

#: Contact groups: robot geoms touch the world's (table, parts) but not each other, as in the
#: pybullet cell (loaded without self-collision); parts and the table touch everything.
ROBOT_CONTYPE, ROBOT_CONAFFINITY = 2, 1
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 3
#: Geom groups: collision shapes of parts are hidden (group 3), their visuals drawn (group 1).
VISUAL_GROUP, HIDDEN_GROUP = 1, 3
#: Bullet's coefficient of the table, the links and a default part: the common factor of every product.
BULLET_BASE_FRICTION = DEFAULT_PART_FRICTION
FINGER_BODIES = ("left_finger", "right_finger")
TABLE_THICKNESS_M = 0.04
#: A contact between two parts has ``solref``'s time constant this many time steps (``MujocoPhysics``).
PART_CONTACT_TIME_STEPS = 4.0


@dataclass(frozen=True)
class MujocoPhysics:
    """MuJoCo's own settings: the contact model and the servos. Every figure says where it comes from.

    ``solref`` is (time constant, damping ratio): the time constant is twice the time step, the
    stiffest MuJoCo's documentation recommends for a step (wood, steel and aluminium are rigid at
    this scale; the pybullet cell's contacts are rigid too), critically damped (restitution 0 in
    the pybullet cell). ``solimp`` is MuJoCo's default. The cone is elliptic: the pyramid's
    friction depends on the push's direction against the world axes (FACTS.md), an elliptic cone
    does not. No-slip iterations remove the creep of MuJoCo's soft friction under a steady load,
    which a sticking real contact has not (the pybullet cell pins sticking contacts with friction
    anchors for the same reason). ``friction_scale`` and ``solref_scale`` exist for the
    sensitivity study (``docs/mujoco.md``) and are 1 otherwise.
    """

    cone: str = "elliptic"
    impratio: float = 1.0
    noslip_iterations: int = 10
    solver_iterations: int = 100
    #: None: twice the time step.
    solref_time_constant_s: float | None = None
    #: ``solref``'s time constant of a contact between two parts (a part landing on another, parts
    #: side by side). None: four time steps. At two a contact arrests an approach within one step:
    #: a face landing tilted by a few hundredths of a degree touches first at one vertex, which takes
    #: the fall's whole impulse alone and spins both parts, and the lower one slides 0.1 mm on its
    #: support (``docs/mujoco.md``). The pads and the table keep the stiffer contact.
    part_solref_time_constant_s: float | None = None
    solref_damping_ratio: float = 1.0
    solimp: tuple[float, float, float, float, float] = (0.9, 0.95, 0.001, 0.5, 2.0)
    friction_scale: float = 1.0
    solref_scale: float = 1.0
    #: Reflected rotor inertia of the UR5's drives (kg m2; 101:1 harmonic drives, an estimate): it
    #: is what lets a stiff servo run at 2 ms, as it lets the real joints'.
    arm_armature_kg_m2: tuple[float, ...] = (0.4, 0.4, 0.4, 0.1, 0.1, 0.1)
    #: Bandwidth of the joint servos (Hz) and their damping ratio; gains follow from each joint's
    #: inertia at the home pose. Setpoints come every 8 ms (125 Hz).
    servo_bandwidth_hz: float = 20.0
    servo_damping_ratio: float = 1.0
    #: The 2F-85's motor and linkage felt at each finger (kg; an estimate).
    finger_armature_kg: float = 0.05
    #: Opening: the position loop's gain (1/s) before the speed limit.
    finger_position_gain_1_s: float = 50.0

    def time_constant_s(self, time_step_s: float) -> float:
        """``solref``'s time constant for a time step (scaled by ``solref_scale``)."""
        base = self.solref_time_constant_s if self.solref_time_constant_s is not None else 2.0 * time_step_s
        return base * self.solref_scale

    def part_time_constant_s(self, time_step_s: float) -> float:
        """``solref``'s time constant of a part-on-part contact for a time step (scaled by ``solref_scale``)."""
        base = self.part_solref_time_constant_s
        return (base if base is not None else PART_CONTACT_TIME_STEPS * time_step_s) * self.solref_scale


@dataclass(frozen=True)
class PartSpec:
    """One part to build: its name, type (as built: a real cell's edge error included), paint and pose."""

    name: str
    object_type: ObjectType
    rgb: tuple[float, float, float]
    pose: Pose
    friction: float = field(default=BULLET_BASE_FRICTION)


def _quat_wxyz(pose: Pose) -> list[float]:
    x, y, z, w = (float(v) for v in pose.quaternion_xyzw)
    return [w, x, y, z]


def camera_quat_wxyz(pose_cv: Pose) -> list[float]:
    """MuJoCo's camera orientation for an OpenCV optical-frame pose: MuJoCo looks down -z, y up."""
    rotation = pose_cv.rotation @ np.diag([1.0, -1.0, -1.0])
    return _quat_wxyz(Pose.from_rotation(pose_cv.position_m, rotation))


def build_spec(config: CellConfig, physics: MujocoPhysics, parts: Sequence[PartSpec] = ()):  # noqa: ANN201
    """The cell's ``MjSpec`` (not yet compiled) with ``parts`` on the table."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(default_urdf_path()))
    spec.compiler.fusestatic = False  # keep tool0 and tcp as bodies: tcp is the TCP frame
    spec.compiler.discardvisual = False  # the URDF's colours (its visuals equal its collisions)
    spec.modelname = "bt_arrange_cell"
    _options(spec, config, physics)
    _robot(spec, config, physics)
    name_finger_geoms(spec)
    _table(spec, config, physics)
    pad = config.physics.pad_contact.lateral_friction
    geoms = {part.name: _part(spec, part, physics, config.physics.time_step_s, pad) for part in parts}
    _part_pairs(spec, parts, geoms, physics, config.physics.time_step_s)
    _camera_and_light(spec, config)
    return spec


def _solref(physics: MujocoPhysics, time_step_s: float) -> list[float]:
    return [physics.time_constant_s(time_step_s), physics.solref_damping_ratio]


def _options(spec, config: CellConfig, physics: MujocoPhysics) -> None:  # noqa: ANN001
    import mujoco

    option = spec.option
    option.timestep = config.physics.time_step_s
    option.gravity = [0.0, 0.0, -config.physics.gravity_m_s2]
    option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC if physics.cone == "elliptic" else mujoco.mjtCone.mjCONE_PYRAMIDAL
    option.impratio = physics.impratio
    option.noslip_iterations = physics.noslip_iterations
    option.iterations = physics.solver_iterations
    width, height = config.camera.width_px, config.camera.height_px
    spec.visual.global_.offwidth = max(width, 640)
    spec.visual.global_.offheight = max(height, 480)
    spec.visual.quality.shadowsize = 0


def _robot(spec, config: CellConfig, physics: MujocoPhysics) -> None:  # noqa: ANN001
    import mujoco

    step = config.physics.time_step_s
    friction = physics.friction_scale * BULLET_BASE_FRICTION * BULLET_BASE_FRICTION
    for body in spec.bodies:
        if body.name == "world":
            continue
        body.gravcomp = 1.0
        for geom in body.geoms:
            geom.contype, geom.conaffinity = ROBOT_CONTYPE, ROBOT_CONAFFINITY
            geom.friction = [friction, 0.0, 0.0]
            geom.condim = 3
            geom.solref = _solref(physics, step)
            geom.solimp = list(physics.solimp)
    joints = {joint.name: joint for joint in spec.joints}
    for name, armature in zip(ARM_JOINT_NAMES, physics.arm_armature_kg_m2, strict=True):
        joints[name].armature = armature
    for name in FINGER_JOINT_NAMES:
        joints[name].armature = physics.finger_armature_kg
    for name in ARM_JOINT_NAMES:
        # Gains are set once the model is compiled (they depend on each joint's inertia).
        actuator = spec.add_actuator(name=f"{name}_servo", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    for name in FINGER_JOINT_NAMES:
        # A velocity servo whose gain is set with each command (``devices.MujocoGripper``) so that a
        # blocked finger presses with the commanded force: no clamp (MuJoCo integrates a clamped
        # actuator's damping explicitly, and a stiff one went unstable at 2 ms, measured).
        actuator = spec.add_actuator(name=f"{name}_servo", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        kv = config.physics.finger_open_force_n / (config.physics.gripper_open_speed_m_s / 2)
        actuator.gainprm = [kv] + [0.0] * 9
        actuator.biasprm = [0.0, 0.0, -kv] + [0.0] * 7
    # The linkage: left = right (each joint is its pad's distance from the centre); a grasp offset
    # (a real cell's) is data[0] = left - right.
    coupling = spec.add_equality(
        name="finger_coupling",
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1=FINGER_JOINT_NAMES[0],
        name2=FINGER_JOINT_NAMES[1],
    )
    coupling.data = [0.0, 1.0, 0.0, 0.0, 0.0] + [0.0] * (len(coupling.data) - 5)
    coupling.solref = [2.0 * step, 1.0]
    tcp = next(body for body in spec.bodies if body.name == TCP_FRAME)
    tcp.add_site(name="tcp", size=[0.002, 0.0, 0.0], group=HIDDEN_GROUP)


def urdf_efforts() -> dict[str, float]:
    """The joints' effort limits as the URDF states them (N m; N for the fingers)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(default_urdf_path()).getroot()
    efforts = {}
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if limit is not None and "effort" in limit.attrib:
            efforts[joint.attrib["name"]] = float(limit.attrib["effort"])
    return efforts


def finish_model(model, config: CellConfig, physics: MujocoPhysics, home_q: Sequence[float]) -> None:  # noqa: ANN001
    """What only a compiled model knows: the clipping planes (in units of its extent) and the servo gains."""
    extent = float(model.stat.extent)
    model.vis.map.znear = config.camera.near_m / extent
    model.vis.map.zfar = config.camera.far_m / extent
    set_arm_gains(model, physics, home_q)


def set_arm_gains(model, physics: MujocoPhysics, home_q: Sequence[float]) -> None:  # noqa: ANN001
    """The arm servos' gains from each joint's inertia at ``home_q`` (armature included)."""
    import mujoco

    data = mujoco.MjData(model)
    for k, name in enumerate(ARM_JOINT_NAMES):
        data.qpos[model.joint(name).qposadr[0]] = home_q[k]
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    omega = 2.0 * math.pi * physics.servo_bandwidth_hz
    for name in ARM_JOINT_NAMES:
        dof = model.joint(name).dofadr[0]
        inertia = full[dof, dof]
        kp = inertia * omega**2
        kv = 2.0 * physics.servo_damping_ratio * omega * inertia
        actuator = model.actuator(f"{name}_servo").id
        model.actuator_gainprm[actuator, 0] = kp
        model.actuator_biasprm[actuator, :3] = [0.0, -kp, -kv]


def _table(spec, config: CellConfig, physics: MujocoPhysics) -> None:  # noqa: ANN001
    import mujoco

    length, width = config.table_size_m
    cx, cy = config.table_centre_xy_m
    spec.worldbody.add_geom(
        name="table",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[length / 2, width / 2, TABLE_THICKNESS_M / 2],
        pos=[cx, cy, -TABLE_THICKNESS_M / 2],
        rgba=[*TABLE_RGB, 1.0],
        contype=WORLD_CONTYPE,
        conaffinity=WORLD_CONAFFINITY,
        friction=[physics.friction_scale * BULLET_BASE_FRICTION * BULLET_BASE_FRICTION, 0.0, 0.0],
        condim=3,
        solref=_solref(physics, config.physics.time_step_s),
        solimp=list(physics.solimp),
    )


def pad_friction(part_friction: float, pad_lateral_friction: float, physics: MujocoPhysics) -> float:
    """The coefficient of a finger-part contact: Bullet's product of the pad's and the part's."""
    return physics.friction_scale * pad_lateral_friction * part_friction


def _part(spec, part: PartSpec, physics: MujocoPhysics, time_step_s: float, pad_lateral: float) -> list:  # noqa: ANN001
    import mujoco

    shape = part.object_type.shape
    body = spec.worldbody.add_body(name=part.name, pos=list(part.pose.position_m), quat=_quat_wxyz(part.pose))
    body.add_freejoint(name=f"{part.name}_free")
    mass = mass_of(part.object_type)
    common = {
        "contype": WORLD_CONTYPE,
        "conaffinity": WORLD_CONAFFINITY,
        "group": HIDDEN_GROUP,
        "priority": 1,
        "friction": [physics.friction_scale * BULLET_BASE_FRICTION * part.friction, 0.0, 0.0],
        "condim": 3,
        "solref": _solref(physics, time_step_s),
        "solimp": list(physics.solimp),
    }
    visual = {"contype": 0, "conaffinity": 0, "group": VISUAL_GROUP, "density": 0.0}
    collision_geoms = []
    if shape.rectangular:
        hx, hy, hz = (v / 2 for v in shape.size_m)
        collision_geoms.append(
            body.add_geom(
                name=f"{part.name}_box", type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, hz], mass=mass, **common
            )
        )
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, hz - TOP_PLATE_M / 2], pos=[0, 0, -TOP_PLATE_M / 2],
            rgba=[*SIDE_RGB, 1.0], **visual,
        )  # fmt: skip
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_BOX, size=[hx, hy, TOP_PLATE_M / 2], pos=[0, 0, hz - TOP_PLATE_M / 2],
            rgba=[*part.rgb, 1.0], **visual,
        )  # fmt: skip
    else:
        half = shape.height_m / 2
        pieces = shape.convex_pieces()
        areas = [abs(_area(piece)) for piece in pieces]
        for k, piece in enumerate(pieces):
            mesh = spec.add_mesh(name=f"{part.name}_piece{k}")
            mesh.uservert = _prism_vertices(piece, -half, half)
            collision_geoms.append(
                body.add_geom(
                    name=f"{part.name}_piece{k}",
                    type=mujoco.mjtGeom.mjGEOM_MESH,
                    meshname=mesh.name,
                    mass=mass * areas[k] / sum(areas),
                    **common,
                )  # fmt: skip
            )
        outline = shape.outline_m
        for label, low, high, rgb in (
            ("sides", -half, half - TOP_PLATE_M, SIDE_RGB),
            ("top", half - TOP_PLATE_M, half, part.rgb),
        ):
            mesh = spec.add_mesh(name=f"{part.name}_{label}")
            mesh.uservert = _prism_vertices(outline, low, high)
            mesh.userface = _prism_faces(outline, pieces)
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh.name, rgba=[*rgb, 1.0], **visual)
    # The pads meet the part through explicit pairs (Bullet's product of coefficients).
    for finger in FINGER_BODIES:
        spec.add_exclude(bodyname1=finger, bodyname2=part.name)
    finger_geoms = [
        (body_.name, k) for body_ in spec.bodies if body_.name in FINGER_BODIES for k in range(len(body_.geoms))
    ]
    for finger_name, k in finger_geoms:
        for geom in collision_geoms:
            spec.add_pair(
                name=f"{finger_name}{k}_{geom.name}",
                geomname1=f"{finger_name}_geom{k}",
                geomname2=geom.name,
                condim=3,
                friction=[pad_friction(part.friction, pad_lateral, physics)] * 2 + [0.0, 0.0, 0.0],
                solref=_solref(physics, time_step_s),
                solimp=list(physics.solimp),
            )
    return collision_geoms


def _part_pairs(spec, parts: Sequence[PartSpec], geoms: dict, physics: MujocoPhysics, time_step_s: float) -> None:  # noqa: ANN001
    """Two parts meet through explicit pairs whose ``solref`` is the part-on-part contact's.

    Everything else is what MuJoCo's dynamic contact between two part geoms of equal priority has:
    the larger friction of the two, condim 3, the parts' ``solimp``; the dynamic contacts between
    the two bodies are excluded.
    """
    solref = [physics.part_time_constant_s(time_step_s), physics.solref_damping_ratio]
    for k, first in enumerate(parts):
        for second in parts[k + 1 :]:
            spec.add_exclude(bodyname1=first.name, bodyname2=second.name)
            friction = physics.friction_scale * BULLET_BASE_FRICTION * max(first.friction, second.friction)
            for geom1 in geoms[first.name]:
                for geom2 in geoms[second.name]:
                    spec.add_pair(
                        name=f"{geom1.name}_{geom2.name}",
                        geomname1=geom1.name,
                        geomname2=geom2.name,
                        condim=3,
                        friction=[friction] * 2 + [0.0, 0.0, 0.0],
                        solref=solref,
                        solimp=list(physics.solimp),
                    )


def name_finger_geoms(spec) -> None:  # noqa: ANN001
    """Name the finger links' geoms ``<finger>_geom<k>`` (the URDF leaves them unnamed) for the pairs."""
    for body in spec.bodies:
        if body.name in FINGER_BODIES:
            for k, geom in enumerate(body.geoms):
                geom.name = f"{body.name}_geom{k}"


def _area(polygon: np.ndarray) -> float:
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _prism_vertices(polygon: np.ndarray, z_low: float, z_high: float) -> list[float]:
    """The vertices of ``polygon`` extruded from ``z_low`` to ``z_high``, flat: bottom ring then top ring."""
    ring = [(float(x), float(y)) for x, y in polygon]
    return [v for z in (z_low, z_high) for x, y in ring for v in (x, y, z)]


def _prism_faces(polygon: np.ndarray, pieces: Sequence[np.ndarray]) -> list[int]:
    """Triangles (outward) of an extruded outline: caps fanned over its convex pieces, two per side."""
    count = len(polygon)
    index = {(round(float(x), 12), round(float(y), 12)): k for k, (x, y) in enumerate(polygon)}
    faces: list[int] = []
    for piece in pieces:
        ids = [index[(round(float(x), 12), round(float(y), 12))] for x, y in piece]
        for k in range(1, len(ids) - 1):
            a, b, c = ids[0], ids[k], ids[k + 1]
            faces += [a, c, b, a + count, b + count, c + count]
    for k in range(count):
        n = (k + 1) % count
        faces += [k, n, n + count, k, n + count, k + count]
    return faces


def _camera_and_light(spec, config: CellConfig) -> None:  # noqa: ANN001
    import mujoco

    camera = config.camera
    pose = camera.pose_world()
    intrinsics = camera.calibrated_intrinsics()
    fovy_deg = math.degrees(2.0 * math.atan((camera.height_px / 2.0) / intrinsics.fy_px))
    spec.worldbody.add_camera(name="top", pos=list(pose.position_m), quat=camera_quat_wxyz(pose), fovy=fovy_deg)
    direction = np.asarray(camera.light_direction, dtype=float)
    direction = -direction / np.linalg.norm(direction)
    spec.worldbody.add_light(
        name="sun",
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
        dir=list(direction),
        pos=[0.5, 0.0, 2.0],
        castshadow=False,
        diffuse=[0.6, 0.6, 0.6],
        ambient=[0.4, 0.4, 0.4],
        specular=[0.0, 0.0, 0.0],
    )
    spec.visual.headlight.active = 0
