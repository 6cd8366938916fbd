"""The ``smartllm-local`` command: a thin layer over the library's functions.

Each command parses its options and calls one plain function. Problems the
user can fix (:class:`~smartllm_local.errors.UserError`) are printed as one
message without a traceback and exit with status 2; failures of a part (the
AI2-THOR process, a model) exit with status 1.
"""

from __future__ import annotations

import importlib
import sys

import typer

from ..errors import SmartLLMError, UserError
from . import benchmark as _benchmark
from . import dispatch as _dispatch
from . import domains as _domains
from . import execute as _execute
from . import plan as _plan
from . import scenes as _scenes
from . import speed as _speed
from . import validate as _validate
from . import view as _view

app = typer.Typer(
    help="Offline multi-robot task planning (SMART-LLM) on local models, executed in AI2-THOR.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
app.add_typer(_scenes.app, name="scenes")
app.add_typer(_benchmark.app, name="benchmark")
app.add_typer(_domains.app, name="domain")
app.command("plan")(_plan.plan_command)
app.command("validate")(_validate.validate)
app.command("execute")(_execute.execute)
app.command("dispatch")(_dispatch.dispatch)
app.command("bench")(_speed.bench_command)
app.command("view")(_view.view)


# Typer may bundle its own copy of click: take the exception classes from wherever it raises them.
_click_exceptions = importlib.import_module(typer.BadParameter.__module__)
_UsageError = _click_exceptions.UsageError
_ClickException = _click_exceptions.ClickException
_NoArgsIsHelpError = getattr(_click_exceptions, "NoArgsIsHelpError", None)


def usage_error_line(exc: Exception) -> str:
    """A click usage error (bad value, unknown option, missing argument) as one ``error: ...`` line,
    with the command's usage and where to get help."""
    message = " ".join(exc.format_message().split())  # type: ignore[attr-defined]
    ctx = getattr(exc, "ctx", None)
    if ctx is None:
        return f"error: {message}"
    usage = " ".join(ctx.get_usage().split())
    if usage.lower().startswith("usage:"):
        usage = usage[len("usage:"):].strip()
    return f"error: {message} (usage: {usage}; see '{ctx.command_path} --help')"


def main() -> None:
    """Console entry point."""
    try:
        # standalone_mode=False: click's usage errors come here instead of being printed in a box.
        code = app(standalone_mode=False)
    except UserError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    except SmartLLMError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(1)
    except _UsageError as exc:
        if _NoArgsIsHelpError is not None and isinstance(exc, _NoArgsIsHelpError):
            sys.exit(exc.exit_code)  # a group run without a command: its help is already printed
        print(usage_error_line(exc), file=sys.stderr)
        sys.exit(2)
    except _ClickException as exc:
        print(f"error: {' '.join(exc.format_message().split())}", file=sys.stderr)
        sys.exit(exc.exit_code)
    except typer.Abort:
        print("Aborted.", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
    # typer.Exit(n), --help (0) and Ctrl-C inside a command (130) come back as an exit code.
    sys.exit(code if isinstance(code, int) and not isinstance(code, bool) else 0)
