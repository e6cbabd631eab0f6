"""The key reference in cases/README.md is generated from the schema and stays in step with it."""
from pathlib import Path

from transient.case.schema import reference_markdown

ROOT = Path(__file__).resolve().parent.parent


def test_case_reference_is_up_to_date():
    text = (ROOT / "cases" / "README.md").read_text()
    assert reference_markdown() in text, "regenerate with: python -m transient.case"


def test_readme_quick_start_commands():
    text = (ROOT / "README.md").read_text()
    assert "python -m pip install -e . && transient run cases/pad_disc.toml" in text
    assert 'python -m pip install -e ".[test]" && python -m pytest' in text
