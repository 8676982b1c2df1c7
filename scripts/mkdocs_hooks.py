"""MkDocs hooks of the documentation site (mkdocs.yml): the home page and the API reference, generated.

- ``index.md`` is README.md, its links to ``docs/...`` made relative to the site (the README links into
  docs/ from the repository root; the site's pages are docs/ itself).
- ``api/NAME.md``, one page per public module of ``bt_arrange`` and ``bt_arrange_sim`` (every module
  whose dotted name has no part starting with ``_``), each the module's docstring and its public
  members by mkdocstrings, and ``api/index.md``, the list of them. The modules are found on disk, so
  a new module gets its page and its place in the navigation without an edit here.

Nothing here is imported by the package or the tests; MkDocs loads it by path (``hooks:``).
"""

from __future__ import annotations

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


def _module_page(name: str) -> str:
    return f"::: {name}\n"


def _api_index(modules: dict[str, list[str]]) -> str:
    lines = [
        "# API reference",
        "",
        "Generated from the docstrings of every public module: `bt_arrange`, the framework, and",
        "`bt_arrange_sim`, the simulated cell and its two engines (the backends `SimBackend` and",
        "`MujocoBackend`). The guides beside it say how the pieces fit together.",
        "",
    ]
    for package, names in modules.items():
        lines += [f"## `{package}`", ""]
        lines += [f"- [`{name}`]({name}.md)" for name in names]
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
    files.append(File.generated(config, "api/index.md", content=_api_index(modules)))
    for names in modules.values():
        for name in names:
            files.append(File.generated(config, f"api/{name}.md", content=_module_page(name)))
    return files
