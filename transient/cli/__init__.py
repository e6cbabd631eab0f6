"""Command line: `transient SUBCOMMAND ...`; parser.py builds the arguments, commands.py and
plotting.py run them."""
from .commands import console, main

__all__ = ["console", "main"]
