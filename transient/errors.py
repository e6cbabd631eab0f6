"""Errors a user can act on: they name the file, the key path and what was expected."""


class CaseError(Exception):
    """Bad input: printed as one line 'FILE: KEY: MESSAGE', exit code 2, no traceback."""

    def __init__(self, path, key, message):
        super().__init__(f"{path}: {key}: {message}" if key else f"{path}: {message}")
        self.path = str(path)
        self.key = key
        self.message = message


class RunAborted(Exception):
    """A run that stopped before its end; the reason is kept in the output file."""
