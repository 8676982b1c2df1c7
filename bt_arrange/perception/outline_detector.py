"""``OutlineDetector``: prism parts of one colour told apart by their outlines, in one frame.

The blob search is the part detector's (``PartDetector``); each face is registered to every
outline (``bt_arrange.perception.outline``), and the better fit names the part.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from bt_arrange.errors import PerceptionError
from bt_arrange.objects import ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourTable
from bt_arrange.perception.detection import PartDetector
from bt_arrange.perception.outline import detect_outlines
from bt_arrange.perception.outline_fit import OutlineModel
from bt_arrange.perception.values import Detection, DetectorConfig, WorldRegion
from bt_arrange.robot import CameraFrame


class OutlineDetector:
    """Finds prism parts' top faces by their outlines; parts of one colour are told apart by outline.

    ``detect(frame, colour, part=name)`` looks for one part (the first by default),
    ``detect_each(frame, colour)`` answers for every part by name: a face that fits another part's
    outline better is that part's. The blob search is the part detector's.
    """

    def __init__(
        self,
        parts: Sequence[ObjectType],
        colours: ColourTable = DEFAULT_COLOUR_TABLE,
        config: DetectorConfig | None = None,
    ) -> None:
        if not parts:
            raise PerceptionError("an outline detector needs at least one part")
        self.models = tuple(OutlineModel.of(part) for part in parts)
        if len({m.name for m in self.models}) != len(self.models):
            raise PerceptionError(
                f"parts of an outline detector need distinct names, got {[m.name for m in self.models]}"
            )
        # The blob search keeps any blob of a quarter of the smallest face.
        smallest = min(self.models, key=lambda m: m.area_m2)
        self.search = PartDetector(colours, replace(config or DetectorConfig(), part=smallest.part))

    def detect(
        self, frame: CameraFrame, colour: str, roi: WorldRegion | None = None, part: str | None = None
    ) -> Detection:
        """The part named ``part`` (default the first) of ``colour``."""
        results = self.detect_each(frame, colour, roi)
        name = part or self.models[0].name
        if name not in results:
            raise PerceptionError(f"unknown part {name!r}: this detector knows {', '.join(results)}")
        return results[name]

    def detect_each(self, frame: CameraFrame, colour: str, roi: WorldRegion | None = None) -> dict[str, Detection]:
        """Every part of ``colour`` by name, each told apart from the others by its outline."""
        colour_range = self.search.colours[colour]
        view = self.search._prepare(frame)
        return detect_outlines(self.search, view, colour_range, roi, self.models)
