"""The documentation the code cites is in the repository: every citation of a ``docs/`` file and
section points at one that exists, relative links in the Markdown files resolve, and nothing
cites a file outside the repository."""
import re
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _tracked_text_files():
    names = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True, check=True).stdout.split()
    for name in names:
        path = REPO / name
        if path.suffix in (".py", ".md", ".toml", ".xml", ".txt", "") and path.is_file():
            try:
                yield path, path.read_text()
            except UnicodeDecodeError:
                continue


def _sections(doc: Path) -> set[str]:
    """Section numbers of a doc's numbered headings (``## 4.`` and ``### 4.2``)."""
    return set(re.findall(r"^#{2,3} (\d+(?:\.\d+)?)\.? ", doc.read_text(), flags=re.MULTILINE))


def test_every_docs_citation_resolves():
    cited = 0
    for path, text in _tracked_text_files():
        for doc, section in re.findall(r"docs/([\w-]+\.md)\)?(?: (?:§|section )(\d+(?:\.\d+)?))?", text):
            target = REPO / "docs" / doc
            assert target.is_file(), f"{path.relative_to(REPO)} cites docs/{doc}, which does not exist"
            if section:
                assert section in _sections(target), f"{path.relative_to(REPO)} cites docs/{doc} §{section}"
                cited += 1
    assert cited >= 8  # the code and READMEs cite sections of the reference docs


def test_nothing_cites_a_file_outside_the_repository():
    for path, text in _tracked_text_files():
        if path.parent.name == "tests":
            continue  # tests may use data beside the clone when it is there (and skip otherwise)
        assert "REFERENCE.md" not in text, path.relative_to(REPO)
        assert "../shared/" not in text, path.relative_to(REPO)


def test_relative_markdown_links_resolve():
    for path, text in _tracked_text_files():
        if path.suffix != ".md":
            continue
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
            if "://" in target or target.startswith("mailto:"):
                continue
            assert (path.parent / target).exists(), f"{path.relative_to(REPO)} links to missing {target}"
