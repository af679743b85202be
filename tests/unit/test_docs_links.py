"""Every relative link in the project's Markdown resolves.

The Markdown files of the repository root, ``docs/`` and ``examples/`` are parsed for inline
links and images, ``[text](path)``, ``[text](path#anchor)``, ``![alt](path)``, and for
reference definitions, ``[label]: path``. A link fails when its target does not exist in the
repository or, with an anchor into a Markdown file, when that file has no heading with the
anchor's GitHub-style slug. Links with a scheme (``http:``, ``https:``, ``mailto:``, ...) are
skipped; text inside fenced code blocks and inline code spans is not parsed. Moving or renaming
a file then fails here, naming each page and link that still points at the old place.
"""

from __future__ import annotations

import re
import unicodedata
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOC_DIRS = ("docs", "examples")  # searched recursively; the root's own *.md files too

_FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
_CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1", re.DOTALL)
# [text](target) and ![alt](target): one level of brackets in the text, one level of parentheses
# in the target, an optional "title" after it.
_INLINE_LINK = re.compile(
    r"!?\[(?:[^\[\]\\]|\\.|\[[^\[\]]*\])*\]"
    r"\(\s*(<[^<>\n]*>|(?:[^\s()\\]|\\.|\([^\s()]*\))*)"
    r"(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^()]*\)))?\s*\)"
)
_REF_DEF = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^<>\n]*>|\S+)", re.MULTILINE)
_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")
_ATX_HEADING = re.compile(r"^ {0,3}(#{1,6})(?:[ \t]+(.*?))?(?:[ \t]+#+)?[ \t]*$")
_SETEXT_UNDERLINE = re.compile(r"^ {0,3}(=+|-+)[ \t]*$")
_HTML_ID = re.compile(r"<[^>]*\b(?:id|name)\s*=\s*[\"']([^\"']+)[\"']", re.IGNORECASE)


def markdown_files(root: Path = ROOT) -> list[Path]:
    """The Markdown files the check covers: the root's, and those under docs/ and examples/."""
    files = sorted(root.glob("*.md"))
    for folder in DOC_DIRS:
        files += sorted((root / folder).rglob("*.md"))
    return files


def prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) for the lines outside fenced code blocks."""
    out: list[tuple[int, str]] = []
    fence: str | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        match = _FENCE.match(line)
        if fence is None:
            if match:
                fence = match.group(1)
                continue
            out.append((number, line))
        elif match and match.group(1)[0] == fence[0] and len(match.group(1)) >= len(fence) \
                and line.strip() == match.group(1):
            fence = None
    return out


def links(text: str) -> list[tuple[int, str]]:
    """(line number, target) of every inline link, image and reference definition."""
    lines = prose_lines(text)
    found: list[tuple[int, str]] = []
    # Paragraphs are joined so that a link whose text wraps over a line break is still seen;
    # each match is credited to the line it starts on.
    block: list[tuple[int, str]] = []
    for number, line in [*lines, (0, "")]:
        if line.strip():
            block.append((number, line))
            continue
        if block:
            joined, starts = "", []
            for n, piece in block:
                starts.append((len(joined), n))
                joined += piece + "\n"
            joined = _CODE_SPAN.sub(lambda m: " " * len(m.group(0)), joined)
            for pattern in (_INLINE_LINK, _REF_DEF):
                for match in pattern.finditer(joined):
                    line_no = max(n for offset, n in starts if offset <= match.start())
                    found.append((line_no, match.group(1)))
            block = []
    return found


def slug(heading: str) -> str:
    """GitHub's anchor for a heading's text (before the -1, -2 suffixes of repeated ones)."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML
    text = text.replace("`", "").strip().lower()
    kept = []
    for char in text:
        category = unicodedata.category(char)
        if char in " -_" or category[0] in "LMN" or category == "Pc":
            kept.append(char)
    return "".join(kept).replace(" ", "-")


def anchors(text: str) -> set[str]:
    """Every anchor a Markdown file defines: its headings' slugs (numbered when repeated) and
    explicit HTML ``id``/``name`` attributes."""
    seen: dict[str, int] = {}
    result: set[str] = set()
    previous = ""
    for _, line in prose_lines(text):
        heading = None
        atx = _ATX_HEADING.match(line)
        if atx:
            heading = atx.group(2) or ""
        elif previous.strip() and not previous.startswith("    ") and _SETEXT_UNDERLINE.match(line):
            heading = previous.strip()
        if heading is not None:
            base = slug(heading)
            count = seen.get(base, 0)
            seen[base] = count + 1
            result.add(base if count == 0 else f"{base}-{count}")
        result.update(_HTML_ID.findall(line))
        previous = line if heading is None else ""
    return result


def broken_links(page: Path, root: Path = ROOT) -> list[str]:
    """One message per link of ``page`` that does not resolve."""
    problems: list[str] = []
    text = page.read_text(encoding="utf-8")
    rel_page = page.relative_to(root)
    for line_no, raw in links(text):
        target = raw[1:-1] if raw.startswith("<") and raw.endswith(">") else raw
        target = target.strip()
        if not target or _SCHEME.match(target):  # http(s), mailto, ...: not ours to check
            continue
        path_part, _, anchor = target.partition("#")
        path_part = unquote(path_part.split("?", 1)[0])
        where = f"{rel_page}:{line_no}: ({raw})"
        if path_part.startswith("/"):
            problems.append(f"{where}: absolute path; use a path relative to the page")
            continue
        resolved = (page.parent / path_part).resolve() if path_part else page.resolve()
        if not resolved.is_relative_to(root):
            problems.append(f"{where}: points outside the repository")
            continue
        if not resolved.exists():
            problems.append(f"{where}: {resolved.relative_to(root)} does not exist")
            continue
        if anchor and resolved.is_file() and resolved.suffix.lower() == ".md":
            if unquote(anchor).lower() not in anchors(resolved.read_text(encoding="utf-8")):
                problems.append(
                    f"{where}: no heading '#{anchor}' in {resolved.relative_to(root)}")
    return problems


@pytest.mark.parametrize("page", markdown_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(page: Path) -> None:
    problems = broken_links(page)
    assert not problems, "broken links:\n" + "\n".join(problems)


def test_the_check_covers_the_readme_and_docs() -> None:
    names = {str(p.relative_to(ROOT)) for p in markdown_files()}
    assert "README.md" in names
    assert any(name.startswith("docs/") for name in names)


# -- the checker itself ---------------------------------------------------------------------------

def _page(root: Path, body: str) -> Path:
    (root / "docs").mkdir(exist_ok=True)
    (root / "docs" / "target.md").write_text(
        "# Target page\n\n## `results.json`\n\n## Beyond the paper: targets\n\n"
        "## Twice\n\n## Twice\n\nSetext heading\n--------------\n\n<a id=\"custom\"></a>\n",
        encoding="utf-8")
    (root / "code.py").write_text("x = 1\n", encoding="utf-8")
    (root / "figure.png").write_bytes(b"")
    page = root / "README.md"
    page.write_text(body, encoding="utf-8")
    return page


@pytest.mark.parametrize("body", [
    "[page](docs/target.md)",
    "[heading](docs/target.md#target-page)",
    "[code heading](docs/target.md#resultsjson)",
    "[punctuation](docs/target.md#beyond-the-paper-targets)",
    "[repeated](docs/target.md#twice-1)",
    "[setext](docs/target.md#setext-heading)",
    "[html id](docs/target.md#custom)",
    "[code line](code.py#L1)",
    "[folder](docs/)",
    "![figure](figure.png)",
    "[titled](docs/target.md \"a title\")",
    "[angle](<docs/target.md>)",
    "[wrapped\ntext](docs/target.md)",
    "[web](https://example.com/missing.md) [mail](mailto:a@b.c)",
    "`[in code](missing.md)`",
    "```md\n[in a fence](missing.md)\n```",
    "[ref]: docs/target.md",
])
def test_checker_accepts(tmp_path: Path, body: str) -> None:
    assert broken_links(_page(tmp_path, body), root=tmp_path) == []


@pytest.mark.parametrize("body, fragment", [
    ("[gone](docs/missing.md)", "docs/missing.md does not exist"),
    ("![gone](figures/missing.png)", "figures/missing.png does not exist"),
    ("[bad anchor](docs/target.md#no-such-heading)", "no heading '#no-such-heading'"),
    ("[not numbered](docs/target.md#twice-2)", "no heading '#twice-2'"),
    ("[own anchor](#nowhere)", "no heading '#nowhere' in README.md"),
    ("[outside](../elsewhere.md)", "outside the repository"),
    ("[absolute](/docs/target.md)", "absolute path"),
    ("text\n\n[ref]: docs/missing.md", "docs/missing.md does not exist"),
])
def test_checker_names_the_broken_link(tmp_path: Path, body: str, fragment: str) -> None:
    problems = broken_links(_page(tmp_path, body), root=tmp_path)
    assert len(problems) == 1 and fragment in problems[0], problems
    assert problems[0].startswith("README.md:")
