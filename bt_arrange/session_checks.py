"""Checks a session makes before a world is built: the plan's colours apart, the ``--record`` folder usable.

Both are ``bt_arrange.session``'s (imported there, and by a backend's run from there).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from bt_arrange.errors import PlanError
from bt_arrange.perception import ColourTable
from bt_arrange.trees import Target


def check_colours_apart(targets: Iterable[Target], colours: ColourTable) -> None:
    """A ``PlanError`` when one colour of the plan would be read as another (one's range holds the other's paint)."""
    used = sorted({t.colour for t in targets}, key=list(colours.names).index)
    for name in used:
        for other in used:
            if other != name and colours[name].contains_rgb(colours[other].paint_rgb):
                raise PlanError(
                    f"colours {name!r} and {other!r} of the plan overlap: {name}'s range holds {other}'s paint "
                    f"{tuple(round(v, 2) for v in colours[other].paint_rgb)}; the camera could not tell them apart: "
                    f"{_colours_apart_text(colours[name], colours[other])}",
                    parts=(("colour", name), ("colour", other)),
                )


def _colours_apart_text(holder: Any, held: Any) -> str:
    """How far ``held``'s paint must move (in hue degrees) to leave ``holder``'s range: the fix of an overlap."""
    import colorsys

    hue_deg = colorsys.rgb_to_hsv(*held.paint_rgb)[0] * 360.0
    ranges = [(low, high) for low, high in holder.hue_ranges_deg if low <= hue_deg <= high]
    if not ranges:
        return f"give {held.name} a paint outside {holder.name}'s saturation and value ranges"
    low, high = ranges[0]
    if len(holder.hue_ranges_deg) == 2 and holder.hue_ranges_deg[0][0] == 0.0:  # a range across hue 0
        low_end, high_end = holder.hue_ranges_deg[1][0] - 360.0, holder.hue_ranges_deg[0][1]
        folded = hue_deg - 360.0 if hue_deg > high_end else hue_deg
        shift = min(folded - low_end, high_end - folded)
        shown = f"{holder.hue_ranges_deg[1][0]:.0f}..360 and 0..{high_end:.0f}"
    else:
        shift = min(hue_deg - low, high - hue_deg)
        shown = f"{low:.0f}..{high:.0f}"
    return (
        f"{held.name}'s paint has hue {hue_deg:.0f} deg, inside {holder.name}'s hue range {shown} deg; move "
        f"{held.name}'s hue at least {shift + 1:.0f} deg away (its rgb, or hue_deg) or narrow {holder.name}'s range"
    )


def check_puzzles_in_view(puzzles: Iterable[Any], view: Any) -> None:
    """A ``PlanError`` when a puzzle's whole slab, grown by the view's margin, is not all inside the camera's image."""
    import math

    import numpy as np

    if view is None:
        return
    for spec in puzzles:
        half_l, half_w = spec.size_m[0] / 2 + view.margin_m, spec.size_m[1] / 2 + view.margin_m
        corners = np.array([spec.to_table(sx * half_l, sy * half_w) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
        if not view.sees_outline(corners, spec.height_m):
            raise PlanError(
                f"[puzzle.{spec.name}]: the whole slab at ({spec.x_m * 1000:.0f}, {spec.y_m * 1000:.0f}) mm, turned "
                f"{math.degrees(spec.yaw_rad):g} deg, is not all in the camera's view: its pieces could be placed "
                "there but never inspected"
            )


def prepare_record_dir(path: Path | str) -> Path:
    """Make the folder ``--record`` writes to, or a ``PlanError`` saying why it cannot be used."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise PlanError(f"cannot record into {folder}: it is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise PlanError(f"cannot record into {folder}: {error.strerror or error}") from error
    if not os.access(folder, os.W_OK):
        raise PlanError(f"cannot record into {folder}: the folder is not writable")
    return folder
