"""Fixtures for the benchmark tests: the feasible and infeasible tasks (the task files and the real runs they
share with the report's tests are in tests/conftest.py)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def feasible(all_tasks):
    return [t for t in all_tasks if t.feasible]


@pytest.fixture(scope="session")
def infeasible(all_tasks):
    return [t for t in all_tasks if not t.feasible]
