"""Shared test helpers: where the repository and the shared folder are."""

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
BLADEX = SHARED / "data" / "bladex-test-blade"
CHECKS = SHARED / "checks"


@pytest.fixture(scope="session")
def bladex_dir() -> Path:
    if not (BLADEX / "upper.stl").is_file():
        pytest.skip("shared BladeX data not present")
    return BLADEX
