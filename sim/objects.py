"""The things on the table: coloured cubes, and the colours the cell paints them in."""

from __future__ import annotations

from dataclasses import dataclass

from bt_arrange.errors import PlanError
from bt_arrange.settings import CUBE_COLOURS_RGB, CUBE_EDGE_M, CUBE_SIDE_RGB

TABLE_RGB = (0.45, 0.45, 0.47)

#: A 5 cm cube of hard wood; light enough for the 2F-85, heavy enough to rest firmly.
CUBE_MASS_KG = 0.1
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


def create_cube(  # noqa: ANN001 - a BulletClient, positions of any sequence type
    client, colour: str, position_m, orientation_xyzw, contact: Contact, edge_m: float = CUBE_EDGE_M
) -> int:
    """Add a cube with a coloured top face; returns its body id.

    The collision shape is one primitive box (no mesh margin); the visual is a near-white
    box with a thin coloured plate on top, so only the top face reads as the cube's colour.
    """
    import pybullet

    if colour not in CUBE_COLOURS_RGB:
        raise PlanError(f"unknown cube colour {colour!r}; known: {', '.join(sorted(CUBE_COLOURS_RGB))}")
    half = edge_m / 2
    collision = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[half, half, half])
    visual = client.createVisualShapeArray(
        shapeTypes=[pybullet.GEOM_BOX, pybullet.GEOM_BOX],
        halfExtents=[[half, half, half - TOP_PLATE_M / 2], [half, half, TOP_PLATE_M / 2]],
        visualFramePositions=[[0, 0, -TOP_PLATE_M / 2], [0, 0, half - TOP_PLATE_M / 2]],
    )
    body = client.createMultiBody(
        baseMass=CUBE_MASS_KG,
        baseCollisionShapeIndex=collision,
        baseVisualShapeIndex=visual,
        basePosition=list(position_m),
        baseOrientation=list(orientation_xyzw),
    )
    # A visual shape array takes one colour per body in createMultiBody; colour each part after.
    client.changeVisualShape(body, -1, shapeIndex=0, rgbaColor=[*CUBE_SIDE_RGB, 1.0])
    client.changeVisualShape(body, -1, shapeIndex=1, rgbaColor=[*CUBE_COLOURS_RGB[colour], 1.0])
    contact.apply(client, body)
    return int(body)
