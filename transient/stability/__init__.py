"""Complex eigenvalue analysis: the modes of the structure linearized at steady sliding, with
the friction stiffness and damping; which of them grow (squeal)."""
from .modes import ComplexModes, complex_modes

__all__ = ["ComplexModes", "complex_modes"]
