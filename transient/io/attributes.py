"""The root attributes of a history: its meta data, text and numbers stored as such, tables,
lists and None as JSON text (their names listed in the attribute `json_attrs`), read back as
plain Python values checked to be what the readers take (ATTRIBUTES)."""
import json

import numpy as np

from ..errors import DamagedHistory

CASE_TEXT = "case"         # root attribute holding the case file as written
BOOKKEEPING = ("status", "rows", "json_attrs")    # written by History itself


def write_attrs(attrs, meta):
    """Store meta (name -> value) in the HDF5 attributes attrs."""
    encoded = json_keys(attrs)
    for key, value in meta.items():
        if key in BOOKKEEPING:
            raise ValueError(f"meta key '{key}' is reserved")
        if isinstance(value, (dict, list, tuple)) or value is None:
            attrs[key] = json.dumps(value)
            encoded.add(key)
        elif isinstance(value, (str, bool, int, float, np.number, np.bool_, np.ndarray)):
            attrs[key] = value
            encoded.discard(key)
        else:
            raise TypeError(f"meta key '{key}': cannot store a {type(value).__name__}")
    attrs["json_attrs"] = json.dumps(sorted(encoded))


def read_attrs(attrs):
    """Root attributes as plain Python values (JSON ones decoded), bookkeeping left out; one
    that is not what `write_attrs` stores, or not what the readers take (ATTRIBUTES), is a
    DamagedHistory naming it."""
    encoded = json_keys(attrs)
    out = {}
    for key, value in attrs.items():
        if key == "json_attrs":
            continue
        value = _plain(key, value)
        if key in encoded:
            if not isinstance(value, str):
                raise DamagedHistory(f"attribute {key}", f"{short(value)}, expected JSON "
                                     "text")
            try:
                value = json.loads(value)
            except (ValueError, RecursionError):
                raise DamagedHistory(f"attribute {key}", f"not JSON text "
                                     f"({short(value)})") from None
        check, expected = ATTRIBUTES.get(key, (None, None))
        if check is not None and not check(value):
            raise DamagedHistory(f"attribute {key}", f"{short(value)}, expected {expected}")
        out[key] = value
    return out


def json_keys(attrs):
    """The names of the attributes stored as JSON text."""
    try:
        keys = json.loads(attrs.get("json_attrs", "[]"))
    except (ValueError, TypeError, RecursionError):
        keys = None
    if not isinstance(keys, list) or not all(isinstance(k, str) for k in keys):
        raise DamagedHistory("attribute json_attrs", "expected a JSON list of names")
    return set(keys)


def _plain(key, value):
    """An attribute as h5py returns it, as text, a number, a flag or a list of them."""
    if isinstance(value, (np.ndarray, np.generic)):
        # "O": h5py's arrays of strings
        if value.dtype.kind not in "biufO":
            raise DamagedHistory(f"attribute {key}", f"{value.dtype} data, expected text or "
                                 "numbers")
        value = value.tolist()
    elif isinstance(value, bytes):
        value = value.decode("utf-8", "surrogateescape")
    items = np.asarray(value, dtype=object).ravel() if isinstance(value, list) else [value]
    for v in items:
        if isinstance(v, str):
            # h5py escapes bytes that are not UTF-8 as lone surrogates, which print refuses
            try:
                v.encode("utf-8")
            except UnicodeEncodeError:
                raise DamagedHistory(f"attribute {key}", "not UTF-8 text") from None
        elif not isinstance(v, (bool, int, float)):
            raise DamagedHistory(f"attribute {key}", f"{type(v).__name__} data, expected "
                                 "text or numbers")
    return value


def short(value):
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _is_text(v):
    return isinstance(v, str)


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_count(v):
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def _is_table(v):
    return isinstance(v, dict)


# what the readers take from the root attributes (info, plots, export, a resumed run and its
# report), checked when present: a damaged one is refused by name, not met as a traceback
ATTRIBUTES = {
    "status": (_is_text, "text"),
    CASE_TEXT: (_is_text, "the case file as text"),
    "case_path": (_is_text, "a path"),
    "overrides": (lambda v: isinstance(v, list) and all(map(_is_text, v)), "a list of texts"),
    "dt": (lambda v: _is_number(v) and 0 < v < np.inf, "a time step > 0 [s]"),
    "dt_end": (lambda v: _is_number(v) and 0 < v < np.inf, "a time step > 0 [s]"),
    "end_row": (lambda v: isinstance(v, bool), "true or false"),
    "subdivisions": (lambda v: isinstance(v, list) and all(
        _is_table(s) and _is_number(s.get("t")) and _is_number(s.get("dt"))
        and _is_text(s.get("why")) for s in v), "a list of tables of t, dt and why"),
    "reduced": (lambda v: isinstance(v, bool), "true or false"),
    "timings": (_is_table, "a table of seconds"),
    "pairs": (lambda v: _is_table(v) and all(map(_is_table, v.values())),
              "a table of contact pairs"),
    "reduced_dofs": (_is_count, "a count"),
    "normal_modes": (_is_count, "a count"),
    "reduction_method": (lambda v: v in ("assembled", "components"),
                         "assembled or components"),
    "reduction_auto": (_is_text, "text"),
    "band_residual": (lambda v: _is_number(v) and v >= 0, "a residual >= 0"),
    "modes_fmax_hz": (lambda v: _is_number(v) and v > 0, "a frequency > 0 [Hz]"),
    "static_shapes": (lambda v: isinstance(v, list) and len(v) == 2 and all(map(_is_count, v)),
                      "two counts"),
    "sampling": (lambda v: _is_table(v) and _is_number(v.get("residual"))
                 and _is_count(v.get("band_modes")), "a table with residual and band_modes"),
}
