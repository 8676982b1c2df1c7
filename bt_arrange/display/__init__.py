"""Show a tree: as text, as Graphviz source, as a PNG or SVG picture, and live in a terminal while it runs.

``render_tree(root, fmt)`` draws a tree built without a robot (``arrangement(...)``, a tree file's
``create_root()``); with ``blackboard=True`` it also shows who writes and who reads each blackboard
key, from the keys every behaviour declared with ``register_key``. Only the clients of the given
tree are drawn, never those left on the global blackboard by other trees built in the same process.

``LiveView`` redraws a running tree with its statuses, the world time and the tip's feedback
message, throttled to a few frames per second of wall time.

PNG and SVG need Graphviz's ``dot`` program; text and dot output do not.

The package keeps three rooms: ``blackboard`` (who writes and reads each key), ``rendering``
(text, dot, PNG, SVG) and ``live`` (the terminal view); everything is importable from here.
"""

from bt_arrange.display.blackboard import KeyAccess, blackboard_access, blackboard_table
from bt_arrange.display.live import LiveView
from bt_arrange.display.rendering import (
    DOT_TIMEOUT_S,
    FORMATS,
    NO_GRAPHVIZ,
    PICTURE_FORMATS,
    dot_graph,
    render_picture,
    render_tree,
    strip_ansi,
    text_tree,
)
from bt_arrange.errors import DisplayError

__all__ = [
    "DOT_TIMEOUT_S",
    "FORMATS",
    "NO_GRAPHVIZ",
    "PICTURE_FORMATS",
    "DisplayError",
    "KeyAccess",
    "LiveView",
    "blackboard_access",
    "blackboard_table",
    "dot_graph",
    "render_picture",
    "render_tree",
    "strip_ansi",
    "text_tree",
]
