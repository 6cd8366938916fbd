#!/usr/bin/env python
"""Screenshots of the run viewer's two views for the docs, taken in Debian's chromium (headless, through
Playwright: ``pip install '.[viewer-test]'``, ``apt-get install chromium``).

Usage::

    python scripts/viewer_screenshots.py RUN_DIR TASK [--out docs/images]

writes ``viewer-run.png`` (the run: summary and task list) and ``viewer-task.png`` (the task: why it failed,
team, goals, map and timeline, with the bar of ``--action`` chosen), from ``RUN_DIR``'s page (written first).
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from playwright.sync_api import sync_playwright

from smartllm_local.report.viewer import write_viewer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("task")
    parser.add_argument("--out", type=Path, default=Path("docs/images"))
    parser.add_argument("--action", type=int, default=2, help="the timeline bar to choose (its index)")
    args = parser.parse_args()
    page_path = write_viewer(args.run, args.run / "viewer.html")
    args.out.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=shutil.which("chromium"), args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        page.goto(page_path.as_uri())
        page.wait_for_selector("#task-table tbody tr")
        page.screenshot(path=str(args.out / "viewer-run.png"), full_page=True)
        page.goto(f"{page_path.as_uri()}#task/{args.task}")
        page.wait_for_selector("#task-view")
        bars = page.locator("#timeline .bar")
        if bars.count() > args.action:
            bars.nth(args.action).locator("rect").first.click()
        page.evaluate("window.scrollTo(0, 0)")
        height = page.evaluate("document.getElementById('action-detail').getBoundingClientRect().bottom + 60")
        page.screenshot(path=str(args.out / "viewer-task.png"), full_page=True,
                        clip={"x": 0, "y": 0, "width": 1280, "height": height})
        browser.close()
    print(f"wrote {args.out / 'viewer-run.png'}, {args.out / 'viewer-task.png'}")


if __name__ == "__main__":
    main()
