"""Names a package offers but loads on first use, so importing the package (or one of its
modules) stays light: `gait_planner` (the Python API), `gait_planner.io`, `gait_planner.viz`."""

from __future__ import annotations

import importlib
import sys
from typing import Any, Callable


def lazy_exports(package: str, exports: dict[str, str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """(__getattr__, __dir__) for `package`: a name of `exports` (name -> submodule) is
    looked up in `package`.<submodule>, imported then; any other name is an AttributeError."""
    def __getattr__(name: str) -> Any:
        if name in exports:
            return getattr(importlib.import_module(f"{package}.{exports[name]}"), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
