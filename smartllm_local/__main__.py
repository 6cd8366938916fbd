"""``python -m smartllm_local`` runs the CLI."""

from .cli import main

main()
