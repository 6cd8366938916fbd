"""The planner: SMART-LLM's stages (decomposition, coalition, allocation) on a local model.

Its rooms: :mod:`.prompting` (what the model is shown), :mod:`.decoding` (grammars and the line
protocol that write a stage under its constraint), :mod:`.constraints` (what each stage may say
next), :mod:`.backends` (the models: llama.cpp, transformers, servers). :mod:`.stages` runs one stage,
:mod:`.pipeline` holds the stages SMART-LLM runs (``Planner.steps``), :mod:`.steps` is the one loop that
takes a task from one stage to the next, and :mod:`.result` what each stage leaves, by its name.
"""

from .backends.cores import share_cores

share_cores()  # before llama.cpp or torch is loaded by anything below: OpenMP reads its wait policy then

from .pipeline import Planner, PlannerConfig  # noqa: E402
from .result import PlanResult  # noqa: E402

__all__ = ["Planner", "PlannerConfig", "PlanResult"]
