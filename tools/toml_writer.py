"""A case dict written as TOML text (tomllib reads, it does not write): the brake tools'
case files and the fuzzer's mutants, any character and any number escaped as TOML has them."""
import math
import re


class Raw(str):
    """TOML text written as it is: deep nesting, malformed values."""


BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
           "\r": "\\r"}


def toml_string(text):
    """A TOML basic string: every character that is not printable ASCII escaped, so the file
    is ASCII and a control character reaches the package as itself."""
    out = []
    for c in text:
        if c in ESCAPES:
            out.append(ESCAPES[c])
        elif " " <= c <= "~":
            out.append(c)
        elif ord(c) <= 0xFFFF:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(f"\\U{ord(c):08x}")
    return '"' + "".join(out) + '"'


def toml_key(key):
    return key if BARE_KEY.fullmatch(key) else toml_string(key)


def toml_value(value):
    if isinstance(value, Raw):
        return str(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"no TOML for {type(value).__name__}")


def dumps(data):
    """TOML text of a case dict: scalars of a table under its [header], sub-tables after.

    Parameters
    ----------
    data : dict
        Tables, strings (any character), numbers (nan, inf and ints of any size), booleans,
        lists, and `Raw` text written as it is.

    Returns
    -------
    str
        ASCII TOML that tomllib reads back to data (Raw values aside).
    """
    lines = []

    def table(node, path):
        scalars = [(k, v) for k, v in node.items() if not isinstance(v, dict)]
        tables = [(k, v) for k, v in node.items() if isinstance(v, dict)]
        # an empty table needs its header to exist; one of sub-tables only is implied by them
        if path and (scalars or not tables):
            lines.append("[" + ".".join(toml_key(k) for k in path) + "]")
        lines.extend(f"{toml_key(k)} = {toml_value(v)}" for k, v in scalars)
        for k, v in tables:
            table(v, path + [k])

    table(data, [])
    return "\n".join(lines) + "\n"
