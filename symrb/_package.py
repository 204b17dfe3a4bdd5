"""What a subpackage's ``__init__`` shares: the public classes name the package as their home."""

from __future__ import annotations

from collections.abc import Iterable, MutableMapping
from typing import Any


def adopt_classes(namespace: MutableMapping[str, Any], names: Iterable[str], package: str) -> None:
    """Set ``__module__`` of every public class of ``package`` defined in one of its submodules to
    ``package`` itself, so reprs, tracebacks, the API reference and pickles (sent to Dask workers)
    name ``symrb.scenes.Plan``, not ``symrb.scenes.plan.Plan``."""
    for name in names:
        obj = namespace[name]
        if isinstance(obj, type) and obj.__module__.startswith(f"{package}."):
            obj.__module__ = package
