"""The things on the table: coloured cuboids, painted from the one colour table perception reads."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.files import shared_temp_file
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, PAINT_RGB, SIDE_RGB, ColourRange, ColourTable
from bt_arrange.shapes import Prism

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
#: Parts of no stated mass whose volume is known (prisms) weigh as hard wood: the paper's 5 cm
#: cube of 0.1 kg is 800 kg/m3.
WOOD_DENSITY_KG_M3 = 800.0
#: The collision margin Bullet puts around a mesh's convex hull (pybullet's default, measured: an L
#: of unshrunk hulls rested 0.99 mm above its true height).
HULL_MARGIN_M = 0.001


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
    """The type's ``mass_kg``; else a prism's volume at ``WOOD_DENSITY_KG_M3``, a cuboid's ``DEFAULT_MASS_KG``."""
    if object_type.mass_kg is not None:
        return object_type.mass_kg
    shape = object_type.shape
    if not shape.rectangular:
        return WOOD_DENSITY_KG_M3 * shape.area_m2 * shape.height_m
    return DEFAULT_MASS_KG


def prism_mesh_files(shape: Prism) -> tuple[str, str, str]:
    """OBJ files of a prism, centred on its centre of mass: collision, sides and top plate.

    The collision file holds one object per convex piece (``Prism.convex_pieces``): Bullet makes a
    compound of their convex hulls, exact for a non-convex outline. The files are named by their
    content in the temporary directory and written once, whole or absent (``files.shared_temp_file``).
    """
    half = shape.height_m / 2
    pieces = shape.convex_pieces()
    outline = shape.outline_m
    # Bullet grows a convex hull by its collision margin all round (a box keeps its margin inside):
    # each piece is shrunk by it, so hull and margin together are the outline and the height.
    inner = [_shrunk(piece, HULL_MARGIN_M) for piece in pieces]
    collision = _obj(
        [(f"piece{k}", piece, -half + HULL_MARGIN_M, half - HULL_MARGIN_M, [piece]) for k, piece in enumerate(inner)]
    )
    sides = _obj([("sides", outline, -half, half - TOP_PLATE_M, pieces)])
    top = _obj([("top", outline, half - TOP_PLATE_M, half, pieces)])
    collision_path, sides_path, top_path = (
        str(shared_temp_file("bt_arrange_mesh_", ".obj", text)) for text in (collision, sides, top)
    )
    return collision_path, sides_path, top_path


def _shrunk(polygon: np.ndarray, margin_m: float) -> np.ndarray:
    """A convex counter-clockwise polygon with every edge moved ``margin_m`` inward."""
    before = polygon - np.roll(polygon, 1, axis=0)
    after = np.roll(polygon, -1, axis=0) - polygon
    n_in = np.column_stack([before[:, 1], -before[:, 0]]) / np.linalg.norm(before, axis=1)[:, None]
    n_out = np.column_stack([after[:, 1], -after[:, 0]]) / np.linalg.norm(after, axis=1)[:, None]
    miter = (n_in + n_out) / (1.0 + np.sum(n_in * n_out, axis=1))[:, None]
    return polygon - margin_m * miter


def _obj(objects: list[tuple[str, np.ndarray, float, float, list[np.ndarray]]]) -> str:
    """OBJ text of polygons (counter-clockwise) extruded from ``z_low`` to ``z_high``, one object each.

    Each object's caps are fanned over its convex ``pieces`` (vertices of the polygon), its sides
    are one quad per edge; faces wind outward.
    """
    lines: list[str] = []
    offset = 1  # OBJ numbers vertices from 1, across the whole file
    for name, polygon, z_low, z_high, pieces in objects:
        count = len(polygon)
        lines.append(f"o {name}")
        lines += [f"v {x:.9f} {y:.9f} {z_low:.9f}" for x, y in polygon]
        lines += [f"v {x:.9f} {y:.9f} {z_high:.9f}" for x, y in polygon]
        index = {(round(float(x), 12), round(float(y), 12)): k for k, (x, y) in enumerate(polygon)}
        for piece in pieces:
            ids = [index[(round(float(x), 12), round(float(y), 12))] for x, y in piece]
            for k in range(1, len(ids) - 1):
                first, second, third = ids[0] + offset, ids[k] + offset, ids[k + 1] + offset
                lines.append(f"f {first} {third} {second}")  # the bottom, facing down
                lines.append(f"f {first + count} {second + count} {third + count}")  # the top, facing up
        for k in range(count):
            nxt = (k + 1) % count
            lines.append(f"f {k + offset} {nxt + offset} {nxt + count + offset} {k + count + offset}")
        offset += 2 * count
    return "\n".join(lines) + "\n"


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
    if shape.rectangular:
        hx, hy, hz = (v / 2 for v in shape.size_m)
        collision = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[hx, hy, hz])
        visual = client.createVisualShapeArray(
            shapeTypes=[pybullet.GEOM_BOX, pybullet.GEOM_BOX],
            halfExtents=[[hx, hy, hz - TOP_PLATE_M / 2], [hx, hy, TOP_PLATE_M / 2]],
            visualFramePositions=[[0, 0, -TOP_PLATE_M / 2], [0, 0, hz - TOP_PLATE_M / 2]],
        )
    else:
        collision_obj, sides_obj, top_obj = prism_mesh_files(shape)
        collision = client.createCollisionShape(pybullet.GEOM_MESH, fileName=collision_obj)
        visual = client.createVisualShapeArray(
            shapeTypes=[pybullet.GEOM_MESH, pybullet.GEOM_MESH], fileNames=[sides_obj, top_obj]
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
