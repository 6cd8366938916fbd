"""``smartllm-local view``: a run folder as one HTML page that opens in any browser, offline."""

from __future__ import annotations

import sys
import webbrowser
from pathlib import Path

import typer

from .options import given_path


def view(
    run: Path = typer.Argument(..., help="A run folder: the --out of `benchmark run`, or of `plan`."),
    out: Path | None = typer.Option(None, "--out", parser=given_path, metavar="FILE", help=(
        "Where to write the page (default: RUN/viewer.html).")),
    open_page: bool = typer.Option(False, "--open", help="Also open the page in the default browser."),
) -> None:
    """Write a run's viewer: one self-contained HTML file (no server, no network) with the run's summary, its
    tasks (filterable) and, per task, why it failed, its stages, its plan, a timeline and a map."""
    from ..report.viewer import write_viewer

    written = write_viewer(run, out)
    typer.echo(str(written))
    if open_page and not webbrowser.open(written.resolve().as_uri()):
        print("notice: no browser to open it with here; open the file above in one", file=sys.stderr)
