"""Numbers as text for people: fixed decimals, never a ``-0.00``.

``f"{-0.0001:.2f}"`` is ``-0.00``: a sign on a figure that rounds to zero says nothing but looks
like a direction. Feedback messages, the replay page and the live view write figures through
``fixed`` instead.
"""

from __future__ import annotations


def fixed(value: float, digits: int = 2, *, sign: bool = False) -> str:
    """``value`` with ``digits`` decimals (``sign``: always signed, ``+0.00`` for zero), never ``-0.00``.

    >>> fixed(-0.0001), fixed(-0.0001, sign=True), fixed(-1.234, 1), fixed(0.004, 2, sign=True)
    ('0.00', '+0.00', '-1.2', '+0.00')
    """
    spec = f"{'+' if sign else ''}.{digits}f"
    text = format(value, spec)
    if text.lstrip("+-").strip("0.") == "" and text.startswith("-"):
        text = format(0.0, spec)
    return text
