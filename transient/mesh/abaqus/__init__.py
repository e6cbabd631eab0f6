"""Abaqus input decks (.inp): nodes, solid elements, node and element sets, surfaces, parts
and their placed instances, read into a Mesh (read_abaqus)."""
from .build import read_abaqus

__all__ = ["read_abaqus"]
