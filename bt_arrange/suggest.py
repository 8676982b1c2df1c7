"""Nearest-name suggestions for a mistyped name: ``did you mean 'six_in_a_row'?``.

One function the messages share (tree files and examples, object types, colours, experiment
rows, cells, XML nodes): ``nearest(name, known)`` is the closest known names by ``difflib``'s
ratio, case folded, and ``did_you_mean`` the text to put after the unknown name.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

#: How alike two names must be (difflib's ratio, 0..1) for one to be offered for the other.
CUTOFF = 0.6


def nearest(name: object, known: Iterable[str], count: int = 1) -> list[str]:
    """The known names nearest ``name`` (at most ``count``), best first; none when nothing is alike."""
    if not isinstance(name, str) or not name:
        return []
    names = list(dict.fromkeys(str(k) for k in known))
    folded = {k.casefold(): k for k in names}
    exact = folded.get(name.casefold())
    if exact is not None and exact != name:
        return [exact]
    close = difflib.get_close_matches(name.casefold(), list(folded), n=count, cutoff=CUTOFF)
    if not close:
        # "six_in_row" -> "six_in_a_row": a name that holds every word of the one typed is near too.
        words = [w for w in name.casefold().replace("-", "_").replace(" ", "_").split("_") if w]
        close = [k for k in folded if words and all(w in k for w in words)][:count]
    return [folded[c] for c in close]


def did_you_mean(name: object, known: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` for the nearest known name, or ``""`` when none is near."""
    found = nearest(name, known)
    return f" (did you mean {found[0]!r}?)" if found else ""
