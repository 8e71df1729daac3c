"""The README stays a page a newcomer reads (issue 26, item 7), and its links lead somewhere.

The reference lives next to what it describes (sessions/, procedures/, station/...); the top
README points to it. A link to a file that moved or a heading that was renamed fails here.
"""

from __future__ import annotations

import re
import unicodedata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
README_LIMIT = 15_000
"""Bytes: "at most 15 KB" read strictly."""

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)


def _documents() -> list[Path]:
    """Every Markdown file of the repository's own: none under a dot folder (.venv, .git,
    .pytest_cache)."""
    return sorted(
        p
        for p in ROOT.rglob("*.md")
        if not any(part.startswith(".") for part in p.relative_to(ROOT).parts)
    )


def _slug(heading: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = heading.strip().lower().replace("`", "")
    kept = "".join(c for c in text if c in " -_" or unicodedata.category(c)[0] in ("L", "N"))
    return kept.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6} +(.+?) *#*$", text, re.M)}


def _links(path: Path) -> list[str]:
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    return [m.group(1) for m in LINK.finditer(text)]


def test_the_readme_is_at_most_15_kb():
    size = len(README.read_bytes())
    assert size <= README_LIMIT, (
        f"README.md is {size} bytes (at most {README_LIMIT}): move reference text next to what "
        "it describes (sessions/README.md, procedures/README.md, station/**/README.md)"
    )


def test_the_readme_keeps_its_two_commands():
    """Start here: install and demo, then the test command CI runs (see test_architecture)."""
    text = README.read_text(encoding="utf-8")
    assert (
        "python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && .venv/bin/station demo\n"
        in text
    )
    assert ".venv/bin/python -m pytest\n" in text


@pytest.mark.parametrize("document", _documents(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_leads_to_a_file_and_heading_that_exist(document: Path):
    broken = []
    for target in _links(document):
        if re.match(r"[a-z]+:", target):  # https:, mailto: ...
            continue
        file_part, _, anchor = target.partition("#")
        linked = (document.parent / file_part).resolve() if file_part else document
        if not linked.exists():
            broken.append(f"{target}: no such file")
        elif anchor and linked.suffix == ".md" and anchor not in _anchors(linked):
            broken.append(f"{target}: no heading #{anchor} in {linked.relative_to(ROOT)}")
    assert not broken, broken


def test_the_readme_links_to_the_reference():
    """Each reference page is reachable from the README."""
    links = {t.partition("#")[0] for t in _links(README)}
    for page in (
        "sessions/README.md",
        "procedures/README.md",
        "station/README.md",
        "station/analysis/README.md",
        "station/instruments/README.md",
        "station/tui/README.md",
    ):
        assert page in links, page
