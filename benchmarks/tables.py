"""What the benchmark and study scripts do with their table: print it, append it to the
performance page (or any markdown file) and write their rows as JSON when asked."""
import json
from pathlib import Path


def publish(table, markdown=None, json_path=None, rows=None):
    """Print the markdown table; append it to markdown, and rows to json_path, when given."""
    print(table)
    if markdown:
        with open(markdown, "a") as f:
            f.write(table + "\n")
    if json_path:
        Path(json_path).write_text(json.dumps(rows, indent=1))


def table(header, rows):
    """A markdown table of the header's columns and rows (lists of cells, formatted)."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(str(c) for c in r) + " |" for r in rows])
