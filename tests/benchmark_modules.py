"""Load a script of benchmarks/ as a module (the benchmarks are scripts, not a package)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]


def load_benchmark(file_name: str, module_name: str | None = None) -> ModuleType:
    """``benchmarks/<file_name>`` imported as ``module_name`` (default: the stem), registered in ``sys.modules``."""
    name = module_name or Path(file_name).stem
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / file_name)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
