"""The colour table: default ranges, red's wrap-around, extension, unknown colours."""

from __future__ import annotations

import colorsys

import numpy as np
import pytest

from bt_arrange.errors import PerceptionError
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.perception.synthetic import SIM_PART_COLOURS_RGB, SIM_SIDE_RGB, SIM_TABLE_RGB


@pytest.mark.parametrize("name", sorted(SIM_PART_COLOURS_RGB))
@pytest.mark.parametrize("brightness", [0.45, 0.7, 1.0])
def test_default_table_covers_the_sim_colours_under_any_lighting(name: str, brightness: float) -> None:
    rgb = tuple(brightness * c for c in SIM_PART_COLOURS_RGB[name])
    assert DEFAULT_COLOUR_TABLE[name].contains_rgb(rgb)
    others = [other for other in DEFAULT_COLOUR_TABLE if other != name]
    assert not any(DEFAULT_COLOUR_TABLE[other].contains_rgb(rgb) for other in others)


@pytest.mark.parametrize("name", sorted(SIM_PART_COLOURS_RGB))
def test_default_ranges_keep_a_hue_margin(name: str) -> None:
    # 10 degrees of hue either way (a lamp, a camera's white balance) must stay inside.
    hue, saturation, value = colorsys.rgb_to_hsv(*SIM_PART_COLOURS_RGB[name])
    for shift_deg in (-10.0, 10.0):
        shifted = colorsys.hsv_to_rgb((hue + shift_deg / 360.0) % 1.0, saturation, value)
        assert DEFAULT_COLOUR_TABLE[name].contains_rgb(shifted), shift_deg


@pytest.mark.parametrize(
    "grey",
    [SIM_SIDE_RGB, SIM_TABLE_RGB, (0.1, 0.1, 0.1), (0.3, 0.3, 0.32), (1.0, 1.0, 1.0), (0.02, 0.0, 0.0)],
)
def test_greys_and_black_belong_to_no_colour(grey: tuple[float, float, float]) -> None:
    assert not any(colour.contains_rgb(grey) for colour in DEFAULT_COLOUR_TABLE.values())


def test_red_wraps_around_hue_zero() -> None:
    red = DEFAULT_COLOUR_TABLE["red"]
    assert len(red.hue_ranges_deg) == 2
    below_zero = (0.80, 0.08, 0.20)  # hue about 350 deg
    above_zero = (0.80, 0.20, 0.08)  # hue about 9 deg
    assert colorsys.rgb_to_hsv(*below_zero)[0] * 360 > 340
    assert colorsys.rgb_to_hsv(*above_zero)[0] * 360 < 20
    assert red.contains_rgb(below_zero) and red.contains_rgb(above_zero)
    # The wrap-around covers only red: a hue of 180 (cyan) is far from either range.
    assert not red.contains_rgb((0.08, 0.80, 0.80))


def test_mask_marks_exactly_the_pixels_of_the_colour() -> None:
    import cv2

    rgb = np.zeros((2, 3, 3), dtype=np.uint8)
    rgb[0, 0] = (204, 20, 20)  # red
    rgb[0, 1] = (204, 20, 50)  # red, hue just below 360
    rgb[0, 2] = (115, 115, 120)  # table grey
    rgb[1, 0] = (26, 166, 51)  # green
    rgb[1, 1] = (92, 9, 9)  # red at 45 % light
    rgb[1, 2] = (217, 217, 209)  # cube side
    mask = DEFAULT_COLOUR_TABLE["red"].mask(cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV))
    assert mask.tolist() == [[255, 255, 0], [0, 255, 0]]


def test_around_splits_a_range_that_crosses_zero() -> None:
    colour = ColourRange.around("magenta-red", 350.0, 20.0)
    assert colour.hue_ranges_deg == ((0.0, 10.0), (330.0, 360.0))
    assert ColourRange.around("green", 120.0, 20.0).hue_ranges_deg == ((100.0, 140.0),)


def test_table_can_be_extended_with_a_measured_colour() -> None:
    orange = ColourRange.around_rgb("orange", (1.0, 0.5, 0.0))
    table = DEFAULT_COLOUR_TABLE.with_colour(orange)
    assert table.names == (*DEFAULT_COLOUR_TABLE.names, "orange")
    assert table["orange"].contains_rgb((0.9, 0.45, 0.05))
    assert "orange" not in DEFAULT_COLOUR_TABLE  # the default table is left alone
    assert table.without_colour("orange").names == DEFAULT_COLOUR_TABLE.names


def test_unknown_colour_names_itself_and_the_known_ones() -> None:
    with pytest.raises(PerceptionError) as error:
        DEFAULT_COLOUR_TABLE["purple"]
    message = str(error.value)
    assert "'purple'" in message
    for known in ("red", "green", "blue", "yellow"):
        assert known in message


@pytest.mark.parametrize(
    "make",
    [
        lambda: ColourRange("bad", ((30.0, 10.0),)),
        lambda: ColourRange("bad", ((0.0, 400.0),)),
        lambda: ColourRange("bad", ()),
        lambda: ColourRange("bad", ((0.0, 10.0),), saturation_range=(0.5, 1.5)),
        lambda: ColourRange.around_rgb("grey", (0.5, 0.5, 0.52)),
        lambda: ColourTable([ColourRange.around("red", 0.0), ColourRange.around("red", 5.0)]),
    ],
)
def test_malformed_colours_raise(make) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(PerceptionError):
        make()
