"""GoToObject puts each member on the nearest cell to the target that no agent and no earlier member takes."""

from __future__ import annotations

from random import Random

import pytest

from smartllm_local.executor.dry_run import DryRun
from smartllm_local.world.navigation import Box

from .helpers import CATALOGUE


def _nearest_free(cells, box: Box, taken) -> tuple[float, float]:
    """The rule, written as a scan of every cell."""
    return min((c for c in cells if c not in taken), key=lambda c: (round(box.distance(*c), 6), c))


@pytest.mark.parametrize("floor_plan", [6, 212])
@pytest.mark.parametrize("members", [[0], [0, 1, 2], [2, 0]])
def test_members_go_to_the_nearest_free_cells(floor_plan, members):
    """Calls chained from wherever the previous one left the team, targets repeating, an agent left out."""
    dry = DryRun(floor_plan, CATALOGUE.team([1, 2, 3]), CATALOGUE.skills)
    world = dry._world
    types = sorted({o["objectType"] for o in dry.objects})
    for name in Random(floor_plan).choices(types, k=60):
        before = [world.position(i) for i in range(3)]
        outcome = dry.apply(members, "GoToObject", [name])
        assert outcome.success, (name, outcome.error)
        box = Box.of(next(o for o in dry.objects if o["objectId"] == outcome.object_id))
        now = list(before)
        for member in members:
            expected = _nearest_free(world.cells, box, {p for i, p in enumerate(now) if i != member})
            assert world.position(member) == expected, (name, member)
            now[member] = expected
