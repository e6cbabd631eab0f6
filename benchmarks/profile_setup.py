"""Where a case's setup spends its time: `prepare` under cProfile, after one unprofiled
`prepare` that compiles the kernels, with the stages' times and the cumulative and own seconds
of the functions named. One BLAS thread, as `transient run` sets up; set OMP_NUM_THREADS and
NUMBA_NUM_THREADS for the rest. The package imported is the one on PYTHONPATH, so two checkouts
can be profiled in turn (run from outside both). solver.t_end is 1e-3 unless --set says
otherwise: the setup does not depend on it, and the load's work bound does.

    python benchmarks/profile_setup.py [CASE] [--set key=value ...] [--functions block_lanczos,...]
"""
import argparse
import cProfile
import pstats
import time
from pathlib import Path

from transient.case.loading import load
from transient.stages import prepare

CASE = Path(__file__).resolve().parent.parent / "cases" / "pad_disc_long.toml"
FUNCTIONS = "normal_modes,block_lanczos,m_orthonormalize,_call,free_block,nnls_gram"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default=str(CASE))
    ap.add_argument("--set", dest="overrides", action="append", default=[])
    ap.add_argument("--functions", default=FUNCTIONS)
    args = ap.parse_args()
    case = load(args.case, overrides=["solver.t_end=1e-3", *args.overrides])
    prepare(case)
    profile = cProfile.Profile()
    t0 = time.perf_counter()
    profile.enable()
    setup = prepare(case)
    profile.disable()
    print(f"setup {time.perf_counter() - t0:.2f} s (profiled)",
          {k: round(v, 2) for k, v in setup.stages.items()})
    wanted = set(args.functions.split(","))
    for (path, line, name), (_, calls, own, cum, _) in pstats.Stats(profile).stats.items():
        if name in wanted:
            print(f"  {name:24s} {Path(path).name}:{line}  calls {calls}  cum {cum:.2f} s"
                  f"  own {own:.2f} s")


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    main()
