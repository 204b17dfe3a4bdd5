"""Shared pytest configuration: fixed seeds and one BLAS thread for reproducible numerics."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

settings.register_profile("symrb", deadline=None, max_examples=40, derandomize=True)
settings.load_profile("symrb")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240208)
