"""What differs between two files that should be byte for byte the same: the first npz member
or JSON field, named with both values, for the failure message of a rebuild test."""

from __future__ import annotations

import json
import lzma
from pathlib import Path
from typing import Any

import numpy as np

XZ_MAGIC = b"\xfd7zXZ\x00"


def npz_difference(built: Path, shipped: Path) -> str:
    """The first npz member (array) that differs, and how; or what else differs."""
    with np.load(built, allow_pickle=False) as a, np.load(shipped, allow_pickle=False) as b:
        if sorted(a.files) != sorted(b.files):
            return f"members differ: built {sorted(a.files)}, shipped {sorted(b.files)}"
        for name in sorted(a.files):
            x, y = a[name], b[name]
            if x.dtype != y.dtype or x.shape != y.shape:
                return f"{name}: built {x.dtype}{x.shape}, shipped {y.dtype}{y.shape}"
            if not np.array_equal(x, y):
                where = np.argwhere(x != y)[0] if x.ndim else ()
                index = tuple(int(i) for i in where)
                return (
                    f"{name}[{', '.join(map(str, index))}]: built {x[index].item()!r}, "
                    f"shipped {y[index].item()!r} ({int(np.sum(x != y))} elements differ)"
                )
    return "every array is equal: the zip container differs (member order or metadata)"


def _document(path: Path) -> Any:
    data = path.read_bytes()
    if data.startswith(XZ_MAGIC):
        data = lzma.decompress(data)
    return json.loads(data)


def json_difference(built: Path, shipped: Path) -> str:
    """The first JSON path whose value differs (xz or plain files), with both values."""
    found = _first_difference(_document(built), _document(shipped), "$")
    return found or "the JSON is equal: the encoding or compression differs"


def _first_difference(a: Any, b: Any, path: str) -> str | None:
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):
            return f"{path}: keys differ: built {list(a)[:8]}, shipped {list(b)[:8]}"
        for key in a:
            found = _first_difference(a[key], b[key], f"{path}.{key}")
            if found:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{path}: built {len(a)} items, shipped {len(b)}"
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            found = _first_difference(x, y, f"{path}[{i}]")
            if found:
                return found
        return None
    if type(a) is not type(b) or a != b:
        return f"{path}: built {a!r}, shipped {b!r}"
    return None
