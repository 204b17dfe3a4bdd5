"""Helpers shared by the scene tests (``tests/test_scenes*.py``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import symrb
from symrb.scenes import SceneError, load_scene, plan_scene


def same(a: Any, b: Any) -> None:
    """Equal bit for bit, with the same shape and dtype."""
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b), strict=True)


def problems(source: Any, match: str | None = None) -> list[dict[str, Any]]:
    """The problems of the SceneError that reading (a TOML text) and planning, or planning (a
    mapping or a model), raises; the error is a symrb.InputError as well."""
    with pytest.raises(SceneError, match=match) as info:
        plan_scene(load_scene(source) if isinstance(source, str) else source)
    assert isinstance(info.value, symrb.InputError)
    return info.value.problems


def problem(source: Any, match: str | None = None) -> dict[str, Any]:
    """The one problem of :func:`problems`."""
    found = problems(source, match)
    assert len(found) == 1, found
    return found[0]
