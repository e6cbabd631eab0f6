"""A table of rows (dicts) written as CSV: one line per row, the columns given, an empty cell
where a row holds None (csv's own rendering of it)."""
import csv


def write_csv(path, columns, rows):
    """The rows, each a dict holding every column, written to path under a header line."""
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, columns)
        writer.writeheader()
        writer.writerows({k: r[k] for k in columns} for r in rows)
