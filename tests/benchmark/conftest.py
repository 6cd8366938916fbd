"""Fixtures for the benchmark tests: the project's task files, loaded once."""

from __future__ import annotations

import pytest

from smartllm_local.robots import load_catalogue
from smartllm_local.tasks import load_tasks


@pytest.fixture(scope="session")
def catalogue():
    return load_catalogue()


@pytest.fixture(scope="session")
def all_tasks(catalogue):
    return load_tasks(catalogue=catalogue)


@pytest.fixture(scope="session")
def feasible(all_tasks):
    return [t for t in all_tasks if t.feasible]


@pytest.fixture(scope="session")
def infeasible(all_tasks):
    return [t for t in all_tasks if not t.feasible]
