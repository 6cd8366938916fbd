"""The documentation holds together: every relative link in the README, the changelog and docs/ reaches a file
(and, with an anchor, a heading of it, slugged as GitHub slugs headings), the README stays short, every docs page
is in the site's navigation, every docs path the code names exists, and the mkdocs site builds strictly."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent
DOCS = ROOT / "docs"
README_MAX_LINES = 250

FENCE = re.compile(r"^ {0,3}(```|~~~)")
HEADING = re.compile(r"^ {0,3}(#{1,6})[ \t]+(.*?)[ \t]*#*[ \t]*$")
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1")
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]*)>?(?:\s+[\"'(][^)]*)?\)")
REFERENCE_DEFINITION = re.compile(r"^ {0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$")
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def documents() -> list[Path]:
    return [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted(DOCS.glob("**/*.md"))]


def prose_lines(text: str, code_spans: bool = False) -> list[str]:
    """The lines outside fenced code blocks (blank inside them), with inline code spans blanked unless
    ``code_spans`` (links in code are not links; a heading's code is part of its text)."""
    lines, fenced = [], None
    for line in text.splitlines():
        fence = FENCE.match(line)
        if fence:
            if fenced is None:
                fenced = fence.group(1)
            elif fence.group(1) == fenced:
                fenced = None
            lines.append("")
            continue
        if fenced:
            lines.append("")
        else:
            lines.append(line if code_spans else CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line))
    return lines


def github_slug(heading: str) -> str:
    """GitHub's anchor for a heading: lowercase, punctuation other than '-' and '_' dropped, spaces to '-'."""
    return "".join(c for c in heading.strip().lower() if c.isalnum() or c in "-_ ").replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every anchor GitHub gives the headings of a Markdown file (a repeated slug gets -1, -2, …)."""
    seen: dict[str, int] = {}
    found = set()
    for line in prose_lines(path.read_text(encoding="utf-8"), code_spans=True):
        match = HEADING.match(line)
        if not match:
            continue
        slug = github_slug(match.group(2))
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        found.add(slug if count == 0 else f"{slug}-{count}")
    return found


def link_targets(path: Path) -> list[tuple[int, str]]:
    """(line number, target) of every link in a Markdown file, inline or by reference definition."""
    targets = []
    for number, line in enumerate(prose_lines(path.read_text(encoding="utf-8")), start=1):
        definition = REFERENCE_DEFINITION.match(line)
        if definition:
            targets.append((number, definition.group(1)))
            continue
        targets.extend((number, match.group(1)) for match in INLINE_LINK.finditer(line))
    return targets


def broken_links(path: Path) -> list[str]:
    """Every relative link of ``path`` whose file is missing, or whose anchor names no heading of its file."""
    problems = []
    for number, target in link_targets(path):
        if not target or SCHEME.match(target) or target.startswith("//"):
            continue
        file_part, _, anchor = target.partition("#")
        linked = (path.parent / file_part).resolve() if file_part else path
        where = f"{path.relative_to(ROOT)}:{number}: {target}"
        if not linked.exists():
            problems.append(f"{where}: no such file")
        elif anchor and linked.suffix == ".md" and anchor not in anchors(linked):
            problems.append(f"{where}: no heading of {linked.name} has the anchor #{anchor}")
    return problems


def test_the_link_checker_finds_broken_links_and_anchors(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "other.md").write_text(
        "# Other page\n\n## Why `outlines` is not a dependency\n\n## Twice\n\n## Twice\n")
    page = tmp_path / "page.md"
    page.write_text(
        "# Page\n\n[fine](other.md#why-outlines-is-not-a-dependency) [also](other.md#twice-1) [self](#page)\n"
        "[gone](missing.md) [bad anchor](other.md#why-outlines) [web](https://example.org/x.md)\n"
        "`[in code](missing.md)`\n```\n[in a block](missing.md)\n```\n[ref]: other.md#nowhere\n")
    assert broken_links(page) == [
        "page.md:4: missing.md: no such file",
        "page.md:4: other.md#why-outlines: no heading of other.md has the anchor #why-outlines",
        "page.md:9: other.md#nowhere: no heading of other.md has the anchor #nowhere",
    ]


def test_github_slugs():
    assert github_slug("Token sampling in the llama.cpp backend") == "token-sampling-in-the-llamacpp-backend"
    assert github_slug("Qwen2.5-Coder and the token-aligned grammar") == "qwen25-coder-and-the-token-aligned-grammar"
    assert github_slug("Peers' datasets") == "peers-datasets"
    assert github_slug("Set-up: two commands") == "set-up-two-commands"


@pytest.mark.parametrize("path", documents(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_reaches_a_file_and_heading(path):
    assert path.exists(), f"{path.relative_to(ROOT)} is missing"
    assert not broken_links(path), "\n".join(broken_links(path))


def test_the_readme_is_short():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_MAX_LINES, (
        f"README.md has {len(lines)} lines (at most {README_MAX_LINES}): move detail to a page under docs/")


def test_every_docs_page_is_in_the_site_navigation():
    yaml = pytest.importorskip("yaml")  # PyYAML comes with mkdocs

    def pages(nav) -> list[str]:
        if isinstance(nav, str):
            return [nav]
        if isinstance(nav, dict):
            return [page for value in nav.values() for page in pages(value)]
        return [page for item in nav for page in pages(item)]

    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))
    assert config["docs_dir"] == "docs"
    listed = pages(config["nav"])
    assert len(listed) == len(set(listed)), listed
    assert sorted(listed) == sorted(str(p.relative_to(DOCS)) for p in DOCS.glob("**/*.md"))


def test_every_docs_page_the_code_names_exists():
    named = {
        (path.relative_to(ROOT), match.group(0))
        for folder in ("smartllm_local", "scripts", "tests", ".ci")
        for path in (ROOT / folder).rglob("*")
        if path.is_file() and path.suffix in {".py", ".sh", ""} and path.name != Path(__file__).name
        for match in re.finditer(r"\bdocs/[\w./-]+\.md\b", path.read_text(encoding="utf-8", errors="replace"))
    }
    missing = sorted(f"{path}: {page}" for path, page in named if not (ROOT / page).exists())
    assert not missing, "\n".join(missing)


def test_the_site_builds_strictly(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"), "-d", str(tmp_path)],
        capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.stdout + done.stderr)[-4000:]
    assert (tmp_path / "servers-and-gpus" / "index.html").exists()
