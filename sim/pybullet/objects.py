"""The parts as pybullet bodies: a cuboid's box or a prism's compound of hulls, painted from the colour table."""

from __future__ import annotations

import hashlib
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, SIDE_RGB, ColourRange, ColourTable
from bt_arrange.shapes import Prism
from bt_arrange_sim.config import Contact
from bt_arrange_sim.parts import TOP_PLATE_M, mass_of, paint_of

__all__ = ["apply_contact", "create_cube", "create_object"]

#: The collision margin Bullet puts around a mesh's convex hull (pybullet's default, measured: an L
#: of unshrunk hulls rested 0.99 mm above its true height).
HULL_MARGIN_M = 0.001


def apply_contact(contact: Contact, client, body: int, link: int = -1) -> None:  # noqa: ANN001
    """Set a contact's figures on one link of a body (``-1`` is the base): pybullet's ``changeDynamics``."""
    client.changeDynamics(
        body,
        link,
        lateralFriction=contact.lateral_friction,
        spinningFriction=contact.spinning_friction,
        rollingFriction=contact.rolling_friction,
        restitution=contact.restitution,
        frictionAnchor=int(contact.friction_anchor),
    )


def create_cube(client, colour: str, position_m, orientation_xyzw, contact: Contact) -> int:  # noqa: ANN001
    """Add a 5 cm cube with a top face of a colour of the default table; returns its body id."""
    return create_object(client, CUBE, colour, position_m, orientation_xyzw, contact)


def prism_mesh_files(shape: Prism, folder: Path, top_uv: np.ndarray | None = None) -> tuple[str, str, str]:
    """OBJ files of a prism in ``folder``, centred on its centre of mass: collision, sides and top plate.

    The collision file holds one object per convex piece (``Prism.convex_pieces``): Bullet makes a
    compound of their convex hulls, exact for a non-convex outline. The files are named by their
    content (pybullet caches a mesh by its file name: one name never stands for two meshes).
    ``top_uv`` (one per outline vertex) gives the top plate texture coordinates (a painted piece).
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
    top = _obj([("top", outline, half - TOP_PLATE_M, half, pieces)], uv=top_uv)
    paths = []
    for text in (collision, sides, top):
        path = folder / f"{hashlib.sha1(text.encode()).hexdigest()[:16]}.obj"
        path.write_text(text, encoding="utf-8")
        paths.append(str(path))
    collision_path, sides_path, top_path = paths
    return collision_path, sides_path, top_path


def _shrunk(polygon: np.ndarray, margin_m: float) -> np.ndarray:
    """A convex counter-clockwise polygon with every edge moved ``margin_m`` inward."""
    before = polygon - np.roll(polygon, 1, axis=0)
    after = np.roll(polygon, -1, axis=0) - polygon
    n_in = np.column_stack([before[:, 1], -before[:, 0]]) / np.linalg.norm(before, axis=1)[:, None]
    n_out = np.column_stack([after[:, 1], -after[:, 0]]) / np.linalg.norm(after, axis=1)[:, None]
    miter = (n_in + n_out) / (1.0 + np.sum(n_in * n_out, axis=1))[:, None]
    return polygon - margin_m * miter


def _obj(objects: list[tuple[str, np.ndarray, float, float, list[np.ndarray]]], uv: np.ndarray | None = None) -> str:
    """OBJ text of polygons (counter-clockwise) extruded from ``z_low`` to ``z_high``, one object each.

    Each object's caps are fanned over its convex ``pieces`` (vertices of the polygon), its sides
    are one quad per edge; faces wind outward. ``uv`` (one object only: a row per polygon vertex)
    are texture coordinates, the same at both heights.
    """
    if uv is not None:
        text = _obj(objects)
        body = "\n".join(f"vt {u:.9f} {v:.9f}" for u, v in uv)
        count = len(uv)

        def textured(line: str) -> str:
            if not line.startswith("f "):
                return line
            return "f " + " ".join(f"{i}/{(int(i) - 1) % count + 1}" for i in line.split()[1:])

        return body + "\n" + "\n".join(textured(line) for line in text.splitlines()) + "\n"
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
    *,
    picture: str | None = None,
    picture_uv: Sequence[tuple[float, float]] = (),
) -> int:
    """Add a part of the type's shape with a top face painted ``colour``; returns its body id.

    A cuboid's collision shape is one primitive box (no mesh margin); the visual is a near-white
    box with a thin coloured plate on top, so only the top face reads as the part's colour. The
    paint comes from the colour table perception reads (``ColourRange.paint_rgb``). The type's
    ``lateral_friction`` replaces the contact's when given. A prism's ``picture`` (a file) is printed on
    its top plate instead of the paint, each outline vertex at its ``picture_uv`` (a painted puzzle).
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
        body = _multi_body(client, object_type, collision, visual, position_m, orientation_xyzw)
    else:
        # The meshes live only while pybullet loads them (the renderer reads the visual ones in
        # createMultiBody): a campaign of fractured parts leaves no file behind in the temporary folder.
        with tempfile.TemporaryDirectory(prefix="bt_arrange_mesh_") as folder:
            top_uv = np.asarray(picture_uv, dtype=float) if picture is not None else None
            collision_obj, sides_obj, top_obj = prism_mesh_files(shape, Path(folder), top_uv)
            collision = client.createCollisionShape(pybullet.GEOM_MESH, fileName=collision_obj)
            visual = client.createVisualShapeArray(
                shapeTypes=[pybullet.GEOM_MESH, pybullet.GEOM_MESH], fileNames=[sides_obj, top_obj]
            )
            body = _multi_body(client, object_type, collision, visual, position_m, orientation_xyzw)
    # A visual shape array takes one colour per body in createMultiBody; colour each part after.
    client.changeVisualShape(body, -1, shapeIndex=0, rgbaColor=[*SIDE_RGB, 1.0])
    if picture is not None and not shape.rectangular:
        texture = client.loadTexture(str(picture))
        client.changeVisualShape(body, -1, shapeIndex=1, textureUniqueId=texture, rgbaColor=[1.0, 1.0, 1.0, 1.0])
    else:
        client.changeVisualShape(body, -1, shapeIndex=1, rgbaColor=[*rgb, 1.0])
    if object_type.lateral_friction is not None:
        contact = dataclasses.replace(contact, lateral_friction=object_type.lateral_friction)
    apply_contact(contact, client, body)
    return int(body)


def _multi_body(client, object_type: ObjectType, collision: int, visual: int, position_m, orientation_xyzw) -> int:  # noqa: ANN001
    """A body of the part's mass from its collision and visual shapes, at a pose."""
    return int(
        client.createMultiBody(
            baseMass=mass_of(object_type),
            baseCollisionShapeIndex=collision,
            baseVisualShapeIndex=visual,
            basePosition=list(position_m),
            baseOrientation=list(orientation_xyzw),
        )
    )
