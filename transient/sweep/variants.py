"""The parameters of a sweep and its variants.

A parameter is KEY=VALUES: VALUES a TOML value or list ([0.2, 0.4]) or start:stop:count
(count values from start to stop, both included). The variants are every combination (grid,
the first parameter slowest) or the lists paired (zip, equal lengths). Each variant is the case
with its values as --set overrides after the sweep's own.
"""
import itertools
import tomllib
from dataclasses import dataclass

import numpy as np

from ..case.loading import literal
from ..errors import CaseError

WHERE = "command line"
MAX_VARIANTS = 10_000      # a campaign of more is a typo (a count of 1e5)


@dataclass(frozen=True)
class Parameter:
    key: str
    values: tuple


@dataclass(frozen=True)
class Variant:
    name: str              # v000, v001, ...: its history is DIR/<name>.h5
    values: dict           # key -> value

    def overrides(self):
        return [f"{k}={literal(v)}" for k, v in self.values.items()]

    def label(self):
        return ", ".join(f"{k}={literal(v)}" for k, v in self.values.items())


def parse_parameter(text):
    """A Parameter from KEY=VALUES; CaseError on a malformed one."""
    key, sep, values = text.partition("=")
    key, values = key.strip(), values.strip()
    if not sep or not key or not values:
        raise CaseError(WHERE, "--param", f"expected KEY=VALUES, got '{text}'")
    parts = values.split(":")
    if len(parts) == 3 and not values.startswith(("[", '"')):
        try:
            start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise CaseError(WHERE, f"--param {key}", f"expected start:stop:count (numbers, "
                            f"an integer count), got '{values}'") from None
        if count < 1:
            raise CaseError(WHERE, f"--param {key}", f"count {count}: expected at least 1")
        # to 15 digits: 0:0.6:4 is 0.4, not linspace's 0.39999999999999997
        return Parameter(key, tuple(float(f"{x:.15g}") for x in np.linspace(start, stop,
                                                                            count)))
    try:
        value = tomllib.loads(f"x = {values}")["x"]
    except tomllib.TOMLDecodeError:
        raise CaseError(WHERE, f"--param {key}", f"expected a TOML value or list, or "
                        f"start:stop:count, got '{values}'") from None
    if isinstance(value, list):
        if not value:
            raise CaseError(WHERE, f"--param {key}", "an empty list: no variant")
        return Parameter(key, tuple(value))
    return Parameter(key, (value,))


def make_variants(parameters, mode="grid"):
    """The variants of the parameters: 'grid' (every combination) or 'zip' (paired)."""
    if not parameters:
        raise CaseError(WHERE, "--param", "a sweep needs at least one --param KEY=VALUES")
    keys = [p.key for p in parameters]
    if len(set(keys)) < len(keys):
        raise CaseError(WHERE, "--param", f"a key given twice: {', '.join(keys)}")
    if mode == "zip":
        lengths = {p.key: len(p.values) for p in parameters}
        if len(set(lengths.values())) > 1:
            raise CaseError(WHERE, "--zip", "the lists must be as long as each other: "
                            + ", ".join(f"{k} {n}" for k, n in lengths.items()))
        rows = list(zip(*(p.values for p in parameters)))
    else:
        count = int(np.prod([len(p.values) for p in parameters]))
        if count > MAX_VARIANTS:
            raise CaseError(WHERE, "--param", f"{count} variants (more than {MAX_VARIANTS})")
        rows = list(itertools.product(*(p.values for p in parameters)))
    return [Variant(f"v{i:03d}", dict(zip(keys, row))) for i, row in enumerate(rows)]
