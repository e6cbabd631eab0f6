"""The error of a mesh file that cannot be used, shared by the readers of every format."""


class MeshFileError(Exception):
    """A mesh file that cannot be used: missing, unreadable or with unsupported content."""

    def __init__(self, path, message):
        super().__init__(f"{path}: {message}")
        self.path = str(path)
        self.message = message
