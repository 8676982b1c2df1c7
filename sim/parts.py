"""What a part is made of, in either engine: its paint, its mass, the thin painted plate on its top."""

from __future__ import annotations

from bt_arrange.errors import PlanError
from bt_arrange.objects import ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, PAINT_RGB, SIDE_RGB, ColourRange, ColourTable

__all__ = ["PAINT_RGB", "SIDE_RGB", "TABLE_RGB", "mass_of", "paint_of"]

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
