"""Shared pytest configuration: fixed seeds, one BLAS thread, and the Hypothesis profiles.

Profiles (``--hypothesis-profile=NAME``; the plugin loads it after this file):

``ci`` (the default, and what CI runs)
    derandomised (the same examples on every run and machine), no example database, 40 examples
    per property (the property suite of tests/test_properties.py scales this per test, a few
    hundred examples per property in total, the whole suite in about 3 minutes on two cores).
``thorough``
    random, 25 times as many examples, the database kept under ``.hypothesis/`` so that a
    failure found once replays first on the next run; no per-test timeout.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import HealthCheck, settings  # noqa: E402
from hypothesis.database import DirectoryBasedExampleDatabase  # noqa: E402

_SLOW_OK = [HealthCheck.too_slow, HealthCheck.data_too_large]
settings.register_profile(
    "ci",
    deadline=None,
    max_examples=40,
    derandomize=True,
    database=None,
    print_blob=True,
    suppress_health_check=_SLOW_OK,
)
settings.register_profile("symrb", parent=settings.get_profile("ci"))  # the former name
settings.register_profile(
    "thorough",
    deadline=None,
    max_examples=1000,
    derandomize=False,
    database=DirectoryBasedExampleDatabase(".hypothesis/examples"),
    print_blob=True,
    suppress_health_check=_SLOW_OK,
)
settings.load_profile("ci")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240208)


def pytest_configure(config: pytest.Config) -> None:
    # the per-test timeout (pyproject's timeout = 900 s) guards CI against a hang; under the
    # thorough profile a property runs 25 times as many examples and may take longer than that
    # (the first thorough run saw the halving property cut off by it mid-example, which
    # Hypothesis then reported as a flaky failure)
    if config.getoption("hypothesis_profile", None) == "thorough" and hasattr(
        config.option, "timeout"
    ):
        config.option.timeout = 0
