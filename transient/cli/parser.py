"""The command line's arguments: one subparser per command, `plot` with one per picture."""
import argparse

from .. import __version__

FMAX_HELP = ("highest frequency drawn [Hz] (default: the model's band, the fmax of the case "
             "the history keeps, as transient cea takes it; inf: half the sample rate)")


def _case_args(p):
    p.add_argument("case", help="case file (TOML)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case value with a TOML literal, e.g. "
                   "parts.upper.mesh.divisions=[3,3,3] (repeatable)")


def _dry_args(p):
    p.add_argument("--dry-run", action="store_true", help="build the model and the contact "
                   "pairs' fine rules, check them, say the dofs by part, the contact points, "
                   "the memory and setup-time estimates (and a run's steps), then stop: "
                   "nothing factorized or written")


def _parts_args(p):
    """Where the components path (solver.reduction.method) reduces its parts."""
    p.add_argument("--workers", type=int, default=0, help="components path: reduce the parts "
                   "on an embedded Dask cluster of N one-thread processes, one task a part "
                   "(default 0: in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="components path: reduce the parts "
                   "on an existing Dask scheduler (tcp://HOST:PORT) instead")
    p.add_argument("--cache", metavar="DIR", help="components path: keep each part's "
                   "reduction in DIR and read back the parts a later case makes the same")


def build_parser():
    parser = argparse.ArgumentParser(prog="transient", description="Long transient vibrations "
                                     "of elastic solids in contact across non-conforming meshes.")
    parser.add_argument("--version", action="version", version=f"transient {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("modes", help="normal modes of the case's model")
    _case_args(p)
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    _dry_args(p)
    p = sub.add_parser("cea", help="complex eigenvalue analysis: the modes of the structure "
                       "linearized at steady sliding with friction, which of them grow")
    _case_args(p)
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    _dry_args(p)
    _parts_args(p)
    p = sub.add_parser("run", help="transient: preload, then time integration to solver.t_end, "
                       "streamed to an HDF5 history")
    _case_args(p)
    p.add_argument("-o", "--output", help="HDF5 file (default: output.file, or the case's "
                   "name with .h5)")
    p.add_argument("--resume", action="store_true", help="continue the run stored in the "
                   "output file from its last checkpoint (after an abort, or to a later t_end)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    _dry_args(p)
    _parts_args(p)
    p = sub.add_parser("info", help="summary of an HDF5 history")
    p.add_argument("file", help="HDF5 file written by transient run")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p = sub.add_parser("compat", help="compatibility of a contact interface: fine rule, "
                       "singular values of the gap energy, C(eps)")
    _case_args(p)
    p.add_argument("--pair", help="contact pair to report (default: the first)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p = sub.add_parser("bench", help="error against run time for a sweep of contact rules: "
                       "fine (reference), fine regularized at each eps, centre, centre "
                       "regularized, greedy at several m, sampled at several tolerances")
    _case_args(p)
    p.add_argument("--pair", help="contact pair to sweep (default: the first)")
    p.add_argument("--eps", default="1e-6,1e-4,1e-3,1e-2", help="eps of the regularized fine "
                   "rule, comma separated (default 1e-6,1e-4,1e-3,1e-2)")
    p.add_argument("--points", help="greedy m, comma separated, 0 the rank of the kept shapes "
                   "(default: the greedy rule's own count r, then r/2, r/4, 4r, 10r below "
                   "the fine rule's count)")
    p.add_argument("--tolerances", default="3e-2,1e-2,3e-3", help="sampling tolerances of "
                   "the sampled rule, regularized at the case's eps, comma separated (default "
                   "3e-2,1e-2,3e-3; empty for none)")
    p.add_argument("--t-end", type=float, help="simulated time [s] (default: the case's)")
    p.add_argument("--reference", default="fine", help="fine (the fine rule, default) or case "
                   "(the case's own rule at half its step: a saturated squeal, where the fine "
                   "rule's implicit steps cost too much)")
    p.add_argument("--cycle-from", type=float, help="with friction: the start of the limit "
                   "cycle's window [s] (default: the run's last quarter)")
    p.add_argument("--out", metavar="DIR", help="directory of bench.csv, bench.json and "
                   "bench.png (default: <case name>_bench in the working directory)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p = sub.add_parser("sweep", help="a campaign: the case run (or analysed) for every "
                       "combination of parameter values, on Dask")
    p.epilog = ("Each variant's outputs are named by its values (DIR/v-<hash>.h5, .json); "
                "sweep.csv and sweep.json list them with their values. The folder is held by "
                "one campaign at a time, and a file there that this package did not write is "
                "never replaced. Exit code: 0 when every variant completes, 2 when a variant "
                "is refused (bad input: the first one is said), 3 when none is refused but "
                "one did not complete (a run aborted).")
    _case_args(p)
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUES",
                   help="a case key and its values: a TOML list ([0.2,0.4]) or "
                   "start:stop:count (repeatable)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--grid", dest="mode", action="store_const", const="grid",
                      help="every combination of the values (the default)")
    mode.add_argument("--zip", dest="mode", action="store_const", const="zip",
                      help="the lists paired, value by value")
    p.add_argument("--kind", default="run", help="run (a history per variant, the default), "
                   "cea (its complex modes) or both (the two from one setup)")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the embedded "
                   "Dask cluster, one thread each (default 2)")
    p.add_argument("--cache", metavar="DIR", help="components path: the folder where each "
                   "part's reduction is kept and read back, shared by the variants")
    p.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler "
                   "(tcp://HOST:PORT) instead of the embedded cluster")
    p.add_argument("--out", metavar="DIR", required=True, help="directory of the variants' "
                   "outputs, sweep.csv and sweep.json")
    p.add_argument("--resume", action="store_true", help="keep the variants whose outputs "
                   "in DIR are complete and made with the same case and overrides (as run "
                   "--resume checks), continue the histories stopped short of solver.t_end, "
                   "make the others; an output of another case is refused")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    _plot_parser(sub)
    p = sub.add_parser("export", help="a history as time series for ParaView: the contact "
                       "points of each pair (gap, pressure) and, if output.field was stored, "
                       "the displacement on the mesh")
    p.add_argument("file", help="HDF5 file written by transient run")
    p.add_argument("--out", metavar="DIR", help="directory of the files (default: next to the "
                   "history, <name>_export)")
    p.add_argument("--format", choices=("xdmf", "vtu"), default="xdmf", help="xdmf: one "
                   ".xdmf (+ .h5) per series; vtu: one .vtu per row and a .pvd collection "
                   "(default xdmf)")
    p.add_argument("--every", type=int, default=1, metavar="K", help="export one stored row "
                   "in K, and the last one (default 1)")
    p.epilog = ("The displacement field rebuilds the model's mesh from the case text kept in "
                "the history; a reduced run stores its basis with the state (output.field).")
    return parser


def _plot_parser(sub):
    """`transient plot KIND ...`: one sub-subcommand per kind of picture."""
    kinds = sub.add_parser("plot", help="pictures (PNG) of a case or a history").add_subparsers(
        dest="kind", required=True)
    p = kinds.add_parser("compat", help="compatibility of each contact pair: shapes, singular "
                         "values and C(eps), raw and regularized gap observation")
    _case_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="directory of the PNG files")
    p.add_argument("--pair", metavar="NAME", help="only this contact pair")
    p.add_argument("--shapes", metavar="I,J,...", help="shape numbers to draw, from 1 by "
                   "increasing incompatibility (default: the first, the last kept, two beyond)")
    p = kinds.add_parser("cea", help="complex modes with friction: the stability diagram, "
                         "the shapes of the unstable modes, and (--mu) the map of the modes "
                         "against the friction coefficient")
    _case_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="directory of the PNG files")
    p.add_argument("--mu", metavar="START:STOP:COUNT", help="friction coefficients of the map "
                   "(or a comma-separated list), e.g. 0:0.6:13: one analysis each")
    p.add_argument("--pair", metavar="NAME", help="contact pair whose mu the map varies "
                   "(default: the first)")
    p.add_argument("--colour", choices=("out-of-plane", "magnitude"), default="out-of-plane",
                   help="the modes' colour: the signed displacement along the rotation's axis "
                   "(or the model's thinnest direction), whose zero is the nodal lines, or "
                   "its magnitude |u| (default out-of-plane)")
    p = kinds.add_parser("modal-frf", help="the transfer function between two sensors from "
                         "the case's modes (contact tied as solver.modes.tie says) against the "
                         "same case with other settings, and each mode's frequency shift (the "
                         "paper's figure 11)")
    _case_args(p)
    p.add_argument("--input", required=True, metavar="SENSOR", help="the sensor where the "
                   "force is applied (along its direction)")
    p.add_argument("--output", required=True, metavar="SENSOR", help="the sensor whose "
                   "displacement responds")
    p.add_argument("--against", action="append", default=[], metavar="KEY=VALUE",
                   help="an override of the second model, on top of --set (repeatable), "
                   "e.g. contact.pad_disc.rule=gauss")
    p.add_argument("--labels", nargs=2, metavar="TEXT", help="names of the two models "
                   "(default: case, and the --against overrides)")
    p.add_argument("--damping", type=float, default=0.01, help="modal damping ratio of the "
                   "transfer functions (default 0.01)")
    p.add_argument("--fmax", type=float, metavar="HZ", help="highest frequency drawn [Hz] "
                   "(default: just above the highest mode)")
    p.add_argument("-o", "--png", metavar="PNG", help="picture to write (default: "
                   "<case name>_modal_frf.png in the working directory)")
    series = ("scalar series to draw: full names (sensors/tip, energy/kinetic) or groups "
              "(sensors, energy); default: every sensor")
    p = kinds.add_parser("history", help="time histories of a history's sensors (or energy "
                         "terms), time in ms; each sensor about its preload")
    _history_args(p, "history")
    p.add_argument("--series", nargs="+", metavar="NAME", help=series)
    p.add_argument("--keep-preload", action="store_true", help="draw the sensors' values as "
                   "stored, their preload included (default: each about its value at the "
                   "run's first row, the preload it starts from)")
    p = kinds.add_parser("spectrum", help="amplitude spectra (Hann window, one-sided, log "
                         "amplitude) of a history's sensors, frequency in kHz")
    _history_args(p, "spectrum")
    p.add_argument("--series", nargs="+", metavar="NAME", help=series)
    p.add_argument("--fmax", type=float, metavar="HZ", help=FMAX_HELP)
    p = kinds.add_parser("frf", help="transfer function to a sensor of a history from a load "
                         "of its run (receptance, mobility or accelerance) or from another "
                         "series: H1 = Pxy / Pxx from Welch averages, magnitude, phase and "
                         "coherence")
    _history_args(p, "frf")
    p.add_argument("--input", metavar="NAME", help="loads/NAME, a load of the run's case "
                   "(its size times its signal, rebuilt from the case the history keeps), or "
                   "a series, e.g. sensors/tip (default: the case's one load that varies in "
                   "time)")
    p.add_argument("--output", required=True, metavar="NAME", help="output series, e.g. "
                   "sensors/tail")
    # not args.kind: that is the picture's (plot KIND)
    p.add_argument("--kind", dest="frf_kind", choices=("receptance", "mobility",
                                                       "accelerance"),
                   help="from a load: displacement, velocity or acceleration per unit of the "
                   "load (default receptance)")
    p.add_argument("--window", choices=("hann", "rectangular"), help="Welch segments: Hann, "
                   "half overlapping, or rectangular, end to end (default: rectangular from "
                   "the start of an impulse load, Hann otherwise)")
    p.add_argument("--segment", type=int, metavar="SAMPLES", help="samples per Welch segment "
                   "(default: every row from an impulse load's start; otherwise the largest power of "
                   "two up to a quarter of the rows)")
    p.add_argument("--fmax", type=float, metavar="HZ", help=FMAX_HELP)
    p = kinds.add_parser("spectrogram", help="time-frequency map of a series of a history: "
                         "short-time amplitude spectra in dB")
    _history_args(p, "spectrogram")
    p.add_argument("--series", metavar="NAME", help="the series (default: the first sensor)")
    p.add_argument("--segment", type=int, metavar="SAMPLES", help="samples per segment "
                   "(default: half the transfer function's default)")
    p.add_argument("--fmax", type=float, metavar="HZ", help=FMAX_HELP)
    p = kinds.add_parser("envelope", help="envelopes of a history's series and their "
                         "exponential growth (or decay) rate fitted over the linear phase")
    _history_args(p, "envelope")
    p.add_argument("--series", nargs="+", metavar="NAME", help=series)
    p.add_argument("--window", metavar="T0:T1", help="times [s] of the fit (default: a growth "
                   "from the start to a tenth of the envelope's peak, a decay from the peak to "
                   "a thousandth of it)")
    p.add_argument("--band", metavar="F0:F1", help="the series' part in this band [Hz] only "
                   "(one mode's growth among others)")
    p = kinds.add_parser("modal-growth", help="a run with output.field read mode by mode: its "
                         "reduced state projected on the left complex eigenvectors of its "
                         "system linearized at its preload, each mode's amplitude in time and "
                         "growth rate fitted over the linear phase, beside the CEA's real part "
                         "(a PNG, a CSV and the table printed)")
    _history_args(p, "modal-growth")
    p.add_argument("--csv", metavar="CSV", help="table to write (default: next to the "
                   "history, <name>_modal-growth.csv)")
    p.add_argument("--window", metavar="T0:T1", help="times [s] fitted whole by every mode "
                   "(default: from the loads' end over the linear phase, each mode as long "
                   "as its log amplitude stays within --tolerance of a line)")
    p.add_argument("--tolerance", type=float, metavar="RMS", help="RMS deviation of a mode's "
                   "log amplitude (and phase) from its line that a fit admits (default 0.01)")
    p = kinds.add_parser("friction", help="the friction of a run with output.contact: the "
                         "sliding's input and the slip's dissipated power in time, the shares "
                         "of the contact area open, sticking (|slip| < v_eps) and slipping, and "
                         "their map on Gamma at a time")
    _history_args(p, "friction")
    p.add_argument("--pair", metavar="NAME", help="contact pair (default: the first stored)")
    p.add_argument("--time", type=float, metavar="T", help="time [s] of the map (default: the "
                   "last row)")
    p = kinds.add_parser("sweep", help="a sweep's pictures: the stability map of a cea sweep "
                         "(frequency against a parameter, coloured by the real part), a run "
                         "sweep's growth, limit-cycle RMS and frequency against a parameter")
    p.add_argument("directory", help="the DIR of transient sweep --out")
    p.add_argument("--x", metavar="KEY", help="the parameter on the horizontal axis (default: "
                   "the first; the others split the variants into groups)")
    p.add_argument("-o", "--png", help="PNG file (default: DIR/sweep_<kind>.png)")
    p = kinds.add_parser("pressure", help="contact pressure maps on Gamma, one panel per "
                         "history side by side with one colour scale (e.g. fine, centre and "
                         "regularized rules)")
    p.add_argument("file", nargs="+", help="HDF5 files written by transient run with "
                   "output.contact = true")
    p.add_argument("--pair", metavar="NAME", help="contact pair (default: the first stored)")
    p.add_argument("--time", type=float, metavar="T", help="time [s]: each panel shows its "
                   "stored row nearest to it (default: the time of the largest total contact "
                   "force in the first file)")
    p.add_argument("--labels", nargs="+", metavar="TEXT", help="one title per file (default: "
                   "the file names)")
    p.add_argument("-o", "--png", metavar="PNG", help="picture to write (default: next to "
                   "the first file, <name>_pressure.png)")


def _history_args(p, kind):
    p.add_argument("file", help="HDF5 file written by transient run")
    p.add_argument("-o", "--png", metavar="PNG", help="picture to write (default: next to "
                   f"the history, <name>_{kind}.png)")
