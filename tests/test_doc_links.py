"""Every relative link in the README and docs/ points at a file (and a heading or <a id> anchor) in the repository."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def _anchor(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_relative_links_resolve(page):
    broken = []
    for target in LINK.findall(page.read_text(encoding="utf-8")):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve()
        if not resolved.exists():
            broken.append(target)
        elif anchor and resolved.suffix == ".md":
            text = resolved.read_text(encoding="utf-8")
            headings = {_anchor(h) for h in re.findall(r"^#+ (.+)$", text, re.M)}
            named = set(re.findall(r'<a id="([^"]+)"></a>', text))  # explicit anchors, e.g. <a id="ch7"></a>
            if anchor not in headings | named:
                broken.append(target)
    assert broken == [], f"{page.name}: broken links {broken}"
