"""The FE model stage: parts meshed, K and M assembled, constraints, loads and sensors."""
from .model import Model, Part, build_model, constant_load, resolve_set

__all__ = ["Model", "Part", "build_model", "constant_load", "resolve_set"]
