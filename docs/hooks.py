"""MkDocs hook: the case-key page takes its text from cases/README.md and its key table from
the schema at build time (as `python -m transient.case` writes it), so the manual cannot fall
behind the case files it documents."""
import sys
from pathlib import Path

SETS = "<!-- cases/README.md: selections and generator sets -->"
KEYS = "<!-- case keys: generated from transient/case/schema.py -->"


def on_page_markdown(markdown, page, config, files):
    if SETS not in markdown and KEYS not in markdown:
        return markdown
    root = Path(config["config_file_path"]).resolve().parent
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    from transient.case.schema import reference_markdown
    text = (root / "cases" / "README.md").read_text()
    # between the title and the generated section
    sets = text.split("\n", 1)[1].split("\n## Keys", 1)[0].strip()
    return markdown.replace(SETS, sets).replace(KEYS, reference_markdown())
