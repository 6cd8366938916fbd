"""The planner: SMART-LLM's stages (decomposition, coalition, allocation) on a local model.

Its rooms: :mod:`.prompting` (what the model is shown), :mod:`.decoding` (grammars and the line
protocol that write a stage under its constraint), :mod:`.constraints` (what each stage may say
next), :mod:`.backends` (the models: llama.cpp, transformers, servers). :mod:`.pipeline` takes a
task through the stages, :mod:`.stages` runs one.
"""

from .pipeline import Planner, PlannerConfig, PlanResult

__all__ = ["Planner", "PlannerConfig", "PlanResult"]
