"""`transient bench`: the rows of a sweep of contact rules (api.bench) printed as they come,
then whether the target is met and the files written."""
import json
from pathlib import Path

from .. import api
from ..errors import CaseError

HEADER = (f"{'rule':<22} {'points':>6} {'kept':>5} {'setup s':>8} {'kernel s':>8} "
          f"{'total s':>8} {'steps/s':>9} {'error_rms':>9} {'preload':>9} {'p_max err':>9} "
          f"{'freq err':>9}")
OSCILLATION_HEADER = (f" {'growth':>9} {'grow err':>9} {'cycle rms':>9} {'rms err':>9} "
                      f"{'cycle Hz':>9} {'Hz err':>9}")


def cmd_bench(args):
    eps = _numbers(args.eps, "--eps", float)
    points = _numbers(args.points, "--points", int) if args.points else None
    tolerances = _numbers(args.tolerances, "--tolerances", float)
    case = api.load(args.case, args.overrides)
    shown = []

    def show(row):
        if args.json:
            return
        if not shown:       # the first row says whether the squeal's columns follow
            print(HEADER + (OSCILLATION_HEADER if row.get("growth_rate") is not None else ""))
        shown.append(row)
        print(format_row(row), flush=True)
    result = api.bench(case, args.pair, eps, points, args.t_end, tolerances, args.reference,
                       args.cycle_from, bench_directory(args.out, args.case), show)
    rows, best = result.rows, result.target
    if args.json:
        print(json.dumps(result.summary()))
        return 0
    ref = rows[0]["label"]
    if best:
        print(f"target met: {best['label']} within {best['error_rms']:.2%} of {ref} at "
              f"{best['kernel_s'] / rows[0]['kernel_s']:.2f} of its kernel time")
    else:
        print(f"target not met: no regularized coarse rule within 1% of {ref} at a "
              "third or less of its kernel time")
    print("wrote " + ", ".join(str(f) for f in result.files))
    return 0


def bench_directory(out, case):
    """The bench's folder: --out, or <case name>_bench in the working directory (not next to
    a shipped case); api.bench checks it writable before the sweep."""
    return Path(out) if out else Path.cwd() / f"{Path(case).stem}_bench"


def _numbers(text, key, kind):
    try:
        return [kind(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CaseError("command line", key, f"expected comma separated numbers, got "
                        f"'{text}'") from None


def format_row(row):
    """A row of the table: a refused variant's label and reason, or its figures."""
    if row["setup_s"] is None:
        return f"{row['label']:<22} {row['status']}"
    kept = row["kept"] if row["kept"] is not None else "-"
    return (f"{row['label']:<22} {row['points']:>6} {kept:>5} "
            f"{row['setup_s']:8.2f} {row['kernel_s']:8.2f} {row['total_s']:8.2f} "
            f"{row['steps_per_s']:9.0f} {row['error_rms']:9.2e} {row['preload_error']:9.2e} "
            f"{row['pressure_max_error']:9.2e} "
            f"{row['frequency_error']:9.2e} {_oscillation_cells(row)}{row['status']}")


def _oscillation_cells(row):
    """The squeal's columns of a row, when it has them."""
    if row.get("growth_rate") is None:
        return ""
    return (f"{row['growth_rate']:9.1f} {row['growth_error']:9.2e} {row['cycle_rms']:9.2e} "
            f"{row['cycle_rms_error']:9.2e} {row['cycle_frequency']:9.1f} "
            f"{row['cycle_frequency_error']:9.2e} ")
