"""The world plans run in: AI2-THOR scenes, reached only through an ai2thor Controller.

Import heavy pieces from their modules; this package only re-exports the door.
"""

from .controller import open_controller
from .scenes import all_floor_plans, floor_plan_name, load_scene, scene_info

__all__ = ["open_controller", "all_floor_plans", "floor_plan_name", "load_scene", "scene_info"]
