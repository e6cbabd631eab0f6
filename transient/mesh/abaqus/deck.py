"""An Abaqus input deck as a list of keyword blocks: each keyword line with its parameters and
the data lines under it, *INCLUDE files followed in place.

The syntax is the Abaqus Keywords Reference's (also CalculiX's): a line starting with '**' is
a comment; one starting with '*' is a keyword line, 'KEYWORD, PARAM=VALUE, FLAG', continued
on the next line when it ends with a comma; other lines are data lines of comma-separated
fields. Keywords and parameter names are case-insensitive (kept here in upper case), values
are kept as written, without the double quotes that may enclose a name with spaces.
"""
from dataclasses import dataclass
from pathlib import Path

from ...errors import one_line
from ..fileerror import MeshFileError

# keywords whose data may come from a file of their own (PARAM INPUT=FILE), read here; the
# others are not read, so a missing file of theirs (an amplitude's table) stops nothing
DATA_FILES = ("NODE", "ELEMENT", "NSET", "ELSET", "SURFACE")
_MAX_DEPTH = 20          # nested *INCLUDE files: deeper is a cycle in practice


@dataclass(frozen=True)
class Keyword:
    """One keyword line and its data lines.

    name : the keyword in upper case with single spaces ('NODE', 'END INSTANCE').
    params : parameter name (upper case) -> value as written (None for a flag).
    data : the data lines, each a tuple of stripped fields (trailing empty fields dropped).
    lines : the line number of each data line in `source`.
    path, line : where the keyword line is.
    source : the file holding the data lines (path, or the file of an INPUT parameter).
    text : the keyword line as written, for messages.
    files : the file of each data line when some come from an *INCLUDE file, else ().
    """
    name: str
    params: dict
    data: tuple
    lines: tuple
    path: Path
    line: int
    source: Path
    text: str
    files: tuple = ()

    def error(self, message, row=None):
        """A MeshFileError naming the file, the line (of data row `row`, else of the keyword
        line) and the keyword line."""
        if row is None:
            path, line = self.path, self.line
        else:
            path, line = (self.files[row] if self.files else self.source), self.lines[row]
        return MeshFileError(path, f"line {line}: {self.text}: {message}")

    def get(self, param, default=None):
        return self.params.get(param, default)


def read_keywords(path):
    """The keyword blocks of the deck at path, in order, *INCLUDE files read in their place
    (relative to the including file, else to the deck's folder)."""
    path = Path(path)
    blocks, head, data = [], None, []

    def close():
        if head is not None:
            blocks.append(_block(*head, data))

    for where, line, text in _lines(path, path.parent, ()):
        stripped = text.strip()
        if not stripped or stripped.startswith("**"):
            continue
        if head is not None and head[2].endswith(",") and not data:
            # a keyword line ending with a comma goes on on the next line
            head = (head[0], head[1], head[2] + " " + stripped)
            continue
        if stripped.startswith("*"):
            close()
            head, data = (where, line, stripped), []
        elif head is not None:
            data.append((where, line, stripped))
    close()
    return blocks


def _block(path, line, text, data):
    name, params = _keyword(text)
    keyword = Keyword(name, params, (), (), path, line, path, _short(text))
    source = path
    if "INPUT" in params and name in DATA_FILES:
        source = _resolve(keyword, params["INPUT"], path.parent)
        data = [(f, n, t.strip()) for f, n, t in _read(source, keyword)
                if t.strip() and not t.strip().startswith("**")]
    fields = tuple(_fields(t) for _, _, t in data)
    files = tuple(f for f, _, _ in data) if any(f != source for f, _, _ in data) else ()
    return Keyword(name, params, fields, tuple(n for _, n, _ in data), path, line, source,
                   keyword.text, files)


def _short(text):
    """The keyword line for messages: its first 60 characters, on one line."""
    text = one_line(" ".join(text.split()))
    return text if len(text) <= 60 else text[:57] + "..."


def _lines(path, root, stack):
    """(file, line number, text) of every line, *INCLUDE lines replaced by their file's."""
    if len(stack) >= _MAX_DEPTH or path.resolve() in stack:
        raise MeshFileError(path, f"*INCLUDE nested {len(stack)} deep or in a cycle "
                            f"({' -> '.join(p.name for p in stack)}): expected a file that "
                            "does not include itself")
    stack = stack + (path.resolve(),)
    for where, line, text in _read(path, None):
        if text.lstrip()[:8].upper() == "*INCLUDE":
            name, params = _keyword(text.strip())
            if name == "INCLUDE":
                keyword = Keyword(name, params, (), (), where, line, where, _short(text))
                if not params.get("INPUT"):
                    raise keyword.error("expected INPUT=FILE, the file to include")
                yield from _lines(_resolve(keyword, params["INPUT"], root), root, stack)
                continue
        yield where, line, text


def _read(path, keyword):
    """(path, line number, text) of the lines of a text file, any encoding's bytes kept."""
    try:
        # latin-1 maps every byte: a comment in another encoding does not stop the reading
        with open(path, encoding="latin-1") as f:
            for n, text in enumerate(f, 1):
                yield path, n, text.rstrip("\r\n")
    except OSError as exc:
        if keyword is None:
            raise MeshFileError(path, f"cannot read: {exc.strerror or exc}") from None
        raise keyword.error(f"cannot read '{path}': {exc.strerror or exc}") from None


def _resolve(keyword, name, root):
    """The file an INPUT parameter names: relative to the file of the keyword, else to the
    deck's folder (Abaqus takes it relative to where the job runs, the deck's folder)."""
    for folder in (keyword.path.parent, root):
        candidate = folder / name
        if candidate.is_file():
            return candidate
    raise keyword.error(f"no such file '{name}' (looked in {keyword.path.parent}"
                        + ("" if root == keyword.path.parent else f" and {root}") + ")")


def _keyword(text):
    """Name and parameters of a keyword line '*NAME, P=V, FLAG'."""
    fields = _split(text.lstrip("*"))
    name = " ".join(fields[0].upper().split())
    params = {}
    for field in fields[1:]:
        if not field:
            continue
        key, eq, value = field.partition("=")
        params[" ".join(key.upper().split())] = _unquote(value.strip()) if eq else None
    return name, params


def _fields(text):
    if '"' in text:
        fields = [_unquote(f.strip()) for f in _split(text)]
    else:
        fields = [f.strip() for f in text.split(",")]
    while fields and not fields[-1]:
        fields.pop()
    return tuple(fields)


def _split(text):
    """Comma-separated fields, commas inside double quotes kept."""
    if '"' not in text:
        return text.split(",")
    fields, current, quoted = [], [], False
    for c in text:
        if c == '"':
            quoted = not quoted
        if c == "," and not quoted:
            fields.append("".join(current))
            current = []
        else:
            current.append(c)
    fields.append("".join(current))
    return fields


def _unquote(text):
    return text[1:-1] if len(text) >= 2 and text[0] == text[-1] == '"' else text
