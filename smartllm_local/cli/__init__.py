"""The ``smartllm-local`` command: a thin layer over the library's functions.

Each command parses its options and calls one plain function. Problems the
user can fix (:class:`~smartllm_local.errors.UserError`) are printed as one
message without a traceback and exit with status 2; failures of a part (the
AI2-THOR process, a model) exit with status 1.
"""

from __future__ import annotations

import sys

import typer

from ..errors import SmartLLMError, UserError
from . import benchmark as _benchmark
from . import plan as _plan
from . import plans as _plans
from . import scenes as _scenes

app = typer.Typer(
    help="Offline multi-robot task planning (SMART-LLM) on local models, executed in AI2-THOR.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
app.add_typer(_scenes.app, name="scenes")
app.add_typer(_benchmark.app, name="benchmark")
_benchmark.app.command("run")(_plan.benchmark_run)
app.command("plan")(_plan.plan_command)
app.command("validate")(_plans.validate)
app.command("execute")(_plans.execute)


def main() -> None:
    """Console entry point."""
    try:
        app()
    except UserError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    except SmartLLMError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
