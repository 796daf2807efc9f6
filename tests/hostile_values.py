"""Hypothesis strategies of hostile values for the fields of the files decoy reads (issue 51),
as raw JSON text or CSV cells, and a way to put one into a document at a field's place.

Usage from another test module: `from hostile_values import hostile_json, leaf_places, put`.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from hypothesis import strategies as st

_SCALARS = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from([0, -1, 2**63, -(2**63), 2**63 - 1, 10**300]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([sys.float_info.max, -sys.float_info.max, 5e-324, -0.0, 1e308]),
    st.text(max_size=30),
    st.sampled_from(["", "NaN", "inf", "de_dust2", "../..", "\x1b[2J", "a" * 5000]),
)
_VALUES = st.recursive(
    _SCALARS,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=12,
)
_RAW = st.sampled_from(["Infinity", "-Infinity", "NaN", "1e999", "-1e999", "9" * 5000])
_DEEP = st.integers(min_value=1, max_value=5000).map(lambda n: "[" * n + "]" * n)


def hostile_json() -> st.SearchStrategy[str]:
    """Raw JSON text of a hostile value: any JSON value (with NaN and infinities as Python's
    `json` writes them), a number strict JSON has not, or nesting up to 5,000 levels."""
    return st.one_of(_VALUES.map(lambda v: json.dumps(v, allow_nan=True)), _RAW, _DEEP)


def hostile_cell() -> st.SearchStrategy[str]:
    """A hostile CSV cell: text, numbers of every size and kind, empty."""
    return st.one_of(
        _SCALARS.map(str),
        st.sampled_from(["", "nan", "inf", "-inf", "1e999", "True", "1.5", "-3", "0x10", " 7 "]),
    )


Place = tuple[str | int, ...]


def leaf_places(document: Any, place: Place = ()) -> list[Place]:
    """The place of every field of `document` (each object's key, each list's item, down)."""
    items = (
        document.items()
        if isinstance(document, dict)
        else enumerate(document)
        if isinstance(document, list)
        else None
    )
    if items is None or not document:
        return [place]
    places = [place]
    for key, value in items:
        places += leaf_places(value, (*place, key))
    return places


MARK = "\x00HOSTILE\x00"


def put(document: Any, place: Place, raw: str) -> str:
    """`document` as JSON text with the value at `place` replaced by the raw JSON `raw`."""
    if not place:
        return raw
    copy = json.loads(json.dumps(document))
    parent = copy
    for key in place[:-1]:
        parent = parent[key]
    parent[place[-1]] = MARK
    return json.dumps(copy).replace(json.dumps(MARK), raw)
