"""Case files: TOML read with tomllib, `--set` overrides, validation against the schema."""
import copy
import difflib
import math
import re
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

from . import schema as S
from .checks import check
from .sizes import Cluster, check_generated
from .specs import CeaSpec, LimitsSpec, OutputSpec, SolverSpec, build
from ..errors import CaseError


@dataclass(frozen=True)
class Case:
    """A validated case: frozen specs of every table (defaults filled), SI units."""
    path: Path
    text: str            # the file as written, kept in outputs
    overrides: tuple     # the --set assignments applied, as given
    title: str
    materials: dict      # name -> MaterialSpec
    parts: dict          # name -> PartSpec
    constraints: dict    # name -> ConstraintSpec
    loads: dict          # name -> LoadSpec
    contact: dict        # name -> ContactSpec
    sensors: dict        # name -> SensorSpec
    initial: dict        # name -> InitialSpec
    motion: dict         # name -> MotionSpec
    solver: SolverSpec
    output: OutputSpec
    cea: CeaSpec
    limits: LimitsSpec
    # where the components path reduces its parts, as the command says (its memory bounds)
    cluster: Cluster = Cluster()
    # why solver.reduction.method is what it is where the case says "auto" ('' otherwise)
    reduction_auto: str = ""

    @property
    def directory(self):
        return self.path.parent

    def error(self, key, message):
        return CaseError(self.path, key, message)


NAME = re.compile(r"[A-Za-z0-9_-]+")


def parse_override(assignment, path):
    """'a.b.c=LITERAL' -> (['a', 'b', 'c'], value); a bare word is taken as a string."""
    if "=" not in assignment:
        raise CaseError(path, f"--set {assignment}", "expected KEY.PATH=VALUE")
    key, literal = assignment.split("=", 1)
    keys = key.strip().split(".")
    if not all(keys):
        raise CaseError(path, f"--set {assignment}", "expected KEY.PATH=VALUE")
    try:
        value = tomllib.loads(f"v = {literal.strip()}")["v"]
    except (tomllib.TOMLDecodeError, ValueError):     # ValueError: an int of 5000 digits
        value = literal.strip()
    return keys, value


def apply_overrides(data, overrides, path):
    data = copy.deepcopy(data)
    for assignment in overrides:
        keys, value = parse_override(assignment, path)
        node = data
        for k in keys[:-1]:
            node = node.setdefault(k, {})
            if not isinstance(node, dict):
                raise CaseError(path, f"--set {assignment}", f"'{k}' is not a table")
        node[keys[-1]] = value
    return data


def literal(value):
    """A TOML literal of a value: what an override (--set KEY=LITERAL) reads back to
    the same value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(literal(v) for v in value) + "]"
    return repr(value)


def load(path, overrides=(), cluster=Cluster()):
    """Read, override and validate a case file; raises CaseError on any bad input. cluster:
    where the components path will reduce its parts (sizes.Cluster), whose memory bounds
    are checked here."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise CaseError(path, "", "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseError(path, "", f"cannot read: {exc}") from None
    return parse(text, path, overrides, cluster)


def parse(text, path, overrides=(), cluster=Cluster()):
    """A case from its TOML text, such as the copy a history keeps; path locates the files it
    names (meshes) and is the one errors name."""
    path = Path(path)
    try:
        raw = tomllib.loads(text)
        raw = apply_overrides(raw, overrides, path)
        data = _Validator(path).table(S.CASE, raw, "")
    except (tomllib.TOMLDecodeError, ValueError) as exc:
        raise CaseError(path, "", f"invalid TOML: {exc}") from None
    except RecursionError:
        raise CaseError(path, "", "tables or arrays nested too deeply") from None
    return check(Case(path, text, tuple(overrides), **build(data), cluster=cluster))


def on_cluster(case, cluster):
    """The case with its parts reduced where cluster says (sizes.Cluster), its memory bound
    checked again if it was loaded for another place: a script may load a case, then reduce
    its parts on workers, or here."""
    if case.cluster == cluster:
        return case
    case = replace(case, cluster=cluster)
    check_generated(case)
    return case


def _join(prefix, key):
    return f"{prefix}.{key}" if prefix else key


class _Validator:
    def __init__(self, path):
        self.path = path

    def fail(self, key, message):
        raise CaseError(self.path, key, message)

    def node(self, spec, value, key):
        if isinstance(spec, S.Table):
            return self.table(spec, value, key)
        if isinstance(spec, S.Named):
            return self.named(spec, value, key)
        if isinstance(spec, S.Variant):
            return self.variant(spec, value, key)
        return self.value(spec, value, key)

    def expect_table(self, value, key):
        if not isinstance(value, dict):
            self.fail(key, f"expected a table, got {_show(value)}")

    def fields(self, fields, value, key):
        self.expect_table(value, key)
        for k in value:
            if k not in fields:
                close = difflib.get_close_matches(k, list(fields), n=1)
                hint = (f" (did you mean '{close[0]}'?)" if close else
                        f" (expected one of: {', '.join(fields)})" if fields else
                        " (this table takes no key here)")
                self.fail(_join(key, k), f"unknown key{hint}")
        out = {}
        for k, spec in fields.items():
            sub = _join(key, k)
            if k in value:
                out[k] = self.node(spec, value[k], sub)
            elif isinstance(spec, S.Named):
                out[k] = self.named(spec, {}, sub)
            elif isinstance(spec, S.Table) and spec.optional:
                out[k] = self.table(spec, {}, sub)
            elif isinstance(spec, S.Variant) and spec.default:
                out[k] = self.variant(spec, {spec.key: spec.default}, sub)
            elif isinstance(spec, S.Value) and spec.default is not S.REQUIRED:
                out[k] = copy.deepcopy(spec.default)
            else:
                self.fail(sub, "missing key" + (f" ({spec.doc})" if spec.doc else ""))
        return out

    def table(self, spec, value, key):
        return self.fields(spec.fields, value, key)

    def named(self, spec, value, key):
        self.expect_table(value, key)
        if len(value) < spec.min_items:
            self.fail(key, f"expected at least {spec.min_items} table(s) [{key}.NAME]")
        for name in value:
            # names become dotted keys (--set) and HDF5 paths (sensors/NAME)
            if not NAME.fullmatch(name):
                self.fail(_join(key, name), "expected a name of letters, digits, '_' and '-'")
        return {name: self.node(spec.item, item, _join(key, name)) for name, item in value.items()}

    def variant(self, spec, value, key):
        self.expect_table(value, key)
        name = spec.key
        kind = value.get(name, spec.default if spec.implicit else None)
        if kind is None:
            self.fail(_join(key, name), f"missing key (one of: {', '.join(spec.options)})")
        if not isinstance(kind, str):
            self.fail(_join(key, name), f"expected a string (one of: "
                      f"{', '.join(spec.options)}), got {_show(kind)}")
        if kind not in spec.options:
            close = difflib.get_close_matches(str(kind), list(spec.options), n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            self.fail(_join(key, name),
                      f"unknown {'kind' if name == 'kind' else 'value'} {_show(kind)} "
                      f"({hint}expected one of: {', '.join(spec.options)})")
        rest = {k: v for k, v in value.items() if k != name}
        out = self.fields({**spec.common, **spec.options[kind]}, rest, key)
        out[name] = kind
        return out

    def value(self, spec, value, key):
        kind = spec.kind
        if kind in ("floats", "ints", "strs"):
            if not isinstance(value, list):
                self.fail(key, f"expected {_describe(spec)}, got {_show(value)}")
            if spec.length and len(value) != spec.length:
                self.fail(key, f"expected {_describe(spec)}, got {len(value)} item(s)")
            item = S.Value(kind[:-1], spec.doc, choices=spec.choices, minimum=spec.minimum,
                           maximum=spec.maximum, open_min=spec.open_min, open_max=spec.open_max)
            return [self.scalar(item, v, key, spec) for v in value]
        if kind == "eps":
            if value == "auto":
                return value
            return self.scalar(S.Value("float", spec.doc, minimum=spec.minimum,
                                       maximum=spec.maximum), value, key, spec)
        if kind == "table":
            self.expect_table(value, key)
            for k, v in value.items():
                if not isinstance(v, str):
                    self.fail(_join(key, k), f"expected a string, got {_show(v)}")
            return dict(value)
        return self.scalar(spec, value, key, spec)

    def scalar(self, spec, value, key, shown):
        kind = spec.kind
        if kind == "float":
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                self.fail(key, f"expected {_describe(shown)}, got {_show(value)}")
            value = float(value)
            if not math.isfinite(value):
                self.fail(key, f"expected a finite number, got {value}")
        elif kind == "int":
            if isinstance(value, bool) or not isinstance(value, int):
                self.fail(key, f"expected {_describe(shown)}, got {_show(value)}")
        elif kind == "bool":
            if not isinstance(value, bool):
                self.fail(key, f"expected true or false, got {_show(value)}")
            return value
        elif kind in ("str", "choice"):
            if not isinstance(value, str):
                self.fail(key, f"expected {_describe(shown)}, got {_show(value)}")
            if spec.choices and value not in spec.choices:
                close = difflib.get_close_matches(value, list(spec.choices), n=1)
                hint = f"did you mean '{close[0]}'? " if close else ""
                self.fail(key, f"unknown value {_show(value)} ({hint}expected one of: "
                          f"{', '.join(spec.choices)})")
            return value
        if not _in_bounds(spec, value):
            self.fail(key, f"expected {_describe(shown)}, got {value!r}")
        return value


def _in_bounds(spec, v):
    return ((spec.minimum is None or v >= spec.minimum)
            and (spec.maximum is None or v <= spec.maximum)
            and (spec.open_min is None or v > spec.open_min)
            and (spec.open_max is None or v < spec.open_max))


def _describe(spec):
    kind = spec.kind
    base = {"float": "a number", "int": "an integer", "str": "a string", "bool": "true or false",
            "choice": "a string", "floats": "a list of numbers", "ints": "a list of integers",
            "strs": "a list of strings", "eps": "\"auto\" or a number"}[kind]
    if spec.length:
        base = base.replace("a list", f"a list of {spec.length}")
    bounds = []
    if spec.minimum is not None:
        bounds.append(f">= {spec.minimum:g}")
    if spec.open_min is not None:
        bounds.append(f"> {spec.open_min:g}")
    if spec.maximum is not None:
        bounds.append(f"<= {spec.maximum:g}")
    if spec.open_max is not None:
        bounds.append(f"< {spec.open_max:g}")
    if bounds:
        base += " " + " and ".join(bounds)
    if spec.unit and spec.unit != "-":
        base += f" [{spec.unit}]"
    return base


def _show(value):
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f"'{value}'"
    return repr(value)
