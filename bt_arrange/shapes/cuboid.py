"""The box prism, :class:`Cuboid`, kept importable from here: it lives in ``bt_arrange.shapes.prism``."""

from bt_arrange.shapes.prism import SQUARE_TOLERANCE_M, Cuboid

__all__ = ["SQUARE_TOLERANCE_M", "Cuboid"]
