"""The Foxglove layout shipped as ``docs/foxglove-layout.json``, built with the SDK's own layout classes.

``python -m bt_arrange.foxglove.layout > docs/foxglove-layout.json`` writes it again (a test checks
that the file shipped is this one). Panels: the 3-D scene (the arm from ``/robot_description``, the
parts and targets of ``/parts``, the frames of ``/tf``, the camera's image in its frustum), the
camera's image, each part's true offset from its target over time (``/offsets``, a series per
colour of the default table), the feedback log (``/log``) and the tree's statuses (``/tree``).
"""

from __future__ import annotations

import json

import foxglove.layouts as fl

from bt_arrange.perception import DEFAULT_COLOUR_TABLE


def build() -> fl.Layout:
    """The layout."""
    three_d = fl.ThreeDeePanel(
        title="cell",
        config=fl.ThreeDeeConfig(
            follow_tf="world",
            layers={
                "grid": fl.BaseRendererGridLayerSettings(),
                "urdf": fl.BaseRendererUrdfLayerSettings(source_type="topic", topic="/robot_description"),
            },
            topics={
                "/parts": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
                "/camera/image": fl.BaseRendererImageTopicSettings(visible=True),
            },
        ),
    )
    image = fl.ImagePanel(
        title="camera",
        config=fl.ImageConfig(
            image_mode=fl.ImageModeConfig(image_topic="/camera/image", calibration_topic="/camera/calibration")
        ),
    )
    plot = fl.PlotPanel(
        title="offset from target (mm, ground truth)",
        config=fl.PlotConfig(
            paths=[
                fl.PlotSeries(value=f'/offsets.parts[:]{{name=="{name}"}}.offset_mm', label=name)
                for name in DEFAULT_COLOUR_TABLE.names
            ],
            show_legend=True,
        ),
    )
    log = fl.LogPanel(title="feedback", config=fl.LogConfig(topic_to_render="/log"))
    tree = fl.RawMessagesPanel(title="tree", config=fl.RawMessagesConfig(topic_path="/tree.nodes"))
    right = fl.SplitContainer(
        direction="column",
        items=[fl.SplitItem(content=image), fl.SplitItem(content=plot), fl.SplitItem(content=log)],
    )
    return fl.Layout(
        content=fl.SplitContainer(
            direction="row",
            items=[
                fl.SplitItem(proportion=2, content=three_d),
                fl.SplitItem(proportion=1, content=right),
                fl.SplitItem(proportion=1, content=tree),
            ],
        )
    )


def layout_json() -> str:
    """The layout as the file holds it."""
    return json.dumps(json.loads(build().to_json()), indent=2) + "\n"


if __name__ == "__main__":
    print(layout_json(), end="")
