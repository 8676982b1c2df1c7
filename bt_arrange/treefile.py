"""Load a tree file (``trees/*.py``) by path and build its root, with one-line errors.

A tree file exposes ``create_root(...)`` returning a py_trees behaviour, and, to run in a
simulator, ``create_scene(seed)`` returning where the parts start (a real cell needs none). Its
own folder is on ``sys.path`` while it loads, as when Python runs a script, so tree files can share a module.

A ``.xml`` file is a BehaviorTree.CPP tree, read as data by ``bt_arrange.xmltree`` (no code of
the file runs) into a module with the same two functions; a ``.toml`` file is a plan
(``bt_arrange.plans``), likewise. A name without a folder or suffix that is not a file is one of
the examples shipped in the package (``bt_arrange.examples``: ``bt-arrange run six_in_a_row``).
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import py_trees

from bt_arrange.errors import BtArrangeError, TreeFileError
from bt_arrange.filelimits import check_tree_size
from bt_arrange.suggest import nearest

#: What a tree file may be; and how many files of its folder are looked at for a suggestion.
TREE_SUFFIXES = (".py", ".xml", ".toml")
MAX_LISTED = 1000

if TYPE_CHECKING:
    from bt_arrange.backends import Backend


def load(path: str | Path) -> ModuleType:
    """Import the tree file at ``path`` (a ``.py`` file), or read it (a BehaviorTree.CPP ``.xml`` file)."""
    path = Path(path)
    if not path.is_file():
        from bt_arrange import examples

        example = examples.path_of(str(path)) if path.name == str(path) and not path.suffix else None
        if example is None:
            raise TreeFileError(f"tree file {path} not found{_nearest_file(path)}")
        path = example
    if path.suffix == ".xml":
        from bt_arrange import xmltree

        return xmltree.load_module(path)
    if path.suffix == ".toml":
        from bt_arrange import plans

        return plans.load_module(path)
    if path.suffix != ".py":
        raise TreeFileError(
            f"tree file {path} is neither a Python file (.py), a BehaviorTree.CPP XML tree (.xml) nor a plan (.toml)"
        )
    spec = importlib.util.spec_from_file_location(f"bt_arrange_tree_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise TreeFileError(f"cannot load tree file {path}")
    module = importlib.util.module_from_spec(spec)
    folder = str(path.resolve().parent)
    sys.path.insert(0, folder)
    try:
        spec.loader.exec_module(module)
    except BtArrangeError as error:
        raise TreeFileError(f"{path}: {error}") from error
    except SyntaxError as error:
        message = f"cannot load tree file {path}: syntax error at line {error.lineno}: {error.msg}"
        raise TreeFileError(message) from error
    except Exception as error:  # a user's file may raise anything while it loads
        raise TreeFileError(f"cannot load tree file {path}: {type(error).__name__}: {error}") from error
    finally:
        sys.path.remove(folder)
    return module


def _nearest_file(path: Path) -> str:
    """``; did you mean ...?`` for a missing tree file: the nearest file beside it, or the nearest example."""
    from bt_arrange import examples

    folder = path.parent
    near = ""
    if folder.is_dir():
        try:
            files = [p.name for p in sorted(folder.iterdir())[:MAX_LISTED] if p.suffix in TREE_SUFFIXES]
        except OSError:
            files = []
        found = nearest(path.name, files)
        if found:
            shown = str(folder / found[0]) if str(folder) != "." else found[0]
            near = f" (did you mean {shown!r}?)"
    if not near and (path.name == str(path) or not path.suffix):
        found = nearest(path.stem, examples.names())
        if found:
            near = f" (did you mean the example {found[0]!r}?)"
    return f"{near}: bt-arrange examples lists the examples, bt-arrange run NAME runs one"


def build_root(module: ModuleType, **options: Any) -> py_trees.behaviour.Behaviour:
    """Call the file's ``create_root`` with the options it accepts (``None`` values are left out)."""
    create_root = getattr(module, "create_root", None)
    where = getattr(module, "__file__", module.__name__)
    if not callable(create_root):
        raise TreeFileError(f"tree file {where} defines no create_root() function")
    parameters = inspect.signature(create_root).parameters
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values())
    kwargs = {}
    for name, value in options.items():
        if value is None:
            continue
        if name not in parameters and not takes_any:
            raise TreeFileError(f"create_root() in {where} takes no {name} argument")
        kwargs[name] = value
    try:
        root = create_root(**kwargs)
    except BtArrangeError:
        raise
    except RecursionError as error:
        raise TreeFileError(f"create_root() in {where} failed: the tree nests too deep for Python") from error
    except Exception as error:
        raise TreeFileError(f"create_root() in {where} failed: {type(error).__name__}: {error}") from error
    if not isinstance(root, py_trees.behaviour.Behaviour):
        raise TreeFileError(f"create_root() in {where} returned {type(root).__name__}, not a py_trees behaviour")
    check_tree_size(root, f"create_root() in {where}")
    return root


def scene(module: ModuleType, seed: int, backend: Backend | None = None) -> list[Any]:
    """The file's ``create_scene(seed)``: where the parts start in the simulator.

    A ``create_scene`` that takes a ``backend`` (plan and XML files: they scatter their parts
    through it) is handed the run's; without one, such a file asks the default backend. A backend
    that does not put parts into its world (a real cell: not a ``ScatteringBackend``) needs no scene:
    its parts lie where they lie, the file's ``create_scene`` is not called (a file need not have one),
    and the scene is empty.
    """
    from bt_arrange.backends import ScatteringBackend

    if backend is not None and not isinstance(backend, ScatteringBackend):
        return []
    create_scene = getattr(module, "create_scene", None)
    where = getattr(module, "__file__", module.__name__)
    if not callable(create_scene):
        raise TreeFileError(
            f"tree file {where} defines no create_scene(seed): the simulator needs to know where the parts start"
        )
    options: dict[str, Any] = {}
    if backend is not None and _takes(create_scene, "backend"):
        options["backend"] = backend
    try:
        return list(create_scene(seed, **options))
    except BtArrangeError:
        raise
    except Exception as error:
        raise TreeFileError(f"create_scene() in {where} failed: {type(error).__name__}: {error}") from error


def _takes(function: Any, name: str) -> bool:
    """True when ``function`` accepts a keyword argument ``name``."""
    try:
        parameters = inspect.signature(function).parameters
    except (TypeError, ValueError):
        return False
    return name in parameters or any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values())
