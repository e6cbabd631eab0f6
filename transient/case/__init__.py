"""The case stage: a TOML file and `--set` overrides, validated against the schema, become a
Case of frozen specs; every check that needs several keys runs here, before any mesh is built."""
from .loading import Case, load, parse

__all__ = ["Case", "load", "parse"]
