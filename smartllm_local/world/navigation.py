"""Where agents can stand, and how far they are from things.

AI2-THOR answers ``GetReachablePositions`` with the floor grid cells an agent
fits on. The stand-in has no meshes, so it derives the grid from the scene's
bounding boxes: cells inside the Floor's footprint that no floor-standing,
non-pickupable object (counters' cabinets, the fridge, beds, tables...) covers.
Distances are horizontal, from the agent to the nearest point of an object's
axis-aligned bounding box, which is what decides whether it is in reach.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

AGENT_HEIGHT = 0.9009995460510254  # AI2-THOR's default agent position y above the floor
_AGENT_RADIUS = 0.15
_FLOOR_CLEARANCE = 0.4  # an object whose box starts this close to the floor blocks the cell


@dataclass(frozen=True)
class Box:
    """An axis-aligned bounding box in the horizontal plane, plus its vertical extent."""

    x0: float
    x1: float
    z0: float
    z1: float
    y0: float
    y1: float

    @classmethod
    def of(cls, obj: dict[str, Any]) -> Box:
        aabb = obj.get("axisAlignedBoundingBox") or {}
        center = aabb.get("center") or obj["position"]
        size = aabb.get("size") or {"x": 0.0, "y": 0.0, "z": 0.0}
        return cls(
            center["x"] - size["x"] / 2,
            center["x"] + size["x"] / 2,
            center["z"] - size["z"] / 2,
            center["z"] + size["z"] / 2,
            center["y"] - size["y"] / 2,
            center["y"] + size["y"] / 2,
        )

    def distance(self, x: float, z: float) -> float:
        """Horizontal distance from (x, z) to the nearest point of the box (0 inside)."""
        dx = max(self.x0 - x, 0.0, x - self.x1)
        dz = max(self.z0 - z, 0.0, z - self.z1)
        return math.hypot(dx, dz)

    def covers(self, x: float, z: float, margin: float) -> bool:
        return self.x0 - margin < x < self.x1 + margin and self.z0 - margin < z < self.z1 + margin


class ReachableGrid:
    """The cells agents can stand on, at AI2-THOR's default grid size."""

    def __init__(self, objects: Iterable[dict[str, Any]], grid_size: float = 0.25):
        objects = list(objects)
        floor = next((o for o in objects if o["objectType"] == "Floor"), None)
        if floor is None:
            raise ValueError("the scene has no Floor object")
        area = Box.of(floor)
        self.grid_size = grid_size
        self.y = round(area.y1 + AGENT_HEIGHT, 4)
        obstacles = [
            Box.of(o)
            for o in objects
            if o["objectType"] != "Floor"
            and not o.get("pickupable")
            and Box.of(o).y0 < area.y1 + _FLOOR_CLEARANCE
            and Box.of(o).y1 - Box.of(o).y0 > 0.05
        ]
        cells: list[tuple[float, float]] = []
        x = math.ceil(area.x0 / grid_size) * grid_size
        while x <= area.x1 + 1e-9:
            z = math.ceil(area.z0 / grid_size) * grid_size
            while z <= area.z1 + 1e-9:
                if not any(b.covers(x, z, _AGENT_RADIUS) for b in obstacles):
                    cells.append((round(x, 4), round(z, 4)))
                z += grid_size
            x += grid_size
        self.cells = cells
        self._index = set(cells)

    def positions(self) -> list[dict[str, float]]:
        """The cells as AI2-THOR reports them: dicts with x, y, z."""
        return [{"x": x, "y": self.y, "z": z} for x, z in self.cells]

    def snap(self, x: float, z: float, tolerance: float = 0.05) -> tuple[float, float] | None:
        """The grid cell at (x, z), if there is one within ``tolerance``."""
        g = self.grid_size
        cell = (round(round(x / g) * g, 4), round(round(z / g) * g, 4))
        if cell in self._index and abs(cell[0] - x) <= tolerance and abs(cell[1] - z) <= tolerance:
            return cell
        return None

    def nearest_cells(self, box: Box, count: int, taken: set[tuple[float, float]]) -> list[tuple[float, float]]:
        """The ``count`` free cells closest to ``box``, ties broken by position for determinism."""
        ranked = sorted(
            (c for c in self.cells if c not in taken),
            key=lambda c: (round(box.distance(*c), 6), c),
        )
        return ranked[:count]


def facing_yaw(from_x: float, from_z: float, to_x: float, to_z: float) -> float:
    """The yaw (degrees, AI2-THOR convention: 0 faces +z, 90 faces +x) looking from one point to another."""
    if math.isclose(from_x, to_x) and math.isclose(from_z, to_z):
        return 0.0
    return math.degrees(math.atan2(to_x - from_x, to_z - from_z)) % 360.0
