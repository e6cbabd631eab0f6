"""The key reference in cases/README.md is generated from the schema and stays in step with it;
the README and the manual in docs/ keep their promises: links that resolve, a Python example
that runs, no dates or machine loads in the front door."""
import re
import sys
from pathlib import Path

import pytest

from transient.case.schema import reference_markdown

ROOT = Path(__file__).resolve().parent.parent


def test_case_reference_is_up_to_date():
    """cases/README.md holds what the command its message names prints."""
    import subprocess
    text = (ROOT / "cases" / "README.md").read_text()
    printed = subprocess.run([sys.executable, "-m", "transient.case"], capture_output=True,
                             text=True, check=True).stdout
    assert printed.strip() == reference_markdown().strip()
    assert reference_markdown() in text, "regenerate with: python -m transient.case"


def test_readme_quick_start_commands():
    text = (ROOT / "README.md").read_text()
    assert "python -m pip install -e . && transient run cases/pad_disc.toml" in text
    assert 'python -m pip install -e ".[test]" && python -m pytest' in text


# [text](target) and <img src="target">: relative targets must be files of the repository
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)|<img [^>]*src=\"([^\"]+)\"")
HEADING = re.compile(r"^#{1,6} (.+)$", re.M)


def _pages():
    return [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def _slug(heading):
    """The anchor MkDocs (and GitHub) give a heading: lower case, words joined by '-'."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return re.sub(r"[\s]+", "-", text)


def _anchors(path):
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)
    return {_slug(h) for h in HEADING.findall(text)}


def _links(path):
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)
    return [a or b for a, b in LINK.findall(text)]


def test_every_link_of_the_readme_and_the_docs_resolves():
    broken = []
    for page in _pages():
        for target in _links(page):
            if re.match(r"[a-z]+:", target):       # https:, mailto: (not checked offline)
                continue
            file, _, anchor = target.partition("#")
            dest = (page.parent / file).resolve() if file else page
            if not dest.is_file():
                broken.append(f"{page.name}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
                broken.append(f"{page.name}: {target} (no such heading)")
    assert broken == []


def test_the_link_check_sees_a_broken_link(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# Title\n\n[ok](#title) [gone](missing.md) [bad](#nowhere)\n")
    links = _links(page)
    assert links == ["#title", "missing.md", "#nowhere"]
    assert not (tmp_path / "missing.md").exists() and "nowhere" not in _anchors(page)
    assert "title" in _anchors(page)


def test_the_docs_regenerate_the_case_keys_from_the_schema():
    """The case-key page holds no copy of the table: the docs build's hook puts the schema's in."""
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import hooks
    finally:
        sys.path.pop(0)
    page = (ROOT / "docs" / "case-keys.md").read_text()
    assert "| `solver.t_end`" not in page
    built = hooks.on_page_markdown(page, None, {"config_file_path": str(ROOT / "mkdocs.yml")},
                                   None)
    assert reference_markdown() in built
    assert "Generator sets" in built


def test_the_readme_is_a_front_door():
    """Under 1,500 words, no dates, machine loads or wall times: those are in
    docs/performance.md, with their machine and command."""
    text = (ROOT / "README.md").read_text()
    assert len(text.split()) < 1500
    assert not re.search(r"20\d\d-\d\d-\d\d|\bload [0-9]", text)
    assert not re.search(r"\b\d+(\.\d+)?(-\d+(\.\d+)?)? ?(s|min|minutes|seconds|GB)\b", text)
    assert text.isascii()


@pytest.mark.slow
def test_the_readmes_python_example_runs(tmp_path):
    """The README's Python example, as a user runs it from a checkout (the shipped cases under
    cases/), in a folder of its own."""
    import subprocess
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    assert len(blocks) == 1 and len(blocks[0].strip().splitlines()) <= 12
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    done = subprocess.run([sys.executable, "-c", blocks[0]], cwd=tmp_path, capture_output=True,
                          text=True, timeout=1800)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("complete ")
    assert (tmp_path / "pad.h5").is_file()


def test_the_api_page_lists_every_public_function():
    """Each name of transient.__all__ has its `::: module.NAME` on docs/api.md, and each such
    line names the object `transient.NAME` is (not a stale home)."""
    import importlib
    import transient
    text = (ROOT / "docs" / "api.md").read_text()
    documented = {}
    for target in re.findall(r"^::: (transient[\w.]*)$", text, re.M):
        module, _, name = target.rpartition(".")
        documented[name] = getattr(importlib.import_module(module), name)
    missing = [n for n in transient.__all__ if n not in documented]
    assert missing == []
    assert [n for n in transient.__all__ if documented[n] is not getattr(transient, n)] == []
