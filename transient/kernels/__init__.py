"""Numba kernels: plain arrays in, plain arrays out; orchestration lives outside this package."""
