"""What the planner knows of where a task happens: its object types, their masses and affordances (or a site's
entries).

Prompts list the types (with the heaviest instance's mass) and grammars only admit, for each skill argument,
the types that offer what the skill needs. A world builds its scenes (:meth:`.worlds.World.scene`); this
module sits below both the prompts and the constraints, so each reads a scene without importing the other.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .domain import Domain

if TYPE_CHECKING:  # the worlds build scenes, so they import this module
    from .worlds import World

AFFORDANCE_NAMES = ("pickupable", "receptacle", "openable", "toggleable", "sliceable", "breakable", "dirtyable",
                    "movable")


@dataclass(frozen=True)
class SceneObjects:
    floor_plan: str
    masses: dict[str, float]  # type -> heaviest instance (kg)
    by_affordance: dict[str, tuple[str, ...]]  # affordance ("" = any) -> types, sorted
    world: World = field(compare=False, repr=False)  # the world it is a scene of (its dry runs, its examples' scenes)
    site: Domain | None = None  # a site domain's: its entries are the objects

    @property
    def types(self) -> tuple[str, ...]:
        return self.by_affordance[""]

    def types_for(self, affordance: str) -> tuple[str, ...]:
        return self.by_affordance.get(affordance, ())

    def python_list(self, only: Iterable[str] | None = None) -> str:
        """The objects as a Python list of dicts, as the prompts show them."""
        chosen = self.types if only is None else [t for t in self.types if t in set(only)]
        items = ", ".join(self._describe(t) for t in chosen)
        return f"[{items}]"

    def _describe(self, name: str) -> str:
        if self.site is None:
            return f"{{'name': '{name}', 'mass': {self.masses[name]:g}}}"
        place = self.site.places[name]
        area = f", 'area': {place.area:g}" if place.kind == "region" else ""
        reach = f", 'reach': {sorted(place.reach)!r}" if place.reach is not None else ""
        return f"{{'name': '{name}', 'kind': '{place.kind}'{area}{reach}}}"
