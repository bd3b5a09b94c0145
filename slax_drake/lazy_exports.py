"""Package re-exports that import their submodule on first use (PEP 562 module ``__getattr__``).

``from slax_drake.scene import sample_scene`` keeps working, but importing ``slax_drake.scene.commands`` (which
the command-line parser does for every command) does not drag in trimesh, torch or Drake through the package's
``__init__``: ``slax-drake --help`` answers without them.
"""

from __future__ import annotations

import importlib
import sys


def lazy_exports(package: str, exports: dict[str, str]):
    """``(__getattr__, __dir__)`` for the ``__init__`` of ``package``: the name ``exports`` maps to a submodule
    (``{"sample_scene": "sampling"}``) is imported from ``package.submodule`` when first asked for."""

    def __getattr__(name: str):
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{exports[name]}"), name)

    def __dir__() -> list[str]:
        return sorted(set(exports) | set(vars(sys.modules[package])))

    return __getattr__, __dir__
