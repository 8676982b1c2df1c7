"""MkDocs hooks of the documentation site (mkdocs.yml): the home page and the API reference, generated.

- ``index.md`` is README.md, its links to ``docs/...`` made relative to the site (the README links into
  docs/ from the repository root; the site's pages are docs/ itself).
- ``api/NAME.md``, one page per public module of ``bt_arrange`` and ``bt_arrange_sim`` (every module
  whose dotted name has no part starting with ``_``), each the module's docstring and its public
  members by mkdocstrings, and ``api/index.md``, the list of them. The modules are found on disk, so
  a new module gets its page and its place in the navigation without an edit here.

- Lists nested by two spaces, as GitHub reads them, are nested by four for Python-Markdown (which
  would otherwise flatten them): ``nest_lists_by_four``, on every page.

Nothing here is imported by the package; MkDocs loads it by path (``hooks:``).
"""

from __future__ import annotations

import functools
import importlib.util
import re
from pathlib import Path
from typing import Any

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
#: Import name and folder of each package documented (bt_arrange_sim is installed from sim/).
PACKAGES = (("bt_arrange", ROOT / "bt_arrange"), ("bt_arrange_sim", ROOT / "sim"))


def public_modules() -> dict[str, list[str]]:
    """Every public module by package, packages first in each folder, in a stable (sorted) order."""
    found: dict[str, list[str]] = {}
    for package, folder in PACKAGES:
        names = []
        for path in folder.rglob("*.py"):
            parts = [package, *path.relative_to(folder).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts.pop()
            if not any(part.startswith("_") for part in parts):
                names.append(".".join(parts))
        found[package] = sorted(names)
    return found


@functools.cache
def _docstring_markdown() -> Any:
    """``scripts/griffe_docstrings.py`` (what the API pages render the docstrings with), loaded by path."""
    spec = importlib.util.spec_from_file_location("griffe_docstrings", ROOT / "scripts" / "griffe_docstrings.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _first_line(obj: Any) -> str:
    """The summary line of ``obj``'s docstring, as Markdown."""
    docstring = obj.docstring.value if obj.docstring is not None else ""
    return str(_docstring_markdown().to_markdown(docstring.strip().split("\n")[0].strip()))


def _module_page(name: str, modules: list[str], packages: dict[str, Any]) -> str:
    """A module's page: mkdocstrings' rendering; for a package, its modules and the names it exports.

    A package that declares ``__all__`` re-exports names of its modules: its page lists them, each a
    link to the page of the module that defines it, instead of documenting each object twice.
    """
    package = packages.get(name)
    if package is None or not package.is_init_module:
        return f"::: {name}\n"
    exports = sorted(package.exports or [])
    lines = [f"::: {name}", "    options:", f"      members: {'false' if exports else 'true'}", ""]
    children = [m for m in modules if m.rpartition(".")[0] == name]
    if children:
        lines += ["## Modules", ""]
        lines += [f"- [`{child}`]({child}.md): {_first_line(package[child.rpartition('.')[2]])}" for child in children]
        lines.append("")
    if exports:
        lines += [f"## Exported names (`from {name} import ...`)", ""]
        for export in exports:
            member = package.members.get(export)
            target = member.final_target if member is not None and member.is_alias else member
            path = target.path if target is not None else ""
            if path.startswith(tuple(packages)) and not any(part.startswith("_") for part in path.split(".")):
                lines.append(f"- [`{export}`][{path}]: {_first_line(target)}")
            else:
                lines.append(f"- `{export}`")
        lines.append("")
    return "\n".join(lines)


def _load_packages() -> dict[str, Any]:
    """Every public package of ours as griffe reads it (statically), by dotted name."""
    import sys

    import griffe

    found: dict[str, Any] = {}
    for package, _ in PACKAGES:
        top = griffe.load(package, search_paths=[str(ROOT), *sys.path], resolve_aliases=True, resolve_external=False)
        pending = [top]
        while pending:
            module = pending.pop()
            found[module.path] = module
            pending += module.modules.values()
    return found


def _api_index(modules: dict[str, list[str]], packages: dict[str, Any]) -> str:
    lines = [
        "# API reference",
        "",
        "Generated from the docstrings of every public module: `bt_arrange`, the framework, and",
        "`bt_arrange_sim`, the simulated cell and its two engines (the backends",
        "[`SimBackend`][bt_arrange_sim.pybullet.backend.SimBackend] and",
        "[`MujocoBackend`][bt_arrange_sim.mujoco.backend.MujocoBackend]). The guides beside it say how the",
        "pieces fit together.",
        "",
    ]
    for package, names in modules.items():
        lines += [f"## `{package}`", ""]
        for name in names:
            summary = _first_line(packages[name]) if name in packages else ""
            lines.append(f"- [`{name}`]({name}.md)" + (f": {summary}" if summary else ""))
        lines.append("")
    return "\n".join(lines)


def readme_as_home(text: str) -> str:
    """README.md with its links into docs/ made relative to docs/ (the site's root)."""
    return re.sub(r"\]\(docs/", "](", text)


def _nav_tree(names: list[str]) -> list[Any]:
    """The navigation of one package: a module as a page, a package as a section with its own page first."""
    root = names[0]
    children: dict[str, list[str]] = {}
    for name in names[1:]:
        child = ".".join(name.split(".")[: root.count(".") + 2])
        children.setdefault(child, []).append(name)
    entries: list[Any] = [{root: f"api/{root}.md"}]
    for child, members in children.items():
        if len(members) == 1:
            entries.append({child.rpartition(".")[2]: f"api/{child}.md"})
        else:
            entries.append({child.rpartition(".")[2]: _nav_tree(members)})
    return entries


LIST_ITEM = re.compile(r"^( *)((?:[-*+]|\d+[.)]) +)(?=\S)")
BLOCK_START = re.compile(r"^ *(?:[-*+] |\d+[.)] |#|```|~~~|\||>)")


def nest_lists_by_four(markdown: str) -> str:
    """Markdown whose lists are indented as GitHub reads them, re-indented as Python-Markdown reads them.

    GitHub (CommonMark) takes what is indented to a list item's text (2 spaces after ``- ``) as part of
    the item: a wrapped line, a nested list, a table or a paragraph after a blank line. Python-Markdown
    wants 4 spaces per level and would flatten the nested lists and end the items. Each line inside an
    item moves from the item's text column to 4 spaces past its marker, at every level; fenced blocks
    move with their item; a line that continues a paragraph without indent stays as it is.
    """
    out: list[str] = []
    stack: list[tuple[int, int]] = []  # per open item: its text column as written, and as rewritten
    fence, fence_shift, previous_blank = "", 0, True
    for line in markdown.split("\n"):
        stripped = line.lstrip(" ")
        indent = len(line) - len(stripped)
        if fence:
            out.append(" " * fence_shift + line if indent >= 0 and line.strip() else line)
            if stripped.startswith(fence):
                fence = ""
            continue
        if not stripped:
            out.append(line)
            previous_blank = True
            continue
        item = LIST_ITEM.match(line)
        lazy = not previous_blank and not BLOCK_START.match(line)
        while stack and indent < stack[-1][0] and not (lazy and not item):
            stack.pop()
        shift = stack[-1][1] - stack[-1][0] if stack else 0
        if stack and indent < stack[-1][0]:
            out.append(line)  # a lazy continuation line: Python-Markdown reads it as GitHub does
        else:
            out.append(" " * (indent + shift) + stripped)
        if item:
            new_marker = indent + shift
            stack.append((indent + len(item[2]), new_marker + 4))
        if stripped.startswith(("```", "~~~")):
            fence, fence_shift = stripped[:3], shift
        previous_blank = False
    return "\n".join(out)


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """Every page's lists nested as their writers meant (``nest_lists_by_four``)."""
    return nest_lists_by_four(markdown)


def on_config(config: MkDocsConfig) -> MkDocsConfig:
    """Add the API reference to the navigation, after the guides."""
    modules = public_modules()
    reference: list[Any] = [{"Overview": "api/index.md"}]
    reference += [{package: _nav_tree(names)} for package, names in modules.items()]
    config.nav = [*(config.nav or []), {"API reference": reference}]
    return config


def on_files(files: Files, config: MkDocsConfig) -> Files:
    """Generate the home page and one page per public module."""
    files.append(File.generated(config, "index.md", content=readme_as_home((ROOT / "README.md").read_text("utf-8"))))
    modules = public_modules()
    packages = _load_packages()
    files.append(File.generated(config, "api/index.md", content=_api_index(modules, packages)))
    for names in modules.values():
        for name in names:
            files.append(File.generated(config, f"api/{name}.md", content=_module_page(name, names, packages)))
    return files
