"""The parameters of a sweep and its variants.

A parameter is KEY=VALUES: VALUES a TOML value or list ([0.2, 0.4]) or start:stop:count
(count values from start to stop, both included). The variants are every combination (grid,
the first parameter slowest) or the lists paired (zip, equal lengths). Each variant is the case
with its values as --set overrides after the sweep's own, and is named by its values (a hash of
its keys and their TOML literals), so its outputs keep their meaning whatever list it came
from: a resumed sweep with another list finds each value's own outputs, never another's.
"""
import hashlib
import itertools
import math
import tomllib
from dataclasses import dataclass

import numpy as np

from ..case.loading import literal
from ..errors import CaseError

WHERE = "command line"
MAX_VARIANTS = 10_000      # a campaign of more is a typo (a count of 1e5)
PLAIN = (bool, int, float, str)


@dataclass(frozen=True)
class Parameter:
    key: str
    listed: tuple = ()     # the values given as a TOML value or list
    span: tuple = None     # (start, stop, count) of start:stop:count: its values made on demand

    @property
    def count(self):
        """How many values, known before any is made."""
        return self.span[2] if self.span else len(self.listed)

    @property
    def values(self):
        if not self.span:
            return self.listed
        start, stop, count = self.span
        # to 15 digits: 0:0.6:4 is 0.4, not linspace's 0.39999999999999997
        return tuple(float(f"{x:.15g}") for x in np.linspace(start, stop, count))


@dataclass(frozen=True)
class Variant:
    name: str              # v-<12 hex digits> of its values: its history is DIR/<name>.h5
    values: dict           # key -> value

    def overrides(self):
        return [f"{k}={literal(v)}" for k, v in self.values.items()]

    def label(self):
        return ", ".join(f"{k}={literal(v)}" for k, v in self.values.items())


def variant_name(values):
    """The name of the variant of these values (key -> value): a hash of its keys and their
    TOML literals, in key order (0.5 and 0.50 read back to one value, so one name)."""
    text = "\n".join(f"{k}={literal(values[k])}" for k in sorted(values))
    return "v-" + hashlib.sha256(text.encode()).hexdigest()[:12]


def parse_parameter(text):
    """A Parameter from KEY=VALUES; CaseError on a malformed one."""
    key, sep, values = text.partition("=")
    key, values = key.strip(), values.strip()
    if not sep or not key or not values:
        raise CaseError(WHERE, "--param", f"expected KEY=VALUES, got '{text}'")
    parts = values.split(":")
    if len(parts) == 3 and not values.startswith(("[", '"', "'")):
        return Parameter(key, span=_span(key, values, parts))
    try:
        value = tomllib.loads(f"x = {values}")["x"]
    except (tomllib.TOMLDecodeError, ValueError, RecursionError):
        raise CaseError(WHERE, f"--param {key}", f"expected a TOML value or list, or "
                        f"start:stop:count, got '{values}'") from None
    value = value if isinstance(value, list) else [value]
    if not value:
        raise CaseError(WHERE, f"--param {key}", "an empty list: no variant")
    if len(value) > MAX_VARIANTS:
        raise CaseError(WHERE, f"--param {key}", f"{len(value)} values (more than "
                        f"{MAX_VARIANTS} variants)")
    bad = next((v for v in value if not _plain(v)), None)
    if bad is not None:
        kind = "table" if isinstance(bad, dict) else type(bad).__name__
        raise CaseError(WHERE, f"--param {key}", f"a {kind} value: expected "
                        "numbers, strings, booleans or lists of them")
    return Parameter(key, tuple(value))


def _span(key, values, parts):
    """(start, stop, count) of start:stop:count, checked before any value is made."""
    try:
        start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise CaseError(WHERE, f"--param {key}", f"expected start:stop:count (numbers, "
                        f"an integer count), got '{values}'") from None
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise CaseError(WHERE, f"--param {key}", f"start and stop must be finite numbers, "
                        f"got '{values}'")
    if count < 1:
        raise CaseError(WHERE, f"--param {key}", f"count {count}: expected at least 1")
    if count > MAX_VARIANTS:
        raise CaseError(WHERE, f"--param {key}", f"count {count}: more than {MAX_VARIANTS} "
                        "variants")
    return start, stop, count


def _plain(value):
    if isinstance(value, list):
        return all(_plain(v) for v in value)
    return isinstance(value, PLAIN)


def count_variants(parameters, mode="grid"):
    """How many variants the parameters make, from their lengths alone (Python integers: no
    overflow, no list built); CaseError above MAX_VARIANTS or for zip lists of unequal
    lengths."""
    if mode == "zip":
        lengths = {p.key: p.count for p in parameters}
        if len(set(lengths.values())) > 1:
            raise CaseError(WHERE, "--zip", "the lists must be as long as each other: "
                            + ", ".join(f"{k} {n}" for k, n in lengths.items()))
        count = next(iter(lengths.values()))
    else:
        count = math.prod(p.count for p in parameters)
    if count > MAX_VARIANTS:
        raise CaseError(WHERE, "--zip" if mode == "zip" else "--param",
                        f"{count} variants (more than {MAX_VARIANTS})")
    return count


def make_variants(parameters, mode="grid"):
    """The variants of the parameters: 'grid' (every combination) or 'zip' (paired)."""
    if not parameters:
        raise CaseError(WHERE, "--param", "a sweep needs at least one --param KEY=VALUES")
    keys = [p.key for p in parameters]
    if len(set(keys)) < len(keys):
        raise CaseError(WHERE, "--param", f"a key given twice: {', '.join(keys)}")
    count_variants(parameters, mode)
    lists = [p.values for p in parameters]
    rows = zip(*lists) if mode == "zip" else itertools.product(*lists)
    variants, seen = [], set()
    for row in rows:
        values = dict(zip(keys, row))
        name = variant_name(values)
        if name in seen:
            label = ", ".join(f"{k}={literal(v)}" for k, v in values.items())
            raise CaseError(WHERE, "--param", f"the variant {label} is given twice (a variant "
                            "is named by its values)")
        seen.add(name)
        variants.append(Variant(name, values))
    return variants
