"""What decides a round's result, and the fingerprints that key the cache.

`EvalSettings` holds every option that changes a round's result, plus fingerprints of the code,
the map assets and (with combat) the damage models, so a cached result is reused only for the
same file content, round, options, code and models. The fixed grids on which per-round data are
kept compact (`HeatGrid`, the HP time grid) are part of the settings too.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from decoy_cli.damage.choice import ModelChoice
from decoy_cli.esta import Round
from decoy_cli.esta.content import content_sha256
from decoy_cli.evaluate.heat import HeatGrid
from decoy_cli.replay.replayer import ReplaySpec
from decoy_cli.world.navmesh import asset_dir

if TYPE_CHECKING:
    from decoy_cli.waypoints.build import GameWorld

RECORD_VERSION = 9
"""Format of the cached per-round records and file indexes; bump when it changes."""

HP_BIN_S = 1.0
"""Width of a bin of the HP-over-time curve (seconds since freeze-time end)."""

HP_BINS = 240
"""Bins of the HP-over-time curve: 0 to 240 s covers a full round with a planted bomb."""

_CODE_PARTS = (
    "csgo.py",
    "weapons.py",
    "esta",
    "replay",
    "sim",
    "metrics",
    "waypoints",
    "world",
    "damage",
    "evaluate/heat.py",
    "evaluate/job.py",
    "evaluate/record.py",
    "evaluate/settings.py",
)
"""The package's modules that decide a round's result (presentation code is left out)."""


@dataclass(frozen=True, kw_only=True)
class EvalSettings(ReplaySpec):
    """Everything that decides one round's result; its JSON is hashed into the cache key.

    The replay's spec (`ReplaySpec`: the mover, `combat`, `bomb`, the seed, the protocols) and
    what an evaluation adds: the map, the damage-model choice a worker loads (only used with
    combat), the code's and the models' fingerprints, the grids, the graph and sight files.
    """

    map_name: str
    models: ModelChoice
    grid: HeatGrid
    code: str
    """Fingerprint of the result-deciding code and the map's assets (`code_fingerprint`)."""
    models_fingerprint: str
    """Fingerprint of the damage model files ("" without combat or with no model)."""
    fastdtw: bool = False
    """Also compute `paper_dtw_fastdtw` (the paper's FastDTW; slow, `metrics.fastdtw_metric`)."""
    hp_bin_s: float = HP_BIN_S
    hp_bins: int = HP_BINS
    world: str = "csgo"
    """The shipped world rounds replay on without a user's graph: "csgo" or "cs2" ("": the
    user's graph brings its own)."""
    graph: str = ""
    """A user's waypoint graph file, absolute ("": the map's shipped graph); rounds are replayed
    on it and on the world it was built on (`graph_world`)."""
    graph_sha: str = ""
    """SHA-256 of that file (a different graph is a different result)."""
    sight_mesh: str = ""
    """A map's geometry for line of sight (`--sight-mesh`), absolute ("": the graph's world)."""
    sight_mesh_sha: str = ""
    """SHA-256 of that file."""

    @property
    def shipped_world(self) -> GameWorld:
        """The world of the map's shipped graph a run without `graph` replays on."""
        return "cs2" if self.world == "cs2" else "csgo"

    def to_json(self) -> str:
        return json.dumps({**asdict(self), "models": str(self.models)}, sort_keys=True)


def round_key(settings: EvalSettings, file_sha: str, round_num: int) -> str:
    """The cache key of one round's result under these settings."""
    text = f"round|{RECORD_VERSION}|{settings.to_json()}|{file_sha}|{round_num}"
    return hashlib.sha256(text.encode()).hexdigest()


def index_key(settings: EvalSettings, file_sha: str) -> str:
    """The cache key of a file's index (its rounds, map and provenance); depends on the code and
    on the policy for implausible rounds (which decides the rounds that failed) and on the frame
    rate awpy's ticks are read at."""
    text = (
        f"index|{RECORD_VERSION}|{settings.code}|{settings.implausible}|{settings.rate}|{file_sha}"
    )
    return hashlib.sha256(text.encode()).hexdigest()


def round_seed(settings: EvalSettings, source: str, round_num: int) -> int:
    """The simulator seed of one round: fixed by the run's seed, the round's `seed_source` and
    its number."""
    digest = hashlib.sha256(f"{settings.seed}|{source}|{round_num}".encode()).digest()
    return int.from_bytes(digest[:8], "little") & (2**63 - 1)


def seed_source(round_: Round, file_sha: str) -> str:
    """What a round's random numbers are drawn from beside the run's seed: an ESTA round's file
    content, a CS2 round's place in its demo (map, round, ticks, players), so that every form
    of one demo's tables (an awpy 2 zip, a folder of awpy 3 tables, the demo) draws the same."""
    if round_.source == "ESTA":
        return file_sha
    players = sorted((p.steam_id or "", p.name, p.side) for p in round_.players)
    place = [round_.map_name, round_.round_num, round_.start_tick, round_.end_tick, players]
    return hashlib.sha256(json.dumps(place, default=str).encode()).hexdigest()


@cache
def code_fingerprint(map_name: str) -> str:
    """Hash of the result-deciding source files and the map's asset files.

    Computed once per process: the code a process runs does not change while it runs, so two
    runs in one process (a test's interrupted run and its resume) agree even if files change.
    """
    package = Path(__file__).resolve().parents[1]
    files: list[tuple[str, Path]] = []
    for part in _CODE_PARTS:
        path = package / part
        for file in sorted(path.rglob("*.py")) if path.is_dir() else [path]:
            files.append((file.relative_to(package).as_posix(), file))
    assets = asset_dir(map_name)  # the top-level assets/ in a checkout, decoy_cli/assets installed
    for file in sorted(p for p in assets.rglob("*") if p.is_file()):
        files.append((f"assets/{map_name}/{file.relative_to(assets).as_posix()}", file))
    digest = hashlib.sha256()
    for name, path in files:
        digest.update(name.encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def folder_fingerprint(folder: Path) -> str:
    """Hash of every file in a folder (names and contents), e.g. a damage-model folder."""
    digest = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        digest.update(str(path.relative_to(folder)).encode() + b"\0")
        digest.update(content_sha256(path).encode())
    return digest.hexdigest()
