"""transient: long transient vibrations of elastic solids in contact across non-conforming meshes."""
__version__ = "0.1.0"
