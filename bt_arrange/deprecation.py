"""Old public names kept for one release after a rename: each warns once, naming its replacement.

A renamed module attribute (a class, a function, a constant)::

    if TYPE_CHECKING:
        CubeDetector = PartDetector
    else:
        __getattr__ = renamed_attributes(__name__, {"CubeDetector": "PartDetector"})

The ``TYPE_CHECKING`` branch keeps the old name known to mypy (code still on it type-checks) while
the module keeps no ``__getattr__`` that mypy sees, so a misspelt name is still an error there. At
run time Python asks ``__getattr__`` only for names the module lacks, so the new names cost nothing.

A renamed keyword argument: ``@renamed_keywords(cubes="parts")`` on the function.

A moved module keeps its old path as a two-line file: ``moved_module(__name__, "new.path")``, which
warns once and puts the new module in the old one's place (every name, private ones too).

Each old name warns once per process (``DeprecationWarning``): a loop over an old name would
otherwise repeat the same line thousands of times, and the first one says all there is to say.
"""

from __future__ import annotations

import functools
import sys
import warnings
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

__all__ = ["moved_module", "renamed_attributes", "renamed_keywords", "warn_once"]

F = TypeVar("F", bound=Callable[..., Any])

#: The old names that have warned in this process (qualified: ``module.name``, ``function(name=)``).
_warned: set[str] = set()


def warn_once(old: str, new: str, *, stacklevel: int = 3) -> None:
    """Warn that ``old`` is deprecated in favour of ``new``, the first time only.

    ``stacklevel`` 3 points the warning at the caller of the function calling this one: the
    line that used the old name, not the alias machinery.
    """
    if old in _warned:
        return
    _warned.add(old)
    warnings.warn(
        f"{old} is deprecated and will be removed in the next release; use {new}",
        DeprecationWarning,
        stacklevel=stacklevel,
    )


def renamed_attributes(module_name: str, renames: Mapping[str, str]) -> Callable[[str], Any]:
    """A module-level ``__getattr__`` serving ``renames`` (old name -> new name) of ``module_name``.

    The new name is looked up at each access, not at definition, so the factory may be called
    before the module has defined it and the alias always gives what the new name holds.
    """
    unknown = set(renames.values()) & set(renames)
    if unknown:
        raise ValueError(f"names both old and new: {sorted(unknown)}")

    def __getattr__(name: str) -> Any:
        new = renames.get(name)
        if new is None:
            raise AttributeError(f"module {module_name!r} has no attribute {name!r}")
        warn_once(f"{module_name}.{name}", f"{module_name}.{new}")
        return getattr(sys.modules[module_name], new)

    return __getattr__


def renamed_keywords(**renames: str) -> Callable[[F], F]:
    """Decorate a function whose keyword arguments were renamed (``old="new"``): the old ones still work."""

    def decorate(function: F) -> F:
        @functools.wraps(function)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            for old, new in renames.items():
                if old not in kwargs:
                    continue
                if new in kwargs:
                    raise TypeError(f"{function.__qualname__}() got both {old}= (deprecated) and {new}=")
                where = f"{function.__module__}.{function.__qualname__}"
                warn_once(f"{where}({old}=...)", f"{where}({new}=...)")
                kwargs[new] = kwargs.pop(old)
            return function(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate


def moved_module(old: str, new: str) -> None:
    """Serve module ``new`` under its old path ``old`` (call it from the old module's file), warning once."""
    import importlib

    warn_once(old, new, stacklevel=4)
    sys.modules[old] = importlib.import_module(new)
