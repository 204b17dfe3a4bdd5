"""An optional progress bar (tqdm, imported only when a bar is asked for)."""

from __future__ import annotations

from types import TracebackType
from typing import Any

import numpy as np


class _Bar:
    """A tqdm bar updated in strides, or nothing when ``enabled`` is False.

    Long loops call :meth:`step` once per iteration; the bar is advanced every ``stride``
    iterations only, so a bar costs well under a microsecond per step.
    """

    def __init__(self, total: int, desc: str, enabled: bool, unit: str = "step") -> None:
        self.bar: Any = None
        self.pending = 0
        self.stride = max(1, total // 1000)
        if not enabled:
            return
        try:
            from tqdm import tqdm
        except ImportError:  # pragma: no cover - depends on the environment
            raise ImportError(
                "progress=True needs the optional package tqdm: pip install 'symrb[progress]' "
                "(or pip install tqdm)"
            ) from None
        # at most two refreshes a second: a long run in a log file stays a few lines
        self.bar = tqdm(total=total, desc=desc, unit=unit, leave=True, mininterval=0.5)

    def step(self) -> None:
        if self.bar is None:
            return
        self.pending += 1
        if self.pending >= self.stride:
            self.bar.update(self.pending)
            self.pending = 0

    def close(self) -> None:
        if self.bar is not None:
            if self.pending:
                self.bar.update(self.pending)
                self.pending = 0
            self.bar.close()

    def __enter__(self) -> _Bar:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


def progress_bar(total: int, desc: str, enabled: bool) -> _Bar:
    """A progress bar over ``total`` iterations when ``enabled`` (needs tqdm), else a no-op."""
    if not isinstance(enabled, bool | int | np.bool_):
        from .errors import InputError

        raise InputError(f"progress must be True or False, got {enabled!r}")
    return _Bar(int(total), desc, bool(enabled))
