"""The planner: SMART-LLM's stages (decomposition, coalition, allocation) on a local model.

Its rooms: :mod:`.prompting` (what the model is shown), :mod:`.decoding` (grammars and the line
protocol that write a stage under its constraint), :mod:`.constraints` (what each stage may say
next), :mod:`.backends` (the models: llama.cpp, transformers, servers). :mod:`.pipeline` takes a
task through the stages, :mod:`.stages` runs one.
"""

from .backends.cores import share_cores

share_cores()  # before llama.cpp or torch is loaded by anything below: OpenMP reads its wait policy then

from .pipeline import Planner, PlannerConfig, PlanResult  # noqa: E402

__all__ = ["Planner", "PlannerConfig", "PlanResult"]
