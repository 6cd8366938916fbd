"""A classical planner for the household world and site domains: their rules as a planning domain, Fast
Downward's plans as threads.

:mod:`.model` writes the household world's rules (the executor's skills, the simulator's preconditions
and effects) as a Unified Planning problem for one team, scene and goal, and :mod:`.site` a site
domain's (from its domain file); :mod:`.search` runs Fast Downward on it; :mod:`.threads` turns the
plan it finds into sub-tasks and an allocated plan in the plan language. Unified Planning and Fast
Downward are the ``goal-planner`` extra: only this package imports them.
"""

from __future__ import annotations
