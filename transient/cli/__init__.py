"""Command line: `transient SUBCOMMAND ...` (parser.py builds the arguments, commands.py runs them)."""
from .commands import main

__all__ = ["main"]
