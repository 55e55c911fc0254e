"""Lazy package exports: a name is imported from its module on first use.

The command line starts in well under a second because ``import satagraph``
(and its subpackages) no longer import torch, PyG or Lightning up front; the
heavy modules load when one of their names is first looked up.
"""
from __future__ import annotations

import importlib
from typing import Any, Callable, Dict, List, Tuple


def lazy_exports(package: str, exports: Dict[str, str]
                 ) -> Tuple[Callable[[str], Any], Callable[[], List[str]]]:
    """Module-level ``__getattr__`` and ``__dir__`` of a package whose public
    names live in submodules (PEP 562).

    Args:
        package (str): The package's ``__name__``.
        exports (dict[str, str]): Public name -> the module defining it.

    Example::

        __getattr__, __dir__ = lazy_exports(__name__, {
            "read_bvh": "satagraph.io.bvh_reader"})
    """
    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(importlib.import_module(package), name, value)  # next time: direct
        return value

    def __dir__() -> List[str]:
        return sorted(set(exports) | set(vars(importlib.import_module(package))))

    return __getattr__, __dir__
