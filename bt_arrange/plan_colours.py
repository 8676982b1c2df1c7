"""A plan file's ``[colours.NAME]``: a user's colours, as rgb or an HSV range, joined to the cell's own."""

from __future__ import annotations

from typing import Any

from bt_arrange.checks import toml_shown as _shown
from bt_arrange.errors import BtArrangeError, PlanError
from bt_arrange.filelimits import MAX_COLOURS
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable

COLOUR_KEYS = ("rgb", "hue_deg", "saturation", "value")


def read_colour_table(self: Any, table: Any) -> ColourTable:
    """A plan's ``[colours.NAME]`` tables joined to the built-in ones, checked by ``self`` (the plan reader)."""
    colours = DEFAULT_COLOUR_TABLE
    if not isinstance(table, dict):
        raise self.fail("[colours]", f"must be a table of colours, got {_shown(table)}")
    if len(table) > MAX_COLOURS:
        raise self.fail(
            "[colours]",
            f"{len(table)} colours, over the limit of {MAX_COLOURS} (bt_arrange.filelimits.MAX_COLOURS)",
        )
    for name, entry in table.items():
        where = f"[colours.{name}]"
        self.keys(entry, COLOUR_KEYS, where)
        rgb = None
        if "rgb" in entry:
            value = entry["rgb"]
            if not isinstance(value, list) or len(value) != 3:
                raise self.fail(where, f"rgb = {_shown(value)} is not three numbers in 0..1")
            channels = [self.number(v, where, "rgb") for v in value]
            if not all(0.0 <= c <= 1.0 for c in channels):
                raise self.fail(where, f"rgb = {_shown(value)}: each channel must be in 0..1")
            rgb = (channels[0], channels[1], channels[2])
        has_hsv = any(key in entry for key in ("hue_deg", "saturation", "value"))
        try:
            if has_hsv:
                if "hue_deg" not in entry:
                    raise self.fail(where, "an HSV range needs hue_deg = [low, high] (saturation, value optional)")
                hue = self.pair(entry["hue_deg"], where, "hue_deg")
                low, high = hue
                hues = ((low, high),) if low <= high else ((0.0, high), (low, 360.0))
                saturation = self.pair(entry.get("saturation", [0.4, 1.0]), where, "saturation")
                value_range = self.pair(entry.get("value", [0.15, 1.0]), where, "value")
                colour = ColourRange(name, hues, saturation, value_range, rgb)
            elif rgb is not None:
                colour = ColourRange.around_rgb(name, rgb)
            else:
                raise self.fail(where, "a colour needs rgb = [r, g, b] (0..1) or an HSV range (hue_deg = [low, high])")
        except BtArrangeError as error:
            if isinstance(error, PlanError) and str(error).startswith(str(self.path)):
                raise
            raise self.fail(where, str(error)) from None
        colours = colours.with_colour(colour)
    return colours
