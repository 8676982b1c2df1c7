"""The colour table: which HSV pixels belong to which named part colour.

Hues are given in degrees (0..360) and saturation and value as fractions (0..1), the way a
person reads a colour picker; the masks are computed on OpenCV's 8-bit HSV, where hue runs
0..179 (two degrees per step) and saturation and value 0..255.

Extend the table with a range around a colour you measured::

    table = DEFAULT_COLOUR_TABLE.with_colour(ColourRange.around_rgb("orange", (1.0, 0.5, 0.0)))
"""

from __future__ import annotations

import colorsys
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PerceptionError

Mask = NDArray[np.uint8]


@dataclass(frozen=True)
class ColourRange:
    """A named colour: one or more hue intervals, and minimum/maximum saturation and value.

    ``hue_ranges_deg`` holds closed intervals ``(low, high)`` with ``0 <= low <= high <= 360``;
    a colour that straddles hue 0 (red) needs two of them. Use :meth:`around` or
    :meth:`around_rgb` to have the wrap-around split done for you.
    """

    name: str
    hue_ranges_deg: tuple[tuple[float, float], ...]
    saturation_range: tuple[float, float] = (0.40, 1.0)
    value_range: tuple[float, float] = (0.15, 1.0)
    #: The colour a simulated cell paints the top face (RGB, 0..1); None: the middle of the range.
    rgb: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if not self.name:
            raise PerceptionError("a colour range needs a name")
        if not self.hue_ranges_deg:
            raise PerceptionError(f"colour {self.name!r} has no hue range")
        for low, high in self.hue_ranges_deg:
            if not 0.0 <= low <= high <= 360.0:
                raise PerceptionError(
                    f"colour {self.name!r}: hue range ({low}, {high}) deg must satisfy 0 <= low <= high <= 360"
                )
        for label, (low, high) in (("saturation", self.saturation_range), ("value", self.value_range)):
            if not 0.0 <= low <= high <= 1.0:
                raise PerceptionError(
                    f"colour {self.name!r}: {label} range ({low}, {high}) must satisfy 0 <= low <= high <= 1"
                )
        if self.rgb is not None:
            if len(self.rgb) != 3 or not all(0.0 <= float(v) <= 1.0 for v in self.rgb):
                raise PerceptionError(f"colour {self.name!r}: rgb {self.rgb!r} must be three numbers in 0..1")
            object.__setattr__(self, "rgb", tuple(float(v) for v in self.rgb))

    @property
    def paint_rgb(self) -> tuple[float, float, float]:
        """The RGB (0..1) a simulated cell paints this colour with: ``rgb``, or the middle of the range.

        The middle is the first hue interval's centre (of the wrapped interval for a colour split at
        hue 0) at the middle of the saturation and value ranges, so the mask of the range holds it.
        """
        if self.rgb is not None:
            return self.rgb
        if len(self.hue_ranges_deg) == 2 and self.hue_ranges_deg[0][0] == 0.0:
            low, high = self.hue_ranges_deg[1][0] - 360.0, self.hue_ranges_deg[0][1]
        else:
            low, high = self.hue_ranges_deg[0]
        hue = ((low + high) / 2.0) % 360.0
        saturation = sum(self.saturation_range) / 2.0
        value = sum(self.value_range) / 2.0
        red, green, blue = colorsys.hsv_to_rgb(hue / 360.0, saturation, value)
        return (red, green, blue)

    @classmethod
    def around(
        cls,
        name: str,
        hue_deg: float,
        hue_tolerance_deg: float = 20.0,
        min_saturation: float = 0.40,
        min_value: float = 0.15,
        rgb: tuple[float, float, float] | None = None,
    ) -> ColourRange:
        """A range of ``hue_deg +- hue_tolerance_deg``, split in two where it crosses hue 0 (``rgb``: the paint)."""
        if not 0.0 < hue_tolerance_deg < 180.0:
            raise PerceptionError(f"colour {name!r}: hue tolerance {hue_tolerance_deg} deg must be in (0, 180)")
        low = (hue_deg - hue_tolerance_deg) % 360.0
        high = (hue_deg + hue_tolerance_deg) % 360.0
        ranges = ((low, high),) if low <= high else ((0.0, high), (low, 360.0))
        return cls(name, ranges, (min_saturation, 1.0), (min_value, 1.0), rgb)

    @classmethod
    def around_rgb(
        cls,
        name: str,
        rgb: tuple[float, float, float],
        hue_tolerance_deg: float = 15.0,
        saturation_fraction: float = 0.5,
        min_value: float = 0.15,
    ) -> ColourRange:
        """A range around the hue of an RGB colour (0..1), down to a fraction of its saturation.

        Brightness changes (shading, exposure) keep hue and saturation and change value, so the
        value bound stays low: ``min_value`` only rejects pixels too dark to have a stable hue.
        """
        hue, saturation, _ = colorsys.rgb_to_hsv(*rgb)
        if saturation < 0.2:
            raise PerceptionError(
                f"colour {name!r}: {rgb} is nearly grey (saturation {saturation:.2f}); "
                "greys cannot be told apart from the table by hue"
            )
        return cls.around(name, hue * 360.0, hue_tolerance_deg, saturation * saturation_fraction, min_value, rgb)

    def _cv_bounds(self) -> list[tuple[NDArray[np.uint8], NDArray[np.uint8]]]:
        """Inclusive 8-bit HSV bounds for ``cv2.inRange``, one pair per hue interval."""
        s_low, s_high = (round(255 * s) for s in self.saturation_range)
        v_low, v_high = (round(255 * v) for v in self.value_range)
        bounds = []
        for low_deg, high_deg in self.hue_ranges_deg:
            # OpenCV's 8-bit hue is degrees / 2 in 0..179; hue 360 is hue 0, already covered by a
            # range that starts at 0 when the colour wraps.
            h_low = math.ceil(low_deg / 2.0 - 1e-9)
            h_high = min(math.floor(high_deg / 2.0 + 1e-9), 179)
            if h_low <= h_high:
                bounds.append(
                    (
                        np.array([h_low, s_low, v_low], dtype=np.uint8),
                        np.array([h_high, s_high, v_high], dtype=np.uint8),
                    )
                )
        return bounds

    @property
    def many_hues(self) -> bool:
        """True for a range over more than half the hue circle: a picture's colours, no one face chroma."""
        return sum(high - low for low, high in self.hue_ranges_deg) > 180.0

    def mask(self, hsv: NDArray[np.uint8]) -> Mask:
        """Binary mask (0 or 255) of the pixels of an 8-bit HSV image that have this colour."""
        bounds = self._cv_bounds()
        mask = cv2.inRange(hsv, bounds[0][0], bounds[0][1])
        for low, high in bounds[1:]:
            mask = cv2.bitwise_or(mask, cv2.inRange(hsv, low, high))
        return np.asarray(mask, dtype=np.uint8)

    def contains_rgb(self, rgb: tuple[float, float, float]) -> bool:
        """True when an RGB colour (0..1) falls inside this range, as the 8-bit mask would say."""
        pixel = np.clip(np.round(np.asarray(rgb, dtype=float) * 255.0), 0, 255).astype(np.uint8)
        hsv = np.asarray(cv2.cvtColor(pixel.reshape(1, 1, 3), cv2.COLOR_RGB2HSV), dtype=np.uint8)
        return bool(self.mask(hsv)[0, 0])


class ColourTable(Mapping[str, ColourRange]):
    """An immutable, ordered table of named colour ranges; looking up an unknown name raises.

    Asking for a colour that is not in the table is a configuration mistake, not a detection
    outcome: it raises :class:`~bt_arrange.errors.PerceptionError` naming the colour and the
    known ones.
    """

    def __init__(self, ranges: tuple[ColourRange, ...] | list[ColourRange]) -> None:
        names = [r.name for r in ranges]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise PerceptionError(f"colour table lists {', '.join(duplicates)} more than once")
        self._ranges: dict[str, ColourRange] = {r.name: r for r in ranges}

    def __getitem__(self, name: str) -> ColourRange:
        try:
            return self._ranges[name]
        except KeyError:
            known = ", ".join(self._ranges) or "none"
            raise PerceptionError(f"unknown colour {name!r}: the colour table knows {known}") from None

    def __contains__(self, name: object) -> bool:
        return name in self._ranges

    def get(self, name: str, default: ColourRange | None = None) -> ColourRange | None:  # type: ignore[override]
        """The range of ``name``, or ``default`` when the table does not know it (never raises)."""
        return self._ranges.get(name, default)

    def __iter__(self) -> Iterator[str]:
        return iter(self._ranges)

    def __len__(self) -> int:
        return len(self._ranges)

    def __repr__(self) -> str:
        return f"ColourTable({', '.join(self._ranges)})"

    @property
    def names(self) -> tuple[str, ...]:
        """The colour names, in table order."""
        return tuple(self._ranges)

    def with_colour(self, colour: ColourRange) -> ColourTable:
        """A new table with ``colour`` added, or replacing the range of the same name."""
        ranges = dict(self._ranges)
        ranges[colour.name] = colour
        return ColourTable(list(ranges.values()))

    def without_colour(self, name: str) -> ColourTable:
        """A new table without ``name`` (which must be in the table)."""
        self[name]  # raises with the list of known colours
        return ColourTable([r for n, r in self._ranges.items() if n != name])


#: The one colour table of the cell, shared by the simulated cell (which paints each top face with
#: ``rgb``) and the detector (which reads it with the range): red (0.80, 0.08, 0.08) at hue 0,
#: yellow (0.90, 0.80, 0.10) at 53 deg, green (0.10, 0.65, 0.20) at 131 deg, blue
#: (0.10, 0.25, 0.85) at 228 deg, all with saturation 0.85..0.90. The ranges keep 15..40 deg of
#: hue margin, accept half that saturation and down to 15 % value, so a face lit at 45 % still
#: passes, while the near-white part sides, the grey table and the grey/black robot (saturation
#: below 0.1) never do. A user's colour joins it with ``with_colour`` (a plan's ``[colours.NAME]``).
DEFAULT_COLOUR_TABLE = ColourTable(
    [
        ColourRange.around("red", 0.0, 20.0, rgb=(0.80, 0.08, 0.08)),
        ColourRange.around("yellow", 53.0, 15.0, rgb=(0.90, 0.80, 0.10)),
        ColourRange.around("green", 131.0, 40.0, rgb=(0.10, 0.65, 0.20)),
        ColourRange.around("blue", 228.0, 28.0, rgb=(0.10, 0.25, 0.85)),
    ]
)

#: The paint of each built-in colour (RGB 0..1), read from the table (each range's ``rgb``): for
#: callers that want the paint by name; a new colour goes into the table (a plan's ``[colours.NAME]``).
PAINT_RGB: dict[str, tuple[float, float, float]] = {
    name: colour.paint_rgb for name, colour in DEFAULT_COLOUR_TABLE.items()
}
#: A part's sides: near-white, so the top camera sees only its top face in colour.
SIDE_RGB = (0.85, 0.85, 0.82)
