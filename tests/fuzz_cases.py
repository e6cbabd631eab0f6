"""Seeded mutation fuzzer of the command line over the shipped cases: every mutant must end in
exit 0, 2 (one line 'error: ...'), 3 (an aborted run) or 130 (Ctrl-C), never anything else.

Each mutant starts from a small shipped case (bar_impact, two_bars) or a coarsened one
(pad_disc, drilled_cube), its run shortened to a few hundred steps and bounded by [limits], and
applies 1-3 mutations: a value of another type, an extreme value (0, -1, 1e300, 1e-300, nan,
inf, 2**63, empty and long lists), a deleted key, an unknown key, a renamed table, a misspelled
or switched kind, a reference to a missing part, set or material, a cell set used as a surface,
a mesh file that is missing, a directory, a /proc file or a truncated copy of tests/data,
deep nesting, control characters in strings and table names, damaged TOML text, malformed
`--set` literals, outputs that cannot be written, valid but unusual settings, Ctrl-C at a
random moment (--no-interrupts leaves it out: where SIGINT lands depends on the machine's
speed, every other outcome does not). Most mutants are `run`, some `modes`, `compat`, `cea`
and `plot cea` (friction turned on, --mu ranges bad, huge or infinite, --out unwritable);
others damage a copy of a history (truncated, bytes overwritten, datasets or attributes
deleted or retyped, the stored case text broken) and give it to `info`, `plot`, `export` or
`run --resume`. With `--sweeps SHARE`, that share of the mutants run `transient sweep` (a
mutated command line, files of the user at the names it writes, a second campaign on its
folder, a resume after a changed --param list or a killed sweep: sweep_mutant); a file the
package did not write that it replaced, or a row naming an output of other values, is a
FAILURE.

Mutants run in-process through `transient.cli.main` in a worker subprocess (many in sequence)
with an address-space limit (RLIMIT_AS) and a per-mutant timeout; a crash, a timeout or a
MemoryError restarts the worker and is reported, so a runaway mutant never hangs the fuzzer.
Warnings are recorded (`simplefilter("always")`), stdout and stderr captured at the Python and
the file-descriptor level. Outcome classes are the counts of exit 0, 2, 3 and 130 and of the
mutants with a FAILURE: another exit code, an uncaught exception, a traceback, a Python warning,
an exception Python could only ignore (in a finalizer), an error message of more than one line,
not starting with 'error: ' or naming no file, stderr output on success, a timeout, the memory
bound, a crash. One example is shown per failure class. Mutant i of seed S makes the same
mutations on every machine (a base history's bytes hold its timings and paths, so the same
overwritten bytes may hit another structure): `--only I` runs it again, `--keep DIR` keeps its
files so its command line reruns as printed. The exit code is 1 when a FAILURE occurred.

    python tests/fuzz_cases.py [--mutants N] [--seed S] [--cases a,b] [--json] [--keep DIR]
                               [--only I,J] [--no-interrupts] [--timeout SECONDS]
                               [--memory-gb GB] [--sweeps SHARE]
"""
import argparse
import copy
import functools
import json
import os
import random
import re
import resource
import select
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import tomllib
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
MESHES = ROOT / "tests" / "data"


def mesh_files():
    """The files of tests/data, in order: its folders (a shipped case's meshes at a test size)
    are not one mesh file each."""
    return sorted(p for p in MESHES.iterdir() if p.is_file())

# Each base: the shipped file, the keys that coarsen it (so one setup takes about a second) and
# t_end, a few hundred steps at the base's step (the step of its scheme at that mesh).
BASES = {
    "bar_impact": ({}, 3e-5),
    "two_bars": ({}, 5e-5),
    "pad_disc": ({"parts.disc.mesh.divisions": [2, 36, 1], "parts.disc.mesh.element": "hex8",
                  "parts.pad.mesh.divisions": [3, 8, 1, 1], "parts.pad.mesh.element": "hex8",
                  "solver.reduction.fmax": 6000.0, "solver.modes.fmax": 6000.0}, 2e-3),
    # its contact statics (250 shapes of 624 points) would make most of the setup and of the
    # exponential scheme's coefficients: the larger 30 are kept
    "drilled_cube": ({"parts.lower.mesh.divisions": [6, 6, 3],
                      "parts.upper.mesh.divisions": [2, 2, 2],
                      "solver.reduction.statics_tolerance": 0.3}, 5e-4),
}
# The package's own bounds, well inside the worker's: a mutant that makes the mesh or the run
# large is refused by them (exit 2) instead of taking minutes or the fuzzer's memory.
LIMITS = {"memory": 1.0, "steps": 50000}
# Cell sets of each base (surfaces must be face sets) and face sets (region_materials wants
# cell sets).
CELL_SETS = {"bar_impact": ["bar.all"], "two_bars": ["left.all", "right.all"],
             "pad_disc": ["pad.all", "pad.lining", "pad.backplate", "disc.all"],
             "drilled_cube": ["lower.all", "upper.all"]}
FACE_SETS = {"bar_impact": ["bar.xmin", "bar.ymax"], "two_bars": ["left.xmin", "right.xmax"],
             "pad_disc": ["pad.friction", "pad.back", "disc.outer"],
             "drilled_cube": ["lower.hole", "upper.zmax"]}

TIMEOUT_S = 60.0          # a guard against a hung mutant, far above any mutant's cost
MEMORY_GB = 3.0           # RLIMIT_AS of the worker; limits.memory keeps models far below it
OUTPUT_CHARS = 4000       # of stdout kept per mutant (stdout is not judged, only kept)
STDERR_CHARS = 100000     # of stderr kept (judged: one line 'error: ...' is far shorter)
RESTART_VM_GB = 2.0       # a worker grown beyond this is restarted before the next mutant
SUCCESS_CODES = (0, 2, 3, 130)
CASE_COMMANDS = (("run", 78), ("modes", 12), ("compat", 10), ("cea", 10), ("plot cea", 5))
HISTORY_SHARE = 0.15      # mutants that damage a history instead of a case

sys.path.insert(0, str(ROOT / "tools"))      # the TOML writer the brake tools share
from toml_writer import Raw, dumps, toml_value  # noqa: E402


# ----------------------------------------------------------------------------- case dicts


def paths_of(data, prefix=()):
    """Every key path of a nested dict, tables and values, depth first."""
    out = []
    for k, v in data.items():
        out.append(prefix + (k,))
        if isinstance(v, dict):
            out.extend(paths_of(v, prefix + (k,)))
    return out


def get(data, path):
    for k in path:
        data = data[k]
    return data


def put(data, path, value):
    """data[path] = value, making the tables on the way (a value in the way becomes one)."""
    for k in path[:-1]:
        if not isinstance(data.get(k), dict):
            data[k] = {}
        data = data[k]
    data[path[-1]] = value


def dotted(path):
    return ".".join(path)


def base_case(name):
    """A base's case dict: the shipped file, coarsened, shortened and bounded."""
    data = tomllib.loads((CASES / f"{name}.toml").read_text())
    coarse, t_end = BASES[name]
    for key, value in coarse.items():
        put(data, tuple(key.split(".")), value)
    put(data, ("solver", "t_end"), t_end)
    data["limits"] = dict(LIMITS)
    return data


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def misspell(rng, word):
    """A near miss of word: a letter dropped, doubled or swapped, a case or a space changed."""
    if not word:
        return "x"
    i = rng.randrange(len(word))
    choices = [word[:i] + word[i + 1:], word[:i] + word[i] + word[i:], word.upper(),
               word + " ", "_" + word, word.capitalize() + "s"]
    if len(word) > 1:
        j = min(i, len(word) - 2)
        choices.append(word[:j] + word[j + 1] + word[j] + word[j + 2:])
    out = rng.choice(choices)
    return out if out != word else word + "x"


# ----------------------------------------------------------------------------- mutations

EXTREMES = [0, -1, 1e300, -1e300, 1e-300, float("nan"), float("inf"), -float("inf"), "nan",
            2 ** 63, -2 ** 63 - 1, 2 ** 64 + 1, 10 ** 40, [], "long list", 0.5, 1e30]
OTHER_TYPES = {"str": ["abc", "1.5", ""], "number": [1, 2.5], "bool": [True, False],
               "list": [[1, 2, 3], ["a"]], "table": [{"x": 1}, {}]}
# "\ud800" is refused by TOML; "\udcff" is how Python passes an argv byte that is not
# UTF-8 (surrogateescape), so it goes in command lines (WRITE_TARGETS, MALFORMED_SETS)
CONTROL = ["\n", "\r\n", "\t", "\x00", "\x07", "\x1b[31m", "\x7f", "\x85", "\u2028",
           "\ufeff", "\x1c", "\ud800"]
UNKNOWN_KEYS = ["colour", "Kind", "kind ", "t_end", "E", "", "x.y", "\u00e9", "a\nb", "_"]
BAD_NAMES = ["renamed", "a b", "a.b", "\u00e4", "x\ny", "x\x1b[31m", "", "-", "0", "\x00"]
DEPTHS = [30, 300, 3000, 30000]
MALFORMED_SETS = ["solver.t_end=[1,", "solver.t_end=", "=1", "solver..t_end=1", ".=1",
                  "solver.t_end", "solver=3", "solver.t_end.x=1", "solver.t_end=1e400",
                  "solver.t_end=nan", "solver.t_end=-inf", "solver.t_end=0x1F",
                  "solver.t_end=1979-05-27", "title=1979-05-27T07:32:00Z", 'title="\\u0000"',
                  'title="a\nb"', "parts=[]", "materials={}", "solver.t_end=" + "1" * 5000,
                  "title=" + "[" * 5000, "a." * 3000 + "b=1", "x" * 10000 + "=1",
                  "solver.t_end=1e-300", "solver.t_end=\x00", "limits.steps=-1",
                  "solver.t_end = 1e-5", " solver.t_end=1e-5", "solver.t_end==1",
                  'title="\\ud800"', "output={}", "solver.chunk=9223372036854775808",
                  "title=\udcff", "output.file=\udcff.h5"]
WRITE_TARGETS = ["/proc/fuzz.h5", "/proc/self/status", "/sys/fuzz.h5", "/dev/null",
                 "/dev/full", "/", "DIR", "DIR/missing/out.h5", "", "CASE", "CASE/out.h5",
                 "FIFO", "DIR/a\x00b.h5", "DIR/" + "x" * 300 + ".h5", "DIR/out\n.h5",
                 "FOREIGN", "LOCKED", "DIR/out \u00e9.h5", "DIR/\udcff.h5"]
# valid but unusual settings: deeper code paths (key path pattern, values)
VARIATIONS = [
    ("solver.scheme", ["explicit", "implicit", "exponential"]),
    ("solver.reduction.enabled", [True, False]),
    ("solver.reduction.statics", [True, False]),
    ("solver.reduction.statics_tolerance", [0.0, 1.0]),
    ("solver.reduction.fmax", [100.0, 3000.0, 60000.0]),
    ("contact.*.rule", ["fine", "centre", "greedy", "sampled"]),
    ("contact.*.regularized", [True, False]),
    ("contact.*.eps", ["auto", 0.0, 1e-3, 1.0]),
    ("contact.*.law.kind", ["exponential", "linear", "bilateral"]),
    ("contact.*.formulation", ["dual", "primal"]),
    ("contact.*.project", ["surface1", "surface2"]),
    ("contact.*.norm", ["identity"]),
    ("contact.*.master", ["surface2"]),
    ("contact.*.candidates", ["surface1", "surface2"]),
    ("contact.*.weights", ["nnls", "best", "exact"]),
    ("contact.*.points", [1, 5]),
    ("contact.*.order", [1, 2, 20]),
    ("contact.*.k", [1.0, 1e20]),
    ("contact.*.sampling_tolerance", [1.0, 1e-8]),
    ("parts.*.mesh.element", ["hex8", "hex20", "tet4", "tet10", "wedge6", "wedge15"]),
    ("parts.*.mesh.filled", [True]),
    ("parts.*.mesh.ogrid_cells", [1, 3]),
    ("solver.mass", ["lumped", "consistent"]),
    ("solver.corrector", ["propagated", "implicit"]),
    ("solver.corrections", [0, 5]),
    ("solver.chunk", [1, 7]),
    ("solver.dt", [1e-7, 1e-5]),
    ("solver.force_dt", [True]),
    ("solver.drift_tolerance", [1e-12, 1e6]),
    ("solver.damping.modal", [0.01, 10.0]),
    ("solver.damping.residual", [0.5]),
    ("solver.damping.alpha", [1.0, 1e6]),
    ("solver.damping.beta", [1e-7, 1e-3]),
    ("solver.linear_solver", ["cholmod", "pardiso", "superlu"]),
    ("solver.newton.max_iter", [1]),
    ("solver.newton.tolerance", [1e-300, 0.5]),
    ("solver.modes.count", [1, 3]),
    ("solver.modes.fmax", [0.0, 1.0]),
    ("solver.modes.shift", [0.0, 1e5, -1e6]),
    ("solver.quadrature.stiffness", [1, 8]),
    ("solver.quadrature.mass", [1, 8]),
    ("output.every", [3, 100000]),
    ("output.field", [True]),
    ("output.contact", [True, False]),
    ("output.energy", [False]),
    ("output.sensors", [False]),
    ("initial.*.velocity", [[0.0, 0.0, -100.0], [1e3, 0.0, 0.0]]),
    ("loads.*.value", [-1e6, 1e9]),
    ("limits.memory", [1e-6]),
    ("limits.steps", [1]),
]


@dataclass
class Draft:
    """A mutant being built: its case dict or history, command and the notes saying what was
    done; the parent writes its files and the worker runs `argv`."""
    rng: random.Random
    directory: Path
    base: str
    data: dict = None
    command: str = "run"
    options: list = field(default_factory=list)
    output: str = "DIR/out.h5"     # -o of run ('DIR/...': in the mutant's directory; None: no -o)
    text_edit: object = None       # callable(bytes) -> bytes applied to the written case file
    interrupt: float = None        # seconds after which SIGINT is sent, None: never
    locked: bool = False           # the parent holds the -o file's lock while it runs
    notes: list = field(default_factory=list)
    history: Path = None           # history mutants: the damaged copy
    case_file: Path = None
    interrupts: bool = True        # Ctrl-C mutations allowed (their outcome depends on timing)

    def note(self, text):
        self.notes.append(one_line(text))

    def paths(self, want=None):
        """Key paths of the case dict, filtered by want(path, value)."""
        return [p for p in paths_of(self.data) if want is None or want(p, get(self.data, p))]

    def pick(self, choices):
        return self.rng.choice(choices)

    def names(self, table):
        """Names of the tables in data[table] (none if a mutation made it something else)."""
        node = self.data.get(table)
        return [k for k, v in node.items() if isinstance(v, dict)] if isinstance(node,
                                                                                  dict) else []


def one_line(text):
    """text with its non-printable characters escaped (for notes and examples)."""
    return "".join(c if " " <= c <= "~" else c.encode("unicode_escape").decode("ascii")
                   for c in str(text))


def short(value):
    text = one_line(repr(value) if isinstance(value, (str, bytes)) and not isinstance(value, Raw)
                    else toml_value(value))
    return text if len(text) <= 60 else text[:40] + f"...({len(text)} chars)"


def m_type(d):
    """A value replaced by one of another type."""
    leaves = d.paths(lambda p, v: not isinstance(v, dict))
    if not leaves:
        return False
    path = d.pick(leaves)
    old = get(d.data, path)
    kind = ("bool" if isinstance(old, bool) else "number" if is_number(old) else
            "str" if isinstance(old, str) else "list")
    new = d.pick(OTHER_TYPES[d.pick([k for k in OTHER_TYPES if k != kind])])
    put(d.data, path, copy.deepcopy(new))
    d.note(f"type: {dotted(path)} = {short(new)}")
    return True


def m_extreme(d):
    """A number (or one item of a list of numbers) replaced by an extreme value."""
    numeric = d.paths(lambda p, v: is_number(v) or (isinstance(v, list) and v
                                                    and all(is_number(x) for x in v)))
    if not numeric:
        return False
    path = d.pick(numeric)
    value = d.pick(EXTREMES)
    if value == "long list":
        value = [1.0] * d.pick([4, 1000, 100000])
    old = get(d.data, path)
    if isinstance(old, list) and not isinstance(value, list) and d.rng.random() < 0.7:
        i = d.rng.randrange(len(old))
        old[i] = value
        d.note(f"extreme: {dotted(path)}[{i}] = {short(value)}")
    else:
        put(d.data, path, value)
        d.note(f"extreme: {dotted(path)} = {short(value)}")
    return True


def m_delete(d):
    """A key deleted, most often a required one."""
    keys = d.paths()
    if not keys:
        return False
    required = [p for p in keys if p[-1] in required_names()]
    path = d.pick(required if required and d.rng.random() < 0.8 else keys)
    del get(d.data, path[:-1])[path[-1]]
    d.note(f"delete: {dotted(path)}")
    return True


def m_unknown(d):
    """An unknown key in a table, or a near miss of one of its keys."""
    tables = [()] + d.paths(lambda p, v: isinstance(v, dict))
    path = d.pick(tables)
    table = get(d.data, path)
    name = (misspell(d.rng, d.pick(list(table))) if table and d.rng.random() < 0.5
            else d.pick(UNKNOWN_KEYS))
    table[name] = d.pick([1, "x", [1.0], {"y": 2}])
    d.note(f"unknown key: {dotted(path + (name,))}")
    return True


def m_rename(d):
    """A table renamed: a near miss, another name, or one that cannot be a key."""
    tables = d.paths(lambda p, v: isinstance(v, dict))
    if not tables:
        return False
    path = d.pick(tables)
    name = misspell(d.rng, path[-1]) if d.rng.random() < 0.4 else d.pick(BAD_NAMES)
    parent = get(d.data, path[:-1])
    parent[name] = parent.pop(path[-1])
    d.note(f"rename: {dotted(path)} -> {short(name)}")
    return True


# the kinds of each variant (by the key above `kind`) and the values of other choices
VARIANTS = {"mesh": ["box", "drilled_box", "annular_disc", "brake_pad", "file"],
            "signal": ["constant", "step", "impulse", "sine", "chirp", "table"],
            "loads": ["pressure", "force", "gravity"], "law": ["exponential", "linear",
                                                              "bilateral"],
            "sets": ["plane", "box", "cylinder"]}
CHOICES = {"scheme": ["explicit", "implicit", "exponential"],
           "element": ["hex8", "hex20", "tet4", "tet10", "wedge6", "wedge15"],
           "rule": ["fine", "centre", "greedy", "sampled"],
           "corrector": ["evaluated", "propagated", "implicit"],
           "mass": ["auto", "lumped", "consistent"],
           "linear_solver": ["auto", "cholmod", "pardiso", "superlu"]}


def m_kind(d):
    """A kind (or another choice) misspelled, switched to another kind under the old keys, or
    of another type."""
    kinds = d.paths(lambda p, v: p[-1] == "kind" or p[-1] in CHOICES)
    if not kinds:
        return False
    path = d.pick(kinds)
    old = get(d.data, path)
    family = (CHOICES.get(path[-1]) or
              next((VARIANTS[k] for k in reversed(path[:-1]) if k in VARIANTS), None))
    roll = d.rng.random()
    if roll < 0.4 or not isinstance(old, str):
        new = misspell(d.rng, str(old))
    elif roll < 0.8 and family:
        new = d.pick([k for k in family if k != old] or family)
    else:
        new = d.pick([None, 1, True, ["box"], "", "Box"])
    if new is None:
        del get(d.data, path[:-1])[path[-1]]
    else:
        put(d.data, path, new)
    d.note(f"kind: {dotted(path)} = {short(new) if new is not None else '(deleted)'}")
    return True


def reference_keys(data):
    """(path, kind) of every reference: 'set' (PART.SET), 'part', 'parts', 'material'."""
    out = []
    for p in paths_of(data):
        v = get(data, p)
        if p[0] == "parts" and p[-1] == "material" and len(p) == 3:
            out.append((p, "material"))
        elif p[0] == "parts" and len(p) == 4 and p[2] == "region_materials":
            out.append((p, "material"))
        elif p[-1] in ("set", "surface1", "surface2") and isinstance(v, str) and len(p) == 3:
            out.append((p, "set"))
        elif p[-1] == "part" and len(p) == 3:
            out.append((p, "part"))
        elif p[-1] == "parts" and p[0] == "loads":
            out.append((p, "parts"))
    return out


def m_reference(d):
    """A reference to a part, set or material that does not exist (or is spelt differently)."""
    refs = reference_keys(d.data)
    if not refs:
        return False
    path, kind = d.pick(refs)
    old = get(d.data, path)
    part, _, cset = (old if isinstance(old, str) else "x.y").partition(".")
    other = d.pick(d.names("parts") or ["p"])
    if kind == "set":
        new = d.pick(["nosuch", f"nosuch.{cset}", f"{part}.nosuch", f"{part}.", f".{cset}",
                      f"{part}.{cset}.x", "", f"{part.upper()}.{cset}", f"{old} ",
                      f"{other}.{cset}", f"{part}.{cset.upper()}"])
    elif kind == "parts":
        new = d.pick([["nosuch"], [other, other], [""], [other.upper()]])
    else:
        new = d.pick(["nosuch", "", str(old).upper(), f"{old} ", f"{old}.x"])
    put(d.data, path, new)
    d.note(f"reference: {dotted(path)} = {short(new)}")
    return True


def m_cell_set(d):
    """A cell set where a surface is expected ('PART.all'), or a face set as a region."""
    surfaces = [p for p, kind in reference_keys(d.data) if kind == "set"]
    if d.rng.random() < 0.25 or not surfaces:
        part = d.pick(d.names("parts") or ["x"])
        face = d.pick(FACE_SETS[d.base]).split(".", 1)[1]
        path = ("parts", part, "region_materials", face)
        put(d.data, path, d.pick(d.names("materials") or ["steel"]))
        d.note(f"face set as a region: {dotted(path)}")
        return True
    path = d.pick(surfaces)
    new = d.pick(CELL_SETS[d.base])
    put(d.data, path, new)
    d.note(f"cell set as a surface: {dotted(path)} = {new}")
    return True


def m_mesh_file(d):
    """A part's mesh read from a file: missing, a directory, /proc, a device, a damaged or
    intact copy of tests/data."""
    parts = d.names("parts")
    if not parts:
        return False
    part = d.pick(parts)
    sources = mesh_files()
    choice = d.pick(["missing", "directory", "proc", "device", "truncated", "truncated",
                     "corrupted", "intact", "intact", "empty", "case", "nul", "newline"])
    if choice in ("truncated", "corrupted", "intact"):
        source = d.pick(sources)
        data = source.read_bytes()
        if choice == "truncated":
            data = data[:d.rng.randrange(len(data))]
        elif choice == "corrupted":
            data = bytearray(data)
            for _ in range(d.rng.randint(1, 4)):
                data[d.rng.randrange(len(data))] = d.rng.choice(b"-0123456789.eE \n\x00\xff")
            data = bytes(data)
        target = d.directory / f"mesh{source.suffix}"
        target.write_bytes(data)
        path = target.name if d.rng.random() < 0.7 else str(target)
        what = f"{choice} copy of {source.name}"
    else:
        if choice == "empty":
            (d.directory / "empty.msh").write_bytes(b"")
        elif choice == "newline":
            # a file that exists under a name with a newline, so the messages that follow
            # the read name it
            shutil.copy(MESHES / "two_hex_v4.msh", d.directory / "mesh\n.msh")
        path = {"missing": "missing.msh", "directory": d.pick([".", str(d.directory)]),
                "proc": d.pick(["/proc/self/status", "/proc/self/cmdline", "/proc"]),
                "device": d.pick(["/dev/null", "/dev/zero"]), "empty": "empty.msh",
                "case": "case.toml", "nul": "mesh\x00.msh", "newline": "mesh\n.msh"}[choice]
        what = choice
    mesh = {"kind": "file", "path": path}
    if d.rng.random() < 0.3:
        mesh["scale"] = d.pick([1e-3, 1e300, 1e-300])
    d.data["parts"][part]["mesh"] = mesh
    d.note(f"mesh file: parts.{part}.mesh.path = {short(path)} ({what})")
    return True


def m_deep(d):
    """Deeply nested arrays or inline tables, in place of a value or under a new key."""
    depth = d.pick(DEPTHS)
    raw = Raw("[" * depth + "1" + "]" * depth if d.rng.random() < 0.6 else
              "{a = " * depth + "1" + "}" * depth)
    leaves = d.paths(lambda p, v: not isinstance(v, dict))
    if leaves and d.rng.random() < 0.6:
        path = d.pick(leaves)
    else:
        tables = d.paths(lambda p, v: isinstance(v, dict) and p[0] in ("parts", "contact"))
        path = d.pick(tables or [()]) + ("deep",)
    put(d.data, path, raw)
    d.note(f"deep: {dotted(path)} nested {depth} deep")
    return True


def m_control(d):
    """Control characters, newlines, a BOM or a lone surrogate in a string or a table name."""
    char = d.pick(CONTROL)
    strings = d.paths(lambda p, v: isinstance(v, str))
    roll = d.rng.random()
    if roll < 0.5 and strings:
        path = d.pick(strings)
        old = get(d.data, path)
        i = d.rng.randrange(len(old) + 1)
        put(d.data, path, old[:i] + char + old[i:])
        d.note(f"control: {dotted(path)} gets {short(char)}")
    elif roll < 0.8:
        named = d.paths(lambda p, v: isinstance(v, dict) and len(p) == 2)
        if not named:
            return False
        path = d.pick(named)
        parent = get(d.data, path[:-1])
        name = path[-1] + char
        parent[name] = parent.pop(path[-1])
        d.note(f"control: table {dotted(path)} renamed {short(name)}")
    else:
        d.data["title"] = d.pick(["", "x" * 10 ** 6]) + char
        d.note(f"control: title with {short(char)}")
    return True


def _truncate_text(rng):
    return lambda b: b[:rng.randrange(len(b) + 1)]


def _insert(rng, junk):
    def edit(b):
        i = rng.randrange(len(b) + 1)
        return b[:i] + junk + b[i:]
    return edit


def m_text(d):
    """The TOML text damaged: cut, raw control or non-UTF-8 bytes, a BOM, a repeated header,
    CRLF line ends, no text at all."""
    rng = d.rng
    choice = d.pick(["truncate", "control", "utf8", "bom", "header", "crlf", "empty", "nul"])
    d.text_edit = {"truncate": _truncate_text(rng), "control": _insert(rng, b"\x01"),
                   "utf8": _insert(rng, b"\xff\xfe"), "bom": lambda b: b"\xef\xbb\xbf" + b,
                   "header": lambda b: b + b"\n[solver]\n", "crlf": lambda b:
                   b.replace(b"\n", b"\r\n"), "empty": lambda b: b"",
                   "nul": _insert(rng, b"\x00")}[choice]
    d.note(f"text: {choice}")
    return True


def m_set(d):
    """A malformed --set, or a --set of an extreme value on a real key."""
    if d.rng.random() < 0.6:
        text = d.pick(MALFORMED_SETS)
    else:
        path = d.pick(d.paths(lambda p, v: not isinstance(v, dict)) or [("title",)])
        value = d.pick(["[]", "nan", "inf", "1e309", "-0.0", "true", "{}", '""', "bare word",
                        "9223372036854775808", "[1, 2", "'\\x'", "[[1]]"])
        text = f"{dotted(path)}={value}"
    d.options += ["--set", text]
    d.note(f"--set {short(text)}")
    return True


def m_output(d):
    """Outputs that cannot be written: -o, output.file or output.vtu at a /proc path, a
    directory, a device, a FIFO, a foreign or locked file, a name too long..."""
    target = d.pick(WRITE_TARGETS)
    where = d.pick(["-o", "-o", "output.file", "output.vtu"] if d.command == "run"
                   else ["output.vtu"])
    if target == "FIFO":
        if not (d.directory / "fifo.h5").exists():
            os.mkfifo(d.directory / "fifo.h5")
        target = "DIR/fifo.h5"
    elif target == "FOREIGN":
        shutil.copy(d.pick(mesh_files()), d.directory / "foreign.h5")
        target = "DIR/foreign.h5"
    elif target == "LOCKED":
        if where != "-o":
            return False
        target, d.locked = "DIR/locked.h5", True
    if where == "-o":
        d.output = target
    else:
        put(d.data, tuple(where.split(".")), resolve(target, d))
        if where == "output.file":
            d.output = None
    d.note(f"output: {where} = {short(target)}")
    return True


def m_variation(d):
    """A valid but unusual setting (scheme, rule, element, damping...), or a new load,
    sensor or geometric set."""
    roll = d.rng.random()
    if roll < 0.75:
        options = []
        for pattern, values in VARIATIONS:
            table, star, rest = pattern.partition(".*.")
            # a wildcard stands for each named table present; the key itself may be absent
            paths = ([(table, name, *rest.split(".")) for name in d.names(table)] if star
                     else [tuple(pattern.split("."))])
            options += [(p, values) for p in paths]
        path, values = d.pick(options)
        value = copy.deepcopy(d.pick(values))
        put(d.data, path, value)
        d.note(f"variation: {dotted(path)} = {short(value)}")
        return True
    part = d.pick(d.names("parts") or ["x"])
    if roll < 0.85:
        kind = d.pick(["plane", "box", "cylinder"])
        params = {"plane": {"point": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0]},
                  "box": {"min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1e-3]},
                  "cylinder": {"point": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0],
                               "radius": d.pick([0.005, 0.1])}}[kind]
        put(d.data, ("parts", part, "sets", "fz"), {"kind": kind, "tol": d.pick([1e-9, 1e-3]),
                                                    **params})
        use = d.pick(["constraints", "loads"])
        put(d.data, (use, "fz"), {"set": f"{part}.fz"} if use == "constraints" else
            {"kind": "pressure", "set": f"{part}.fz", "value": 1e5})
        d.note(f"variation: {kind} set {part}.fz used by {use}.fz")
    elif roll < 0.95:
        signal_ = d.pick([{"kind": "step", "rise": 1e-5}, {"kind": "sine", "frequency": 3e3},
                          {"kind": "chirp", "f0": 0.0, "f1": 1e4, "duration": 1e-4},
                          {"kind": "table", "times": [0.0, 1e-5], "values": [0.0, 1.0]},
                          {"kind": "impulse", "duration": 1e-6}])
        load = d.pick([{"kind": "gravity", "vector": [0.0, 0.0, -9.81]},
                       {"kind": "force", "part": part, "point": [0.0, 0.0, 0.0],
                        "vector": [1.0, 1.0, 1.0]}])
        put(d.data, ("loads", "fz"), {**load, "signal": signal_})
        d.note(f"variation: {load['kind']} load with a {signal_['kind']} signal")
    else:
        put(d.data, ("sensors", "fz"), {"part": part, "point": [1e3, -1e3, 0.0],
                                        "direction": [0.0, 1.0, 1.0]})
        d.note(f"variation: sensor far from {part}")
    return True


def m_interrupt(d):
    """Ctrl-C (SIGINT) at a random moment of the command."""
    if d.command != "run" or not d.interrupts:
        return False
    # log-uniform from the setup's first milliseconds to past the end of most runs
    d.interrupt = round(10 ** d.rng.uniform(-2.5, 0.5), 4)
    d.note(f"SIGINT after {d.interrupt} s")
    return True


CASE_MUTATIONS = [(m_type, 10), (m_extreme, 12), (m_delete, 8), (m_unknown, 6), (m_rename, 6),
                  (m_kind, 6), (m_reference, 8), (m_cell_set, 5), (m_mesh_file, 7), (m_deep, 4),
                  (m_control, 6), (m_text, 4), (m_set, 6), (m_output, 6), (m_variation, 14),
                  (m_interrupt, 3)]


@functools.lru_cache(maxsize=None)
def required_names():
    """Names of the keys the schema requires somewhere (deleting one is a typical mistake)."""
    from transient.case import nodes, schema
    names = set()

    def walk(node):
        if isinstance(node, nodes.Table):
            for k, sub in node.fields.items():
                if ((isinstance(sub, nodes.Value) and sub.default is nodes.REQUIRED)
                        or (isinstance(sub, nodes.Variant) and sub.default is None)
                        or (isinstance(sub, nodes.Named) and sub.min_items)):
                    names.add(k)
                walk(sub)
        elif isinstance(node, nodes.Named):
            walk(node.item)
        elif isinstance(node, nodes.Variant):
            if node.default is None:
                names.add("kind")
            for fields in [node.common, *node.options.values()]:
                walk(nodes.Table("", fields))

    walk(schema.CASE)
    return frozenset(names)


def resolve(target, d):
    """A write target with its placeholders (DIR, CASE) made paths."""
    return (target.replace("DIR", str(d.directory)).replace("CASE", str(d.case_file))
            if target else target)


# ----------------------------------------------------------------------------- analyses

# `plot cea --mu`: good ranges, and bad, huge, infinite or malformed ones
MU_TEXTS = ["0:0.4:2", "0.1,0.3", "0.2", "0:0.6:1", "a:b:c", "0:1", "0:1:2:3", "0:inf:3",
            "-1e308:1e308:3", "0:0.5:100000", "0:0.5:0", "0:0.5:" + "9" * 30, "-1:0:2",
            "0:20:2", "0.1,nan", "1,2,x", "", ",", ",".join(["0.1"] * 20001), "1e300",
            "0:0.4:1e3"]
PLOT_TARGETS = ["DIR/plots", "DIR/plots", "DIR/plots", "DIR", "/proc/plots", "CASE", "/dev/null",
                "DIR/" + "x" * 300, "DIR/a\x00b", "/"]


def analysis_case(d):
    """Before the mutations of a cea or plot cea: friction on a pair some of the time (the
    coarse pad_disc's disc turns; elsewhere no motion gives the sliding, which is refused)."""
    pairs = d.names("contact")
    if pairs and d.rng.random() < 0.7:
        pair = d.pick(pairs)
        mu = d.pick([0.0, 0.2, 0.4, 0.6])
        put(d.data, ("contact", pair, "friction", "mu"), mu)
        d.note(f"analysis: contact.{pair}.friction.mu = {mu}")


def analysis_argv(d):
    """The command line of a cea or plot cea of d's case: plot cea's --out, --mu, --pair."""
    if d.command == "cea":
        return ["cea", str(d.case_file)] + d.options + (["--json"] if d.rng.random() < 0.3
                                                          else [])
    out = d.pick(PLOT_TARGETS)
    argv = ["plot", "cea", str(d.case_file), "--out", resolve(out, d)] + d.options
    notes = [f"--out {short(out)}"]
    if d.rng.random() < 0.6:
        mu = d.pick(MU_TEXTS)
        argv.append(f"--mu={mu}")
        notes.append(f"--mu {short(mu)}")
    if d.rng.random() < 0.2:
        pair = d.pick(["nosuch", "", "pad_disc", "impact", "wall", "interface"])
        argv += ["--pair", pair]
        notes.append(f"--pair {short(pair)}")
    d.note("plot cea: " + ", ".join(notes))
    return argv


# ----------------------------------------------------------------------------- histories

# histories made once per fuzz session, from a base case: name -> (base, extra keys, exit)
HISTORY_RUNS = {"full": ("bar_impact", {"output.field": True, "output.every": 3}, 0),
                "reduced": ("pad_disc", {"output.field": True}, 0),
                "aborted": ("bar_impact", {"solver.dt": 1e-5, "solver.force_dt": True,
                                           "solver.t_end": 3e-3}, 3)}
HISTORY_COMMANDS = [("info", 25), ("export", 20), ("resume", 20), ("plot history", 10),
                    ("plot spectrum", 7), ("plot frf", 7), ("plot pressure", 6)]
BAD_ATTRS = [-1, 2 ** 62, 1.5, "abc", float("nan"), [1, 2], b"\xff\xfe", "{", "[1,", "",
             "[" * 100000 + "]" * 100000, "x" * 100000, True, "null", "{}"]


def history_layout(path):
    """(datasets, groups, root attributes, attributes of groups) of a history file."""
    import h5py
    datasets, groups = [], []
    with h5py.File(path, "r", locking=False) as f:
        f.visititems(lambda n, o: (datasets if isinstance(o, h5py.Dataset) else groups)
                     .append(n))
        attrs = list(f.attrs)
        group_attrs = [(g, a) for g in groups for a in f[g].attrs]
    return datasets, groups, attrs, group_attrs


def damage_history(d, layout):
    """One damage to the history copy d.history; True if it is no longer an HDF5 file that
    h5py opens (truncated, overwritten, replaced), so no other damage can follow."""
    import h5py
    import numpy as np
    datasets, groups, attrs, group_attrs = layout
    path, rng = d.history, d.rng
    choice = d.pick(["truncate", "overwrite", "replace", "dataset", "dataset", "drop", "drop",
                     "attr", "attr", "attr", "case", "extra"])
    if choice == "truncate":
        size = path.stat().st_size
        cut = rng.randrange(size)
        os.truncate(path, cut)
        d.note(f"history: truncated to {cut} of {size} bytes")
        return True
    elif choice == "overwrite":
        data = bytearray(path.read_bytes())
        spots = [rng.randrange(len(data)) for _ in range(rng.randint(1, 16))]
        for i in spots:
            data[i] = rng.randrange(256)
        path.write_bytes(bytes(data))
        d.note(f"history: {len(spots)} bytes overwritten from {min(spots)}")
        return True
    elif choice == "replace":
        what = d.pick(["empty", "case text", "foreign hdf5", "directory", "missing"])
        path.unlink()
        if what == "empty":
            path.write_bytes(b"")
        elif what == "case text":
            path.write_text(dumps(base_case(d.base)))
        elif what == "foreign hdf5":
            with h5py.File(path, "w") as f:
                f["time"] = np.arange(3.0)
                f.attrs["rows"] = 3
        elif what == "directory":
            path.mkdir()
        d.note(f"history: replaced by {what}")
        return True
    elif choice == "dataset" and datasets:
        name = d.pick(datasets)
        what = d.pick(["shorter", "strings", "2-D", "scalar", "group", "nan", "empty"])
        with h5py.File(path, "r+", locking=False) as f:
            old = f[name][()]
            del f[name]
            rows = np.atleast_1d(old)
            new = {"shorter": rows[: len(rows) // 2], "strings": np.array([b"x"] * len(rows)),
                   "2-D": np.zeros((len(rows), 2, 2)), "scalar": np.float64(1.0),
                   "nan": np.full(rows.shape, np.nan), "empty": np.zeros((0,))}.get(what)
            if what == "group":
                f.create_group(name)
            else:
                f[name] = new
        d.note(f"history: dataset {name} made {what}")
    elif choice == "drop" and (datasets or attrs):
        with h5py.File(path, "r+", locking=False) as f:
            if attrs and (not datasets or rng.random() < 0.5):
                name = d.pick(attrs)
                del f.attrs[name]
                d.note(f"history: root attribute {name} deleted")
            else:
                name = d.pick(datasets)
                del f[name]
                d.note(f"history: dataset {name} deleted")
    elif choice == "attr" and attrs:
        value = d.pick(BAD_ATTRS)
        with h5py.File(path, "r+", locking=False) as f:
            if group_attrs and rng.random() < 0.3:
                group, name = d.pick(group_attrs)
                target, where = f[group].attrs, f"{group}."
            else:
                target, where, name = f.attrs, "", d.pick(attrs)
            target[name] = np.void(value) if isinstance(value, bytes) else value
        d.note(f"history: attribute {where}{name} = {short(value)}")
    elif choice == "case":
        text = d.pick(["", "[solver", dumps({**base_case(d.base), "title": [1]}),
                       dumps({**base_case("two_bars" if d.base != "two_bars" else
                                          "bar_impact")}),
                       "x = " + "[" * 5000, "v = " + "1" * 5000])
        with h5py.File(path, "r+", locking=False) as f:
            f.attrs["case"] = text
        d.note(f"history: stored case text = {short(text)}")
    else:
        name = d.pick(["extra", "energy/extra", "sensors/x y", "time2", "checkpoint/x"])
        with h5py.File(path, "r+", locking=False) as f:
            f[name] = np.zeros(d.pick([0, 1, 1000]))
        d.note(f"history: dataset {name} added")
    return False


def history_mutant(d, base_history, base_case_file):
    """A damaged copy of a history, and the command reading it with unusual options."""
    d.history = d.directory / "history.h5"
    shutil.copy(base_history, d.history)
    for _ in range(d.rng.choices([0, 1, 2, 3], [2, 5, 2, 1])[0]):
        # what the damage before left: a deleted dataset cannot be damaged again
        if damage_history(d, history_layout(d.history)):
            break
    command = d.rng.choices(*zip(*HISTORY_COMMANDS))[0]
    h = str(d.history)
    series = d.pick(["sensors/tip", "sensors", "energy", "energy/kinetic", "nosuch", "time",
                     "field/q", "sensors/", "", "\n"])
    if command == "info":
        argv = ["info", h] + (["--json"] if d.rng.random() < 0.3 else [])
    elif command == "export":
        argv = ["export", h, "--out", str(d.directory / "export")]
        if d.rng.random() < 0.4:
            argv += ["--format", "vtu"]
        if d.rng.random() < 0.4:
            argv += ["--every", str(d.pick([0, -1, 2, 2 ** 63, 10 ** 30]))]
        if d.rng.random() < 0.1:
            argv[3] = d.pick(["/proc/export", str(base_case_file), "/dev/null"])
    elif command == "resume":
        argv = ["run", str(base_case_file), "--resume", "-o", h, "--quiet"]
        if d.rng.random() < 0.5:
            argv += ["--set", d.pick(["solver.t_end=1e-3", "solver.chunk=1", "title='x'",
                                      "solver.dt=1e-9", "output.every=2"])]
    elif command == "plot history":
        argv = ["plot", "history", h] + (["--series", series] if d.rng.random() < 0.5 else [])
    elif command == "plot spectrum":
        argv = ["plot", "spectrum", h] + (["--fmax", d.pick(["0", "-1", "nan", "inf", "1e300",
                                                             "1000"])]
                                          if d.rng.random() < 0.6 else [])
    elif command == "plot frf":
        argv = ["plot", "frf", h, "--input", d.pick(["sensors/tip", series]), "--output",
                d.pick(["sensors/tail", "sensors/pad_back", series])]
        if d.rng.random() < 0.5:
            argv += ["--segment", str(d.pick([0, 1, 4, 2 ** 40, 10 ** 30]))]
    else:
        argv = ["plot", "pressure", h]
        if d.rng.random() < 0.5:
            argv += ["--time", d.pick(["nan", "-1", "1e300", "0", "inf"])]
        if d.rng.random() < 0.3:
            argv += ["--pair", d.pick(["nosuch", "wall", "pad_disc", ""])]
    if command.startswith("plot") and d.rng.random() < 0.15:
        argv += ["-o", d.pick(["/proc/p.png", str(d.directory), "/dev/full",
                               str(d.directory / "missing" / "p.png")])]
    d.note("command: " + " ".join("HISTORY" if a == h else a for a in argv))
    return argv


# ----------------------------------------------------------------------------- sweeps

# Sweep mutants (opt-in, `--sweeps SHARE`: without them every seed makes the mutants it made
# before): `transient sweep` of two_bars with its command line mutated, files in its --out at
# the names it writes, a second campaign holding the folder, a resume with a changed --param
# list or --set, a resume after a killed sweep (a history left running, interrupted or empty,
# a stale lock, the tables missing, a history cut mid-write). Judged as any mutant, and
# beyond: every file of the folder the package did not write is as it was, and each row of
# a sweep that ends 0 names the output its own values made.
SWEEP_CASE = "two_bars"
SWEEP_KEY = "contact.impact.k"
SWEEP_VALUES = [1e14, 5e13]             # the base campaign's, made once per fuzz session
SWEEP_SETS = ["solver.t_end=2e-5", "limits.memory=1.0", "limits.steps=50000"]
SWEEP_FAULTS = [("options", 30), ("user file", 25), ("second campaign", 10),
                ("changed list", 20), ("killed", 15)]
SWEEP_PARAMS = [f"{SWEEP_KEY}=0:1e14:1000000000", f"{SWEEP_KEY}=0:inf:3",
                f"{SWEEP_KEY}=nan:1:2", f"{SWEEP_KEY}=1:2:x", f"{SWEEP_KEY}=1:2:-3",
                f"{SWEEP_KEY}=[]", f"{SWEEP_KEY}=[1e14,", f"{SWEEP_KEY}=", "=1",
                f"{SWEEP_KEY}=[1e14, 1.0e14]", f"{SWEEP_KEY}=5e13:5e13:3",
                f"{SWEEP_KEY}={{a = 1}}", f"{SWEEP_KEY}=1979-05-27", f"{SWEEP_KEY}=-1.0",
                f"{SWEEP_KEY}=\"abc\"", "contact.impact.kk=[1.0]", "solver.t_end=[1e-5]",
                f"{SWEEP_KEY}=[" + ",".join(["1e14"] * 20000) + "]",
                f"{SWEEP_KEY}=1:2:" + "9" * 5000, "x" * 5000 + "=[1]", "a\nb=[1]"]
SWEEP_OPTIONS = [["--kind", "CEA"], ["--kind", ""], ["--workers", "0"], ["--workers", "-1"],
                 ["--scheduler", "not an address"], ["--scheduler", ""],
                 ["--scheduler", "tcp://host:port"], ["--scheduler", "foo://bar:1"],
                 ["--scheduler", "tcp://h:99999"], ["--scheduler", "inproc://x"],
                 ["--zip"], ["--resume"], ["--json"]]
SWEEP_OUTS = ["", "CASE", "CASE/out", "/proc/sweep", "/dev/null", "/sys/sweep",
              "DIR/out\x00x", "DIR/" + "x" * 300, "DIR/deeper/out", "DIR/out\n"]
USER_FILES = ["csv", "text", "foreign hdf5", "directory", "json", "empty json list"]


def sweep_argv(d, values, out, kind="run", more=()):
    """The command line of a sweep of two_bars over SWEEP_KEY."""
    argv = ["sweep", str(d.case_file), "--param", f"{SWEEP_KEY}=[{', '.join(map(repr, values))}]",
            "--kind", kind, "--workers", "1", "--out", str(out)]
    for o in SWEEP_SETS + list(more):
        argv += ["--set", o]
    return argv


def sweep_names(values, kind, keys=None):
    """The files a sweep of these values writes (a variant's are named by its values)."""
    from transient.campaign.variants import variant_name
    suffixes = {"run": [".h5"], "cea": [".json"], "both": [".h5", ".json"]}[kind]
    return [variant_name({SWEEP_KEY: v, **(keys or {})}) + s for v in values for s in suffixes]


def user_file(path, what):
    """A file the package did not write, at path."""
    import h5py
    if what == "csv":
        path.write_text("name,value\nmine,1\n")
    elif what == "text":
        path.write_text("notes that are mine\n")
    elif what == "foreign hdf5":
        with h5py.File(path, "w") as f:
            f["time"] = [0.0, 1.0]
            f.attrs["rows"] = 2
    elif what == "directory":
        path.mkdir()
        (path / "inside.txt").write_text("mine")
    elif what == "json":
        path.write_text(json.dumps({"status": "complete", "modes": []}))
    else:
        path.write_text("[]")


def sweep_mutant(d, campaign):
    """A sweep mutant of d (its directory made, d.case_file written): its argv, the files to
    find unchanged (path -> content), the folder whose rows must name their outputs, and the
    lock the parent holds while it runs (None: none)."""
    fault = d.rng.choices(*zip(*SWEEP_FAULTS))[0]
    d.note(f"sweep: {fault}")
    out = d.directory / "out"
    values, kind, more = list(SWEEP_VALUES), "run", []
    if fault in ("changed list", "killed") or (fault == "second campaign"
                                               and d.rng.random() < 0.5):
        shutil.copytree(campaign(), out)
        d.note("the base campaign copied to --out")
    if fault == "options":
        argv = sweep_argv(d, d.rng.sample(SWEEP_VALUES + [2e13], d.rng.randint(1, 2)), out)
        for _ in range(d.rng.randint(1, 2)):
            what = d.pick(["param", "param", "option", "out", "set"])
            if what == "param":
                i = argv.index("--param") + 1
                argv[i] = d.pick(SWEEP_PARAMS + ["sixteen"])
                if argv[i] == "sixteen":
                    argv[i:i + 1] = [a for j in range(16) for a in (f"k{j}.x=0:1:16", "--param")
                                     ][:-1]
                d.note(f"--param {short(argv[i])}")
            elif what == "option":
                option = d.pick(SWEEP_OPTIONS)
                argv += option
                d.note(" ".join(option))
            elif what == "out":
                target = resolve(d.pick(SWEEP_OUTS), d)
                argv[argv.index("--out") + 1] = target
                d.note(f"--out {short(target)}")
            else:
                argv += ["--set", d.pick(MALFORMED_SETS[:12])]
                d.note(f"--set {short(argv[-1])}")
        return argv, {}, out, None
    if fault == "user file":
        kind = d.pick(["run", "cea", "both"])
        names = ["sweep.csv", "sweep.json", "sweep.lock"] + sweep_names(values, kind)
        name = d.pick(names)
        out.mkdir(exist_ok=True)
        what = d.pick(USER_FILES)
        user_file(out / name, what)
        d.note(f"--kind {kind}; {what} at {name}")
        return sweep_argv(d, values, out, kind), guard(out), out, None
    if fault == "second campaign":
        out.mkdir(exist_ok=True)
        d.note("another campaign holds the folder")
        return sweep_argv(d, values, out), guard(out), out, out / "sweep.lock"
    if fault == "changed list":
        values = d.rng.sample(SWEEP_VALUES + [2e13, 1.0e14, 8e13], d.rng.randint(1, 3))
        if len(set(values)) < len(values):
            values = sorted(set(values))
        if d.rng.random() < 0.4:
            more = [d.pick(["solver.t_end=4e-5", "solver.t_end=1e-5", "solver.chunk=7",
                            "materials.steel.rho=7000.0", "title='other'"])]
        d.note(f"--resume with {SWEEP_KEY} = {values}" + (f", --set {more[0]}" if more else ""))
        return sweep_argv(d, values, out, kind, more) + ["--resume"], {}, out, None
    histories = sorted(out.glob("v-*.h5"))
    damage = d.pick(["running", "interrupted", "empty", "stale lock", "no tables", "cut",
                     "temporary"])
    path = d.pick(histories)
    if damage in ("running", "interrupted"):
        import h5py
        with h5py.File(path, "a", locking=False) as f:
            f.attrs["status"] = "running" if damage == "running" else "aborted: interrupted"
    elif damage == "empty":
        path.write_bytes(b"")
    elif damage == "stale lock":
        (out / "sweep.lock").write_text(json.dumps({"lock": "transient sweep", "pid": 999999,
                                                    "host": "gone", "started": "before",
                                                    "command": "killed"}) + "\n")
    elif damage == "no tables":
        for table in ("sweep.csv", "sweep.json"):
            (out / table).unlink()
    elif damage == "cut":
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])
    else:
        (out / ".sweep.json.999999.1").write_text('{"kind": "ru')
    d.note(f"killed: {damage}" + (f" ({path.name})" if damage in ("running", "interrupted",
                                                                  "empty", "cut") else ""))
    if d.rng.random() < 0.3:
        values.append(2e13)
        d.note(f"and {SWEEP_KEY} = 2e13 added")
    return sweep_argv(d, values, out) + ["--resume"], {}, out, None


def make_sweep_mutant(seed, index, directory, campaign):
    """Sweep mutant `index` of `seed` (sweep_mutant), its files written; campaign() gives the
    base campaign's folder, made on first use."""
    d = Draft(random.Random(f"{seed}:{index}:sweep mutant"), directory, SWEEP_CASE)
    directory.mkdir(parents=True)
    d.case_file = directory / "case.toml"
    d.case_file.write_text(dumps(tomllib.loads((CASES / f"{SWEEP_CASE}.toml").read_text())))
    argv, guarded, folder, lock = sweep_mutant(d, campaign)
    return Mutant(index, SWEEP_CASE, argv, d.notes, directory, lock=lock, guarded=guarded,
                  folder=folder)


def guard(folder):
    """Path -> content (bytes, or the sorted names of a folder) of every file in folder: what
    the package did not write must stay as it is."""
    out = {}
    for p in sorted(Path(folder).rglob("*")):
        out[str(p)] = sorted(x.name for x in p.iterdir()) if p.is_dir() else p.read_bytes()
    return out


def changed_files(guarded):
    """The guarded paths whose content changed or went away."""
    out = []
    for path, content in guarded.items():
        p = Path(path)
        now = (sorted(x.name for x in p.iterdir()) if p.is_dir() else p.read_bytes()) \
            if p.exists() or p.is_symlink() else None
        if now != content:
            out.append(path)
    return out


def mislabelled(folder):
    """The rows of a sweep's sweep.json whose output was made with other values than the
    row's (the stored overrides of each output lack the row's key=literal)."""
    import h5py
    from transient.case.loading import literal
    try:
        saved = json.loads((Path(folder) / "sweep.json").read_text())
    except (OSError, ValueError):
        return []
    wrong = []
    for row in saved.get("rows", []):
        want = {f"{k}={literal(row[k])}" for k in saved.get("parameters", [])}
        for key in ("output", "modes_output"):
            path = Path(folder) / row.get(key, "")
            if key not in row or not path.is_file() or row.get("status") != "complete":
                continue
            if path.suffix == ".json":
                stored = json.loads(path.read_text()).get("overrides") or []
            else:
                with h5py.File(path, "r", locking=False) as f:
                    stored = json.loads(f.attrs.get("overrides", "[]"))
            if not want <= set(stored):
                wrong.append(f"{row.get('variant')}: {path.name}")
    return wrong


def _run_sweep_mutant(worker_, mutant, timeout):
    """The worker's result of a sweep mutant (the folder's lock held meanwhile if it asks),
    with what it changed of the files the package did not write (replaced) and the rows that
    name an output of other values (mislabelled)."""
    import fcntl
    job = {"id": mutant.id, "argv": mutant.argv, "cwd": str(mutant.directory),
           "interrupt": None}
    if mutant.lock is None:
        result = worker_.run(job, timeout)
    else:
        with open(mutant.lock, "wb") as held:
            fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
            result = worker_.run(job, timeout)
    result["replaced"] = changed_files(mutant.guarded or {})
    result["mislabelled"] = mislabelled(mutant.folder) if result.get("code") == 0 else []
    return result


def _make_sweep(worker_, directory, timeout):
    """The base campaign of the sweep mutants, made once: its folder."""
    directory.mkdir(parents=True, exist_ok=True)
    d = Draft(random.Random(0), directory, SWEEP_CASE)
    d.case_file = directory / "sweep_case.toml"
    d.case_file.write_text(dumps(tomllib.loads((CASES / f"{SWEEP_CASE}.toml").read_text())))
    out = directory / "campaign"
    result = worker_.run({"id": "sweep", "argv": sweep_argv(d, SWEEP_VALUES, out),
                          "cwd": str(directory), "interrupt": None}, timeout)
    if result.get("code") != 0:
        raise RuntimeError(f"the base campaign could not be made: {json.dumps(result)[:2000]}")
    return out


# ----------------------------------------------------------------------------- mutants


@dataclass(frozen=True)
class Mutant:
    """A mutant ready to run: the command line, its notes, and what the parent does for it."""
    id: int
    base: str
    argv: list
    notes: list
    directory: Path
    interrupt: float = None
    lock: Path = None
    guarded: dict = None      # sweeps: path -> content of the files the package did not write
    folder: Path = None       # sweeps: the --out whose rows must name their own outputs


def case_mutant(d):
    """Mutate the case dict (and the command line) of d, write the case file, give argv."""
    d.command = d.rng.choices(*zip(*CASE_COMMANDS))[0]
    if d.command in ("cea", "plot cea"):
        analysis_case(d)
    for _ in range(d.rng.choices([1, 2, 3], [5, 3, 2])[0]):
        mutations, weights = zip(*CASE_MUTATIONS)
        while not d.rng.choices(mutations, weights)[0](d):
            pass
    text = dumps(d.data).encode()
    if d.text_edit:
        text = d.text_edit(text)
    d.case_file.write_bytes(text)
    argv = [d.command, str(d.case_file)] + d.options
    if d.command in ("cea", "plot cea"):
        argv = analysis_argv(d)
    elif d.command == "run":
        if d.output is not None:
            argv += ["-o", resolve(d.output, d)]
        argv += ["--quiet"]
    elif d.command == "compat" and d.rng.random() < 0.2:
        argv += ["--pair", d.pick(["nosuch", "wall", "impact", "interface", "pad_disc"])]
    if d.rng.random() < 0.2 and d.command != "plot cea":
        argv += ["--json"]
    if d.command != "run":
        d.notes.insert(0, f"command: {d.command}")
    return argv


def make_mutant(seed, index, bases, directory, histories, interrupts=True, sweeps=0.0,
                campaign=None):
    """Mutant `index` of `seed`, its files written: the same on every machine, whatever ran
    before it.

    Parameters
    ----------
    seed, index : int
    bases : list of str
        Base cases the mutant may start from (keys of BASES).
    directory : Path
        Where its files go (made here; it must not exist).
    histories : callable(name) -> (history path, its case file)
        The base histories of HISTORY_RUNS, made on first use.
    interrupts : bool
        Allow Ctrl-C mutations (without them no outcome depends on the machine's speed).
    sweeps : float
        The share of sweep mutants, drawn apart: 0 leaves every other mutant as it was.
    campaign : callable() -> Path
        The base campaign of the sweep mutants, made on first use.

    Returns
    -------
    Mutant
    """
    if sweeps and random.Random(f"{seed}:{index}:sweep").random() < sweeps:
        return make_sweep_mutant(seed, index, directory, campaign)
    rng = random.Random(f"{seed}:{index}")
    base = rng.choice(bases)
    directory.mkdir(parents=True)
    d = Draft(rng, directory, base, interrupts=interrupts)
    d.case_file = directory / "case.toml"
    runs = [n for n, (b, _, _) in HISTORY_RUNS.items() if b in bases]
    if runs and rng.random() < HISTORY_SHARE:
        name = rng.choice(runs)
        d.base = HISTORY_RUNS[name][0]
        argv = history_mutant(d, *histories(name))
        d.notes.insert(0, f"history '{name}' of {d.base}")
        return Mutant(index, d.base, argv, d.notes, directory)
    d.data = base_case(base)
    argv = case_mutant(d)
    lock = directory / "locked.h5" if d.locked else None
    return Mutant(index, base, argv, d.notes, directory, d.interrupt, lock)


# ----------------------------------------------------------------------------- worker


class _Text:
    """A text stream kept in memory that survives close() (main closes stderr on a broken
    pipe)."""

    def __init__(self):
        self.parts = []

    def write(self, text):
        self.parts.append(text)
        return len(text)

    def flush(self):
        pass

    def close(self):
        pass

    def isatty(self):
        return False

    def getvalue(self):
        return "".join(self.parts)


_ARMED = [False]


def _on_sigint(signum, frame):
    # Ctrl-C as Python delivers it, but only while a mutant runs: a late timer is ignored
    if _ARMED[0]:
        raise KeyboardInterrupt


def _interrupt(result):
    result["interrupted"] = _ARMED[0]
    os.kill(os.getpid(), signal.SIGINT)


def _before_command(exc):
    """exc was raised while main parsed its arguments, before the command began."""
    own = [f for f in traceback.extract_tb(exc.__traceback__)
           if Path(f.filename).parts[-2:] == ("cli", "commands.py")]
    return bool(own) and all("parse_args" in (f.line or "") for f in own)


def _vm():
    """VmSize of this process [bytes]: what RLIMIT_AS bounds."""
    status = dict(line.split(":", 1) for line in Path("/proc/self/status").read_text()
                  .splitlines() if ":" in line)
    return int(status["VmSize"].split()[0]) * 1024


def run_job(main, job):
    """Run one command line through main in this process.

    Parameters
    ----------
    main : callable(argv) -> int
        `transient.cli.main`.
    job : dict
        id, argv, cwd (the working directory) and interrupt (seconds after which SIGINT is
        sent, or None).

    Returns
    -------
    dict
        id, code (what main returned, or the SystemExit code), exception and traceback (of
        what escaped main), before_command, interrupted (SIGINT delivered while main ran),
        unraisable (exceptions Python ignored), warnings, stdout, stderr (Python and
        file-descriptor level), seconds, vm (VmSize after it).
    """
    out, err = _Text(), _Text()
    saved = os.dup(1), os.dup(2)
    raw = tempfile.TemporaryFile(), tempfile.TemporaryFile()
    os.dup2(raw[0].fileno(), 1)
    os.dup2(raw[1].fileno(), 2)
    streams = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = out, err
    result = {"id": job["id"], "code": None, "exception": None, "traceback": None,
              "interrupted": False, "unraisable": []}
    sys.unraisablehook = lambda u: result["unraisable"].append(
        f"{u.exc_type.__name__} in {one_line(repr(u.object))[:200]}")
    timer = None
    t0 = time.perf_counter()
    try:
        os.chdir(job["cwd"])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                if job["interrupt"] is not None:
                    timer = threading.Timer(job["interrupt"], _interrupt, (result,))
                    timer.start()
                _ARMED[0] = True
                code = main(job["argv"])
                _ARMED[0] = False
                result["code"] = (0 if code is None else code if isinstance(code, int)
                                  else repr(code))
            except SystemExit as exc:
                result["code"] = (0 if exc.code is None else exc.code
                                  if isinstance(exc.code, int) else 1)
            except BaseException as exc:   # whatever escapes main is the finding
                result["exception"] = f"{type(exc).__name__}: {one_line(exc)[:300]}"
                result["traceback"] = traceback.format_exc()[-6000:]
                result["before_command"] = _before_command(exc)
            finally:
                _ARMED[0] = False
                if timer is not None:
                    timer.cancel()
                    timer.join()
        result["warnings"] = [f"{w.category.__name__}: {one_line(w.message)[:300]} "
                              f"({w.filename}:{w.lineno})" for w in caught]
    finally:
        sys.unraisablehook = sys.__unraisablehook__
        sys.stdout, sys.stderr = streams
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])
    result["seconds"] = time.perf_counter() - t0
    low = [f.seek(0) or f.read().decode(errors="backslashreplace") for f in raw]
    for f in raw:
        f.close()
    result["stdout"] = (out.getvalue() + low[0])[:OUTPUT_CHARS]
    result["stderr"] = (err.getvalue() + low[1])[:STDERR_CHARS]
    result["vm"] = _vm()
    return result


def worker(memory_gb):
    """The worker loop: one JSON job per line on stdin, one JSON result per line on the
    original stdout (fds 1 and 2 are the mutants' while they run)."""
    import faulthandler
    limit = int(memory_gb * 2 ** 30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    reply = os.fdopen(os.dup(1), "w", buffering=1)
    log = os.fdopen(os.dup(2), "w", buffering=1)
    # a crash prints the Python stack to the worker's log, not into a mutant's capture
    faulthandler.enable(file=log)
    from transient.cli import main
    signal.signal(signal.SIGINT, _on_sigint)
    reply.write("ready\n")
    for line in sys.stdin:
        result = run_job(main, json.loads(line))
        reply.write(json.dumps(result) + "\n")


class Worker:
    """A worker subprocess: started on demand, killed (its process group) after a timeout."""

    def __init__(self, memory_gb, log_path):
        self.memory_gb = memory_gb
        self.log_path = log_path
        self.proc = None
        self.buffer = b""
        self.restarts = -1

    def start(self):
        env = dict(os.environ, MPLBACKEND="Agg", PYTHONFAULTHANDLER="1")
        env.pop("CI", None)
        self.log = open(self.log_path, "ab")
        self.proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker",
                                      "--memory-gb", str(self.memory_gb)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self.log, cwd=ROOT, env=env,
                                     start_new_session=True)
        self.buffer = b""
        self.restarts += 1
        line = self._line(time.monotonic() + 300.0)
        if line != b"ready":
            raise RuntimeError(f"worker did not start: {line!r}; see {self.log_path}")

    def stop(self):
        if self.proc is not None:
            try:
                os.killpg(self.proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.proc.wait()
            self.proc.stdin.close()
            self.proc.stdout.close()
            self.log.close()
            self.proc = None

    def _line(self, deadline):
        fd = self.proc.stdout.fileno()
        while b"\n" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                chunk = os.read(fd, 1 << 20)
                if not chunk:
                    raise EOFError
                self.buffer += chunk
        line, _, self.buffer = self.buffer.partition(b"\n")
        return line

    def run(self, job, timeout):
        """The worker's result of job, or a result saying it timed out or crashed (the worker
        is then restarted with the next job)."""
        if self.proc is None:
            self.start()
        t0 = time.monotonic()
        try:
            self.proc.stdin.write((json.dumps(job) + "\n").encode())
            self.proc.stdin.flush()
            result = json.loads(self._line(t0 + timeout))
        except TimeoutError:
            self.stop()
            return {"id": job["id"], "timeout": timeout, "seconds": timeout}
        except (EOFError, BrokenPipeError):
            code = self.proc.wait()
            self.stop()
            # the log holds every worker's: this crash is its last fatal error, if it said one
            log = Path(self.log_path).read_bytes().decode(errors="backslashreplace")
            fatal = log.rfind("Fatal Python error")
            tail = log[fatal:] if fatal >= 0 else log[-3000:]
            return {"id": job["id"], "crash": code, "seconds": time.monotonic() - t0,
                    "stderr": tail}
        # a MemoryError or an interrupt may leave the package half imported or cached;
        # a grown worker would make the next mutant hit the memory bound
        if ("MemoryError" in (result.get("exception") or "") or result.get("interrupted")
                or result.get("vm", 0) > RESTART_VM_GB * 2 ** 30):
            self.stop()
        return result


# ----------------------------------------------------------------------------- outcomes


def without_lock_waits(stderr):
    """stderr without the lines that say a wait for the Numba compile lock (transient.jit):
    whether another process compiles the same kernels meanwhile is the machine's, not the
    mutant's."""
    return "".join(line for line in stderr.splitlines(keepends=True)
                   if not line.startswith("waiting for the Numba compile lock "))


def classify(result):
    """What a worker result says of the contract.

    Parameters
    ----------
    result : dict
        `run_job`'s result, or `Worker.run`'s for a timeout or a crash.

    Returns
    -------
    outcome : int or str
        The exit code (0, 2, 3 or 130), or 'FAILURE'.
    failures : list of str
        The failure classes, empty when the outcome is an exit code.
    """
    failures = []
    if "timeout" in result:
        return "FAILURE", [f"timeout: no result within {result['timeout']:g} s"]
    if "crash" in result:
        code = result["crash"]
        what = f"signal {-code}" if code < 0 else f"exit {code}"
        return "FAILURE", [f"crash: the worker died ({what})"]
    exception = result.get("exception")
    interrupted = result.get("interrupted")
    if exception and exception.startswith("KeyboardInterrupt") and interrupted and result.get(
            "before_command"):
        # Ctrl-C in the few milliseconds main parses its arguments is Ctrl-C at start-up,
        # like one during the imports before main: Python's traceback, not the package's
        return 130, []
    if exception:
        failures.append("memory bound: MemoryError" if exception.startswith("MemoryError")
                        else f"uncaught exception: {exception.split(':')[0]}")
    code = result.get("code")
    if not exception and code not in SUCCESS_CODES:
        failures.append(f"exit code {code!r}")
    stderr = without_lock_waits(result.get("stderr", ""))
    if "Traceback (most recent call last)" in stderr:
        failures.append("traceback on stderr")
    # an interrupted stdlib iterator (glob's scandir) warns when collected; Python shows no
    # ResourceWarning by default
    failures += sorted({f"warning: {w.split(':')[0]}" for w in result.get("warnings", [])
                        if not (interrupted and w.startswith("ResourceWarning"))})
    for u in result.get("unraisable", []):
        # Python's own behaviour at Ctrl-C: a KeyboardInterrupt raised in a finalizer is
        # ignored (and printed); the package cannot catch it
        if not (u.startswith("KeyboardInterrupt ") and interrupted):
            failures.append(f"unraisable exception: {u.split(' ')[0]}")
    if result.get("replaced"):
        failures.append("a file the package did not write was replaced or removed")
    if result.get("mislabelled"):
        failures.append("a sweep's row names an output of other values")
    lines = stderr.splitlines()
    if code in (2, 3) and not exception:
        if len(lines) != 1:
            failures.append(f"error message of {'no' if not lines else 'several'} line(s)")
        elif not lines[0].startswith("error: "):
            failures.append("error message not starting with 'error: '")
        elif code == 2 and not re.match(r"error: (/|\.|command line)", lines[0]):
            # every path the fuzzer gives is absolute ('.' is what -o '' names)
            failures.append("error message naming no file")
    elif code == 0 and stderr and not exception:
        failures.append("stderr output on exit 0")
    elif code == 130 and len(lines) > 1:
        failures.append("interrupt message of several lines")
    return ("FAILURE" if failures else code), failures


def shell(argv):
    """argv as a shell command line (bash $'...' quoting for non-printable characters)."""
    def quote(a):
        if all(" " <= c <= "~" for c in a):
            return shlex.quote(a)
        body = "".join(c if " " <= c <= "~" and c not in "\\'" else
                       "\\" + c if c in "\\'" else c.encode("unicode_escape").decode("ascii")
                       for c in a)
        return f"$'{body}'"
    return "transient " + " ".join(quote(a) for a in argv)


def _clip(text, n):
    text = text.rstrip()
    return text if len(text) <= n else text[:n] + f"... ({len(text)} chars)"


def example(mutant, result):
    """What a report shows of a failing mutant."""
    return {"id": mutant.id, "base": mutant.base, "mutations": mutant.notes,
            "command": _clip(shell(mutant.argv), 600), "directory": str(mutant.directory),
            "code": result.get("code"), "exception": result.get("exception"),
            "stderr": one_line(_clip(result.get("stderr", ""), 1500)),
            "stderr_lines": len(result.get("stderr", "").splitlines()),
            "traceback": result.get("traceback") and _clip(result["traceback"][-1500:], 1500),
            "warnings": result.get("warnings", [])[:5], "seconds": result.get("seconds")}


def fuzz(mutants=200, seed=0, cases=None, keep=None, only=None, timeout=TIMEOUT_S,
         memory_gb=MEMORY_GB, progress=None, interrupts=True, sweeps=0.0):
    """Generate and run mutants; the outcome classes and one example per failure class.

    Parameters
    ----------
    mutants : int
        Number of mutants (ids 0 to mutants - 1), unless `only` names them.
    seed : int
        Mutant i of a seed is the same whatever the machine and whatever ran before it.
    cases : list of str, optional
        Base cases (keys of BASES); all by default.
    keep : str or Path, optional
        Directory that keeps every mutant's files (case, meshes, outputs); a temporary one,
        removed at the end, by default.
    only : list of int, optional
        Run these mutant ids only.
    timeout : float
        Seconds a mutant may take before its worker is killed (a guard, not a measure).
    memory_gb : float
        Address-space limit of the worker [GB].
    progress : callable(str), optional
        Called with a line every 100 mutants.
    interrupts : bool
        Include Ctrl-C mutations. Where SIGINT lands depends on the machine's speed, so
        without them every outcome is the same on every machine.
    sweeps : float
        The share of sweep mutants (sweep_mutant), 0 by default: the other mutants of a seed
        are the same whatever it is.

    Returns
    -------
    dict
        seed, mutants, cases, seconds, worker_restarts, slowest (seconds, id), outcomes
        (exit code or 'FAILURE' -> count), failures (class -> {count, ids, example}).
    """
    bases = list(cases or BASES)
    unknown = [b for b in bases if b not in BASES]
    if unknown:
        raise ValueError(f"unknown case(s) {', '.join(unknown)} (cases: {', '.join(BASES)})")
    ids = list(only) if only is not None else list(range(mutants))
    t0 = time.perf_counter()
    temporary = tempfile.TemporaryDirectory(prefix="fuzz_cases_") if keep is None else None
    root = Path(keep if keep is not None else temporary.name).resolve()
    root.mkdir(parents=True, exist_ok=True)
    worker_ = Worker(memory_gb, root / "worker.log")
    made = {}

    def histories(name):
        if name not in made:
            made[name] = _make_history(worker_, root / "histories", name, timeout)
        return made[name]

    def campaign():
        if "sweep" not in made:
            made["sweep"] = _make_sweep(worker_, root / "histories", timeout)
        return made["sweep"]

    outcomes, failures, slowest = {}, {}, (0.0, -1)
    try:
        for n, i in enumerate(ids, 1):
            directory = root / f"m{i:05d}"
            if directory.exists():
                shutil.rmtree(directory)
            mutant = make_mutant(seed, i, bases, directory, histories, interrupts, sweeps,
                                 campaign)
            result = _run_mutant(worker_, mutant, timeout)
            outcome, classes = classify(result)
            outcomes[outcome] = outcomes.get(outcome, 0) + 1
            slowest = max(slowest, (result.get("seconds", 0.0), i))
            for c in classes:
                entry = failures.setdefault(c, {"count": 0, "ids": [],
                                                "example": example(mutant, result)})
                entry["count"] += 1
                entry["ids"].append(i)
            if keep is None:
                shutil.rmtree(directory, ignore_errors=True)
            else:
                (directory / "result.json").write_text(json.dumps(
                    {"argv": mutant.argv, "notes": mutant.notes, **result}, indent=1))
            if progress and n % 100 == 0:
                progress(f"{n}/{len(ids)} mutants, {time.perf_counter() - t0:.0f} s, "
                         f"{sum(e['count'] for e in failures.values())} failure(s)")
    finally:
        worker_.stop()
        if temporary is not None:
            temporary.cleanup()
    return {"seed": seed, "mutants": len(ids), "cases": bases,
            "seconds": round(time.perf_counter() - t0, 1),
            "worker_restarts": max(worker_.restarts, 0), "slowest": slowest,
            "outcomes": {str(k): v for k, v in sorted(
                outcomes.items(), key=lambda kv: (kv[0] == "FAILURE", str(kv[0]).zfill(3)))},
            "failures": failures}


def _run_mutant(worker_, mutant, timeout):
    """The worker's result of mutant, with the lock on its output held meanwhile if it
    asks for one."""
    if mutant.folder is not None:
        return _run_sweep_mutant(worker_, mutant, timeout)
    job = {"id": mutant.id, "argv": mutant.argv, "cwd": str(mutant.directory),
           "interrupt": mutant.interrupt}
    if mutant.lock is None:
        return worker_.run(job, timeout)
    import fcntl
    with open(mutant.lock, "wb") as held:
        # an empty file is not yet a history; the package must refuse the lock before that
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return worker_.run(job, timeout)


def _make_history(worker_, directory, name, timeout):
    """Run the base of HISTORY_RUNS[name] once: (its history, its case file)."""
    base, extra, expected = HISTORY_RUNS[name]
    directory.mkdir(parents=True, exist_ok=True)
    data = base_case(base)
    put(data, ("output", "contact"), True)
    for key, value in extra.items():
        put(data, tuple(key.split(".")), value)
    case_file = directory / f"{name}.toml"
    case_file.write_text(dumps(data))
    history = directory / f"{name}.h5"
    result = worker_.run({"id": name, "argv": ["run", str(case_file), "-o", str(history),
                                               "--quiet"], "cwd": str(directory),
                          "interrupt": None}, timeout)
    if result.get("code") != expected:
        raise RuntimeError(f"the base history '{name}' could not be made (expected exit "
                           f"{expected}): {json.dumps(result)[:2000]}")
    return history, case_file


def format_report(report):
    """The report as text: outcome classes, then one example per failure class."""
    lines = [f"fuzz_cases: {report['mutants']} mutants of seed {report['seed']} on "
             f"{', '.join(report['cases'])}: {report['seconds']:.1f} s, "
             f"{report['worker_restarts']} worker restart(s), slowest mutant "
             f"{report['slowest'][0]:.1f} s (#{report['slowest'][1]})", "",
             f"{'outcome':<12}{'mutants':>8}"]
    for outcome, count in report["outcomes"].items():
        label = outcome if outcome == "FAILURE" else f"exit {outcome}"
        lines.append(f"{label:<12}{count:>8}")
    if report["failures"]:
        lines += ["", f"{'failure class':<60}{'mutants':>8}"]
        for c, entry in sorted(report["failures"].items(), key=lambda x: -x[1]["count"]):
            lines.append(f"{c:<60}{entry['count']:>8}")
    for c, entry in report["failures"].items():
        e = entry["example"]
        ids = ", ".join(str(i) for i in entry["ids"][:12]) + (", ..." if entry["count"] > 12
                                                              else "")
        lines += ["", f"--- {c}: {entry['count']} mutant(s) ({ids})",
                  f"example #{e['id']} ({e['base']}): " + "; ".join(e["mutations"]),
                  f"  {e['command']}",
                  f"  exit {e['code']}, {e['seconds']:.2f} s, stderr ({e['stderr_lines']} "
                  f"line(s)): {e['stderr']}"]
        if e["exception"]:
            lines.append(f"  exception: {e['exception']}")
        if e["traceback"]:
            lines += ["  " + t for t in e["traceback"].splitlines()[-8:]]
        lines += [f"  {w}" for w in e["warnings"]]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mutants", type=int, default=200, metavar="N")
    parser.add_argument("--seed", type=int, default=0, metavar="S")
    parser.add_argument("--cases", default=",".join(BASES), metavar="A,B",
                        help=f"base cases (default {','.join(BASES)})")
    parser.add_argument("--only", metavar="I,J", help="run these mutant ids only")
    parser.add_argument("--keep", metavar="DIR", help="keep every mutant's files in DIR")
    parser.add_argument("--timeout", type=float, default=TIMEOUT_S, metavar="SECONDS")
    parser.add_argument("--memory-gb", type=float, default=MEMORY_GB, metavar="GB")
    parser.add_argument("--no-interrupts", action="store_true", help="no Ctrl-C mutations "
                        "(then no outcome depends on the machine's speed)")
    parser.add_argument("--sweeps", type=float, default=0.0, metavar="SHARE",
                        help="share of sweep mutants (default 0: the mutants of a seed are "
                        "those it made before they existed)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        return worker(args.memory_gb)
    only = [int(x) for x in args.only.split(",")] if args.only else None
    try:
        report = fuzz(args.mutants, args.seed, [c for c in args.cases.split(",") if c],
                      args.keep, only, args.timeout, args.memory_gb,
                      lambda line: print(line, file=sys.stderr, flush=True),
                      not args.no_interrupts, args.sweeps)
    except (ValueError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(report, indent=1) if args.json else format_report(report))
    return 1 if report["failures"] else 0


if __name__ == "__main__":
    import transient
    transient.configure()     # the settings `transient` makes (its docstring)
    sys.exit(main())
