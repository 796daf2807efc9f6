"""Which JSON decoder the ESTA reader uses: msgspec straight into typed structs, against json,
orjson and msgspec into dicts (the choice stated in decoy_cli/esta/schema.py and reader.py).

Times, on the 15 real T-side matches in ../shared/data/esta_dust2_tside and on a synthetic match
of about 50 MB (the rounds of the largest real file repeated, renumbered, xz-compressed once into
the system temp folder and reused): xz decompression, then each decoder on the decompressed
bytes (json, orjson and msgspec into dicts; msgspec into the reader's typed structs, which is
what the reader does), then the whole `read_match` (read, decompress, decode, build arrays and
tables). Each step is run `--repeats` times per file and the median kept; for the 15 real files
the table shows the median and range over files. The reader's throughput alone is
`decoy bench --sections reader`.

    python benchmarks/studies/json_decoders.py [--repeats 3] [--synthetic-mb 50]
"""

from __future__ import annotations

import argparse
import json
import lzma
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import msgspec
import orjson

from decoy_cli.esta import iter_match_files, read_match
from decoy_cli.esta.source import decode_round, parse

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "esta_dust2_tside"


def _typed_decode(path: Path, data: bytes) -> None:
    """The reader's decoding: split the document, then every round into typed structs."""
    for source in parse(path, data).rounds:
        decode_round(source)


def _steps(path: Path, data: bytes) -> dict[str, Callable[[], object]]:
    generic = msgspec.json.Decoder()
    return {
        "json.loads (dicts)": lambda: json.loads(data),
        "orjson.loads (dicts)": lambda: orjson.loads(data),
        "msgspec (dicts)": lambda: generic.decode(data),
        "msgspec typed (reader)": lambda: _typed_decode(path, data),
        "read_match (total)": lambda: read_match(path),
    }


def _median_time(step: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        step()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _time_file(path: Path, repeats: int) -> tuple[int, dict[str, float]]:
    """Decompressed size and the median time of every step on one file."""
    compressed = path.read_bytes()
    data = lzma.decompress(compressed)
    times = {"xz decompress": _median_time(lambda: lzma.decompress(compressed), repeats)}
    for name, step in _steps(path, data).items():
        times[name] = _median_time(step, repeats)
    return len(data), times


def _synthetic(source: Path, target_mb: float) -> Path:
    """A match of about `target_mb` MB decompressed: the source's rounds repeated, renumbered."""
    folder = Path(tempfile.gettempdir()) / "decoy_json_decoders"
    folder.mkdir(exist_ok=True)
    path = folder / f"synthetic-{target_mb:g}MB-from-{source.name}"
    if path.exists():
        return path
    document = orjson.loads(lzma.decompress(source.read_bytes()))
    rounds = document["gameRounds"]
    per_round = len(orjson.dumps(document)) / len(rounds)
    copies = max(1, round(target_mb * 1e6 / per_round))
    document["gameRounds"] = [{**rounds[i % len(rounds)], "roundNum": i + 1} for i in range(copies)]
    document["matchID"] = f"synthetic from {source.name}"
    path.write_bytes(lzma.compress(orjson.dumps(document)))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per step and file")
    parser.add_argument("--synthetic-mb", type=float, default=50.0, help="synthetic match size")
    args = parser.parse_args()
    if not DATA.is_dir():
        sys.exit(f"real ESTA data not found at {DATA} (../shared/data next to the repo)")

    files = iter_match_files(DATA)
    sizes, per_file = [], []
    for path in files:
        size, times = _time_file(path, args.repeats)
        sizes.append(size)
        per_file.append(times)
    largest = files[sizes.index(max(sizes))]
    synthetic = _synthetic(largest, args.synthetic_mb)
    synthetic_size, synthetic_times = _time_file(synthetic, args.repeats)
    rounds = len(read_match(synthetic).rounds)

    print(
        f"{len(files)} real matches: {min(sizes) / 1e6:.1f}-{max(sizes) / 1e6:.1f} MB decompressed"
        f" (median {statistics.median(sizes) / 1e6:.1f} MB); synthetic: "
        f"{synthetic_size / 1e6:.1f} MB, {rounds} rounds ({synthetic})"
    )
    print(f"median of {args.repeats} runs per file, seconds")
    header = f"{'step':<24} {'real: median':>12} {'[min - max]':>16} {'synthetic':>10}"
    print(header)
    print("-" * len(header))
    for name in per_file[0]:
        values = [times[name] for times in per_file]
        print(
            f"{name:<24} {statistics.median(values):>12.3f} "
            f"{f'[{min(values):.3f} - {max(values):.3f}]':>16} {synthetic_times[name]:>10.3f}"
        )


if __name__ == "__main__":
    main()
