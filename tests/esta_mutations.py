"""Mutations of the fixture match for fuzzing: hypothesis strategies and the file they give.

A mutation deletes keys or list items, or swaps values for other types, nulls, NaN, infinities,
huge numbers and strings (`mutations`); then the bytes may be damaged (`byte_damage`: truncate
or flip a byte) and compressed with xz, maybe cut (`compression`). `damaged_file` applies them
to a copy of `esta_fixtures.make_match()`. Used by the reader's and the CLI's fuzz tests.
"""

from __future__ import annotations

import copy
import json
import lzma
from collections.abc import Iterator
from typing import Any

from esta_fixtures import encode, make_match
from hypothesis import strategies as st

_BASE = encode(make_match())
_DELETE = "<delete>"
_REPLACEMENTS: list[Any] = [
    _DELETE,
    None,
    float("nan"),
    float("inf"),
    -1.0e308,
    2**70,
    -1,
    0,
    1.5,
    12_345.0,
    True,
    "",
    "AK-47",
    "not a value",
    [],
    [None],
    {},
    {"x": 1},
]


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every path to a value inside the document."""
    if isinstance(node, dict):
        items = node.items()
    elif isinstance(node, list):
        items = enumerate(node)
    else:
        return
    for key, child in items:
        yield (*prefix, key)
        yield from _paths(child, (*prefix, key))


_PATHS = list(_paths(make_match()))


def _apply(document: Any, path: tuple[Any, ...], replacement: Any) -> None:
    """Replace or delete the value at `path`; a path an earlier deletion removed is skipped."""
    parent = document
    try:
        for key in path[:-1]:
            parent = parent[key]
        parent[path[-1]]
    except (KeyError, IndexError, TypeError):
        return
    if not isinstance(parent, dict | list):  # an earlier mutation put a string (or number) here
        return
    if isinstance(replacement, str) and replacement == _DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = copy.deepcopy(replacement)


mutations = st.lists(st.tuples(st.sampled_from(_PATHS), st.sampled_from(_REPLACEMENTS)), max_size=4)
byte_damage = st.one_of(
    st.none(),
    st.tuples(st.just("truncate"), st.floats(0, 1), st.just(0)),
    st.tuples(st.just("flip"), st.floats(0, 1), st.integers(1, 255)),
)
compression = st.one_of(st.none(), st.just(1.0), st.floats(0, 1))
"""None: plain JSON; a fraction: xz, cut to that fraction of its length (1.0: whole)."""


def damaged_file(
    changes: list[tuple[tuple[Any, ...], Any]],
    damage: tuple[str, float, int] | None,
    xz_fraction: float | None,
) -> bytes:
    document = json.loads(_BASE)
    for path, replacement in changes:
        _apply(document, path, replacement)
    data = encode(document)
    if damage is not None:
        kind, fraction, xor = damage
        at = min(int(fraction * len(data)), len(data) - 1)
        data = (
            data[:at]
            if kind == "truncate"
            else data[:at] + bytes([data[at] ^ xor]) + data[at + 1 :]
        )
    if xz_fraction is not None:
        data = lzma.compress(data)
        data = data[: max(1, int(xz_fraction * len(data)))]
    return data
