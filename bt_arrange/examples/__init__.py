"""Example plans shipped in the package, so ``pip install`` without a checkout can run them.

``bt-arrange examples`` lists them; ``bt-arrange run NAME`` (and ``show NAME``) runs one by name.
Each is a plan file (docs/plans.md) whose first comment line says what it arranges.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def _folder() -> Path:
    return Path(str(resources.files(__name__)))


def names() -> list[str]:
    """The examples' names (their file stems), sorted."""
    return sorted(path.stem for path in _folder().glob("*.toml"))


def path_of(name: str) -> Path | None:
    """The plan file of the example ``name``, or None when there is none."""
    path = _folder() / f"{name}.toml"
    return path if path.is_file() else None


def describe(name: str) -> str:
    """The first comment line of the example (what it arranges)."""
    path = path_of(name)
    if path is None:
        return ""
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            return line.lstrip("#").strip()
    return ""
