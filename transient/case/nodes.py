"""The kinds of node a case schema is made of (values, tables, named tables, variants), and
the key reference they print; the schema itself is case/schema.py."""
from dataclasses import dataclass, field

REQUIRED = object()


@dataclass(frozen=True)
class Value:
    """A leaf value. kind: float, int, str, bool, floats, ints, strs (lists), choice, table
    (names to strings), eps (a float within bounds or the string "auto")."""
    kind: str
    doc: str
    default: object = REQUIRED
    unit: str = ""
    length: int = 0            # exact list length when > 0
    choices: tuple = ()
    minimum: float = None      # inclusive bounds on numbers (and list items)
    maximum: float = None
    open_min: float = None     # exclusive bounds
    open_max: float = None


@dataclass(frozen=True)
class Table:
    doc: str
    fields: dict
    optional: bool = False     # an absent table is filled with its defaults


@dataclass(frozen=True)
class Named:
    """Tables keyed by a user-chosen name, such as [parts.NAME]."""
    doc: str
    item: object
    min_items: int = 0


@dataclass(frozen=True)
class Variant:
    """A table whose fields depend on its `kind` key (or another: `key`)."""
    doc: str
    options: dict
    common: dict = field(default_factory=dict)
    default: str = None        # kind taken when the table is absent (None: required)
    key: str = "kind"
    # the default kind also when the table is given without its key: a material's elasticity,
    # isotropic unless said (a load's signal, given, must say its kind)
    implicit: bool = False


def reference(node, prefix=""):
    """Markdown rows (path, type, default, unit, meaning) of every key under a schema node."""
    rows = []
    if isinstance(node, Table):
        for key, sub in node.fields.items():
            rows += reference(sub, f"{prefix}.{key}" if prefix else key)
    elif isinstance(node, Named):
        rows += reference(node.item, f"{prefix}.NAME")
    elif isinstance(node, Variant):
        rows.append((f"{prefix}.{node.key}", "choice", repr(node.default) if node.default
                     else "required", "",
                     f"{node.doc}: one of {', '.join(node.options)}"))
        for key, sub in node.common.items():
            rows += reference(sub, f"{prefix}.{key}")
        for kind, fields in node.options.items():
            for key, sub in fields.items():
                rows += reference(sub, f"{prefix}.{key} ({kind})")
    else:
        default = "required" if node.default is REQUIRED else repr(node.default)
        kind = node.kind + (f"[{node.length}]" if node.length else "")
        doc = node.doc + (f" ({', '.join(node.choices)})" if node.choices else "")
        rows.append((prefix, kind, default, node.unit, doc))
    return rows


def reference_markdown(root):
    lines = ["| key | type | default | unit | meaning |", "|---|---|---|---|---|"]
    lines += [f"| `{p}` | {k} | {d} | {u} | {m} |" for p, k, d, u, m in reference(root)]
    return "\n".join(lines)
