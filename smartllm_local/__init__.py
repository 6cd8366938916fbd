"""smartllm-local: SMART-LLM's multi-robot task planning on local models, executed in AI2-THOR."""

__version__ = "0.1.0"
