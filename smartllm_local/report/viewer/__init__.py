"""The run viewer: a run folder (a benchmark run, or a ``plan --out``) as one self-contained HTML page.

It shows what the files hold, for a person to look at rather than read: the run's summary, a task list
filterable by category and outcome, and per task its stages, its plan, a timeline of the executed
actions (a lane per robot) and a top-down map of the robots' paths. The page's script and style are
this package's own (``assets/``), inlined: it opens from disk with no network.
"""

from .data import load_view
from .page import render_page, write_viewer

__all__ = ["load_view", "render_page", "write_viewer"]
