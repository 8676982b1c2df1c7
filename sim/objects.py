"""The things on the table: coloured cuboids, painted from the one colour table perception reads."""

from __future__ import annotations

from dataclasses import dataclass

from bt_arrange.errors import PlanError
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, PAINT_RGB, SIDE_RGB, ColourRange, ColourTable
from bt_arrange.shapes import Cuboid

__all__ = ["PAINT_RGB", "Contact", "create_cube", "create_object"]

TABLE_RGB = (0.45, 0.45, 0.47)

#: A 5 cm cube of hard wood; light enough for the 2F-85, heavy enough to rest firmly.
CUBE_MASS_KG = 0.1
#: Types of no stated mass weigh as much as the cube: a 30 mm cube of wood (22 g) chattered
#: between the 40 N pads (the fingers never came to rest, measured), one of 0.1 kg was held still.
DEFAULT_MASS_KG = CUBE_MASS_KG
#: Thickness of the coloured top plate, part of the cube's visual only: thin, because a 0.5 mm
#: plate showed its coloured sides below the face edge and biased detections by up to 0.15 mm.
TOP_PLATE_M = 0.0001


@dataclass(frozen=True)
class Contact:
    """Friction and contact parameters of one body (pybullet ``changeDynamics``)."""

    lateral_friction: float
    spinning_friction: float = 0.0
    rolling_friction: float = 0.0
    restitution: float = 0.0
    #: Bullet's friction anchors pin a sticking contact point instead of letting it drift a
    #: little every step; without them a held cube crept 1 to 3 mm down and along the pads.
    friction_anchor: bool = True

    def apply(self, client, body: int, link: int = -1) -> None:  # noqa: ANN001
        """Set these parameters on one link of a body (``-1`` is the base)."""
        client.changeDynamics(
            body,
            link,
            lateralFriction=self.lateral_friction,
            spinningFriction=self.spinning_friction,
            rollingFriction=self.rolling_friction,
            restitution=self.restitution,
            frictionAnchor=int(self.friction_anchor),
        )


def create_cube(client, colour: str, position_m, orientation_xyzw, contact: Contact) -> int:  # noqa: ANN001
    """Add a 5 cm cube with a top face of a colour of the default table; returns its body id."""
    return create_object(client, CUBE, colour, position_m, orientation_xyzw, contact)


def paint_of(colour: str | ColourRange, colours: ColourTable = DEFAULT_COLOUR_TABLE) -> tuple[float, float, float]:
    """The RGB a top face of ``colour`` (a name of ``colours``, or a range) is painted with."""
    if isinstance(colour, ColourRange):
        return colour.paint_rgb
    found = colours.get(colour)
    if found is None:
        raise PlanError(f"unknown cube colour {colour!r}; known: {', '.join(sorted(colours.names))}")
    return found.paint_rgb


def mass_of(object_type: ObjectType) -> float:
    """The type's ``mass_kg``, or ``DEFAULT_MASS_KG``."""
    return object_type.mass_kg if object_type.mass_kg is not None else DEFAULT_MASS_KG


def create_object(  # noqa: PLR0913
    client,  # noqa: ANN001
    object_type: ObjectType,
    colour: str | ColourRange,
    position_m,  # noqa: ANN001
    orientation_xyzw,  # noqa: ANN001
    contact: Contact,
    colours: ColourTable = DEFAULT_COLOUR_TABLE,
) -> int:
    """Add a part of the type's shape with a top face painted ``colour``; returns its body id.

    A cuboid's collision shape is one primitive box (no mesh margin); the visual is a near-white
    box with a thin coloured plate on top, so only the top face reads as the part's colour. The
    paint comes from the colour table perception reads (``ColourRange.paint_rgb``). The type's
    ``lateral_friction`` replaces the contact's when given.
    """
    import dataclasses

    import pybullet

    rgb = paint_of(colour, colours)
    shape = object_type.shape
    if not isinstance(shape, Cuboid):
        raise PlanError(f"object type {object_type.name!r}: the pybullet cell builds cuboids only, not {shape!r}")
    hx, hy, hz = (v / 2 for v in shape.size_m)
    collision = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[hx, hy, hz])
    visual = client.createVisualShapeArray(
        shapeTypes=[pybullet.GEOM_BOX, pybullet.GEOM_BOX],
        halfExtents=[[hx, hy, hz - TOP_PLATE_M / 2], [hx, hy, TOP_PLATE_M / 2]],
        visualFramePositions=[[0, 0, -TOP_PLATE_M / 2], [0, 0, hz - TOP_PLATE_M / 2]],
    )
    body = client.createMultiBody(
        baseMass=mass_of(object_type),
        baseCollisionShapeIndex=collision,
        baseVisualShapeIndex=visual,
        basePosition=list(position_m),
        baseOrientation=list(orientation_xyzw),
    )
    # A visual shape array takes one colour per body in createMultiBody; colour each part after.
    client.changeVisualShape(body, -1, shapeIndex=0, rgbaColor=[*SIDE_RGB, 1.0])
    client.changeVisualShape(body, -1, shapeIndex=1, rgbaColor=[*rgb, 1.0])
    if object_type.lateral_friction is not None:
        contact = dataclasses.replace(contact, lateral_friction=object_type.lateral_friction)
    contact.apply(client, body)
    return int(body)
