"""`python -m transient.case`: the key reference of case files (cases/README.md)."""
from .schema import reference_markdown

print(reference_markdown())
