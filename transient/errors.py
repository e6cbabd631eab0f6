"""Errors a user can act on: they name the file, the key path and what was expected."""


def one_line(text):
    """text with its control characters escaped: a value quoted in a message never breaks
    the message over lines."""
    return "".join(c if c.isprintable() or c == " " else c.encode("unicode_escape").decode()
                   for c in str(text))


class CaseError(Exception):
    """Bad input: printed as one line 'FILE: KEY: MESSAGE', exit code 2, no traceback."""

    def __init__(self, path, key, message):
        key, message = one_line(key), one_line(message)
        super().__init__(f"{one_line(path)}: {key}: {message}" if key
                         else f"{one_line(path)}: {message}")
        self.path = str(path)
        self.key = key
        self.message = message


class DamagedHistory(ValueError):
    """A history file whose layout is not the one `io.history.History` writes: key names the
    dataset or the attribute, message what it is and what was expected."""

    def __init__(self, key, message):
        super().__init__(f"{key}: {message}")
        self.key = key
        self.message = message


class FactorizationError(RuntimeError):
    """A sparse factorization that failed (singular, not positive definite, out of memory)."""


class RunAborted(Exception):
    """A run that stopped before its end; the reason is kept in the output file."""


def interrupted(exc):
    """Whether exc is Ctrl-C: a KeyboardInterrupt, or the SystemError CPython raises from one
    (at times from such a SystemError) that lands while a compiled (Numba) function runs
    Python code of its own."""
    return stop_reason(exc) is not None


def stop_reason(exc):
    """What stopped a run interrupted by exc ('interrupted', 'terminated (SIGTERM)'), or None
    when exc is not an interrupt."""
    while isinstance(exc, SystemError):
        exc = exc.__cause__
    if not isinstance(exc, KeyboardInterrupt):
        return None
    return str(exc) or "interrupted"
