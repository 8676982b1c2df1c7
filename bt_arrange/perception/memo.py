"""Results of the contour's registrations kept across looks: a neighbour's unmoved face is registered once.

A look renders a window about the part it looks for; the faces of its neighbours that fall in
the window (most cut by its border) are registered too, look after look, and unless something
moved them their contours are the same to the last bit. The registrations on the contour alone
(``bt_arrange.perception.outline.register``'s coarse fits, ``outline_merged``'s fit on the free
edges) are pure functions of the contour, the model and a few numbers, so their results are kept
here, keyed by those inputs' bytes, and handed back unchanged: the same results as computing them
again. Whatever reads the image's pixels (the sub-pixel edges) is computed every time.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import TypeVar

import numpy as np

from bt_arrange.perception.outline_fit import OutlineModel

T = TypeVar("T")

#: How many results each kind of registration keeps (the oldest dropped first): a few looks' faces.
MEMO_SIZE = 64


def array_key(array: np.ndarray) -> tuple[Hashable, ...]:
    """An array's exact value as a key: its dtype, shape and bytes."""
    return (array.dtype.str, array.shape, array.tobytes())


def model_key(model: OutlineModel) -> tuple[Hashable, ...]:
    """What a registration reads of a model: its outline, height and symmetry."""
    return (array_key(model.outline_m), model.height_m, model.symmetry_rad)


class Memo:
    """A bounded memo of one function's results by key (the oldest dropped first)."""

    def __init__(self, size: int = MEMO_SIZE) -> None:
        self._size = size
        self._results: dict[Hashable, object] = {}
        self.hits = 0

    def get(self, key: Hashable, compute: Callable[[], T]) -> T:
        """The result for ``key``: kept, or computed and kept."""
        if key in self._results:
            self.hits += 1
            return self._results[key]  # type: ignore[return-value]
        result = compute()
        if len(self._results) >= self._size:
            self._results.pop(next(iter(self._results)))
        self._results[key] = result
        return result
