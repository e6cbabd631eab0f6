"""Numba flags in one place: every kernel is cached on disk and compiled without the GIL."""
import numba

njit = numba.njit(cache=True, nogil=True, error_model="numpy")
njit_fast = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath=True)
njit_parallel = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath=True,
                           parallel=True)
