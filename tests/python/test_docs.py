"""The README and docs/: every relative link resolves, and the README starts with the two commands.

Links are Markdown links and images, ``[text](target)``, outside code; a target with an anchor
(``page.md#heading``) must name a heading of that page, slugged as GitHub does.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
CODE_SPAN = re.compile(r"`[^`\n]*`")


def prose(text: str) -> str:
    """The text without fenced code blocks and code spans."""
    return CODE_SPAN.sub("", FENCE.sub("", text))


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    seen: dict[str, int] = {}
    result = set()
    for line in FENCE.sub("", page.read_text(encoding="utf-8")).splitlines():
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        base = slug(m.group(1))
        n = seen.get(base, 0)
        seen[base] = n + 1
        result.add(base if n == 0 else f"{base}-{n}")
    return result


def relative_links(page: Path) -> list[str]:
    return [t for t in LINK.findall(prose(page.read_text(encoding="utf-8")))
            if not re.match(r"[a-z][a-z0-9+.-]*:", t)]


def test_pages_found():
    names = {p.name for p in PAGES}
    assert {"README.md", "architecture.md", "recombine.md", "benchmarks.md",
            "contributing.md", "mesher.md", "freecad.md"} <= names


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(page: Path):
    broken = []
    for target in relative_links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            broken.append(f"{target}: no file {dest}")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{target}: no heading #{anchor} in {dest.name}")
    assert not broken, f"{page.name}: " + "; ".join(broken)


def test_link_pattern_finds_links():
    # The checker itself: it sees links and images, and not what is inside code.
    text = ("See [a](x.md), ![img](y.png) and [b](https://e.org).\n"
            "`[c](z.md)`\n```\n[d](w.md)\n```\n")
    assert LINK.findall(prose(text)) == ["x.md", "y.png", "https://e.org"]
    assert slug("How much? (`bench/hex_ceiling.py`)") == "how-much-benchhex_ceilingpy"


def test_readme_starts_with_the_two_commands():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert lines[0] == "# HexMerge"
    assert lines[2] == "```sh"
    assert lines[3].startswith("bash scripts/example.sh ")
    assert lines[4].startswith("bash scripts/test.sh ")
    assert lines[5] == "```"
    assert "fresh Debian 12 machine" in " ".join(lines[6:10])


def test_readme_has_no_internal_references():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert not re.search(r"\bissues?\s*#?\d", text, re.I), "internal issue number in the README"
    hashes = [w for w in re.findall(r"\b[0-9a-f]{7,40}\b", text)
              if re.search(r"[a-f]", w) and re.search(r"\d", w)]
    assert not hashes, f"commit hashes in the README: {hashes}"
