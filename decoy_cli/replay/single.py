"""One round replayed for a person: from a round address to the files `decoy replay` writes.

`replay_address` reads the round, checks its map, replays it, measures every player and
writes `replay.csv`, `events.csv`, `players.csv`, `summary.json`, `trace.json`, `paths.png`
(and `round.gif`) into the output folder; the command only parses options and prints what
this returns.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, replace
from pathlib import Path

import pandas as pd

from decoy_cli.errors import DecoyError
from decoy_cli.esta import Round, load_round
from decoy_cli.esta.content import content_sha256
from decoy_cli.esta.frame_rate import describe_frame_rate
from decoy_cli.esta.reader import MATCH_SUFFIXES
from decoy_cli.files import staged
from decoy_cli.metrics.players import player_metrics
from decoy_cli.replay.output import animate, plot_paths, write_replay
from decoy_cli.replay.replayer import ReplayOptions, ReplayResult, replay_round
from decoy_cli.sim.setup import SIGHT_WITHOUT_SHOOTING
from decoy_cli.waypoints.build import GameWorld, canonical_map, chosen_graph
from decoy_cli.world.navmesh import BUILTIN_MAP, load_navmesh
from decoy_cli.world.occlusion import read_sight_scene

DEFAULT_REPLAY_OUT = Path("decoy-out") / "replay"


@dataclass(frozen=True)
class SingleReplay:
    """A replayed round with its per-player table, its summary and where it was written."""

    round_: Round
    options: ReplayOptions
    result: ReplayResult
    players: pd.DataFrame
    summary: dict[str, object]
    folder: Path
    seconds: float


def replay_address(
    address: str,
    options: ReplayOptions,
    *,
    models: str | None,
    map_name: str | None = None,
    graph_file: Path | None = None,
    out: Path | None = None,
    gif: bool = False,
    sight_mesh: Path | None = None,
    world: GameWorld = "csgo",
) -> SingleReplay:
    """Replay the round at "FILE:ROUND" and write its files (see the module docstring).

    `models` names the damage models in the summary (None: no shooting). The round is replayed
    on its own map (the file's `mapName`); `map_name`, when given, must agree with it, and so
    must the map a `graph_file` was built for. `sight_mesh`: the map's geometry line of sight
    is tested in when shooting (`read_sight_scene`); without shooting it is an error.
    """
    if map_name is not None:
        map_name = canonical_map(map_name)  # an unknown --map fails before reading the file
    round_ = load_round(address, implausible=options.implausible, rate=options.rate)
    map_id = round_map(address, round_.map_name, map_name)
    graph = chosen_graph(map_id, world, graph_file)
    graph_map = str(graph.meta.get("map", ""))
    if graph_map and graph_map != map_id:
        raise DecoyError(f"{address}: a {map_id} round, but the graph {graph_file} is {graph_map}")
    sight = "the graph's world"
    if sight_mesh is not None:
        if not options.combat:
            raise DecoyError(SIGHT_WITHOUT_SHOOTING)
        scene = read_sight_scene(sight_mesh, graph.positions, map_id)
        options = replace(options, sight=scene)
        sight = f"{sight_mesh.resolve()} (sha256 {scene.sha256[:12]})"
    started = time.perf_counter()
    result = replay_round(round_, graph, options)
    seconds = time.perf_counter() - started
    players = player_metrics(round_, result.trace())
    summary = replay_summary(
        address, round_, options, models, result, players, seconds, sight, graph.world_source
    )
    folder = out or DEFAULT_REPLAY_OUT / replay_folder_name(round_.path, round_.round_num)
    nav = load_navmesh(map_id)
    shown = "".join(c if c.isprintable() else "?" for c in round_.match_id[:8])
    title = f"{shown} round {round_.round_num}: original (dashed) vs replay"
    with staged(folder) as stage:  # all files replace the previous replay's together
        write_replay(stage, round_, result, players, summary)
        plot_paths(stage / "paths.png", round_, result, nav, title=title)
        if gif:
            animate(stage / "round.gif", round_, result, nav)
    return SingleReplay(round_, options, result, players, summary, folder, seconds)


def round_map(address: str, file_map: str, asked: str | None) -> str:
    """The map a round is replayed on: the file's (a built-in map; BUILTIN_MAP when the file
    names none), which must be `asked` when that is given."""
    if not file_map:
        map_id = asked or BUILTIN_MAP
    else:
        try:
            map_id = canonical_map(file_map)
        except DecoyError:
            raise DecoyError(
                f"{address}: a {file_map} round, a map decoy has no world for"
            ) from None
    if asked is not None and asked != map_id:
        raise DecoyError(f"{address}: a {map_id} round, not {asked} (--map)")
    return map_id


def replay_folder_name(file: Path, round_num: int) -> str:
    """The default output folder of a round's replay: the match file's name (letters, digits,
    `.`, `_` and `-` only) and the first 8 hex digits of its content's SHA-256, so the data never
    chooses a path and two files never share a folder."""
    name = file.name
    for suffix in MATCH_SUFFIXES:
        name = name.removesuffix(suffix)
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._")[:64] or "match"
    return f"{safe}-{content_sha256(file)[:8]}_r{round_num}"


def replay_summary(
    address: str,
    round_: Round,
    options: ReplayOptions,
    models: str | None,
    result: ReplayResult,
    players: pd.DataFrame,
    seconds: float,
    sight: str = "the graph's world",
    world: str = "",
) -> dict[str, object]:
    """The contents of `summary.json`: the round, the options, both outcomes, counts, the
    fields inferred, the bomb's fidelity (`BOMB_COLUMNS`, None with the bomb off) and the
    kill-level fidelity (`KILL_COLUMNS`)."""
    outcome = result.outcome
    return {
        "round": address,
        "match_id": round_.match_id,
        "round_num": round_.round_num,
        "options": {
            "combat": options.combat,
            "bomb": options.bomb,
            "mover": options.mover,
            "seed": options.seed,
            "implausible": options.implausible,
            "deaths": options.deaths if options.combat else "data (no shooting)",
            "missing_fields": options.missing,
        },
        "damage_models": models if options.combat else None,
        "world": world,
        "line_of_sight_in": sight if options.combat else None,
        "played_out_s": round(result.played_out_s, 3),
        "outcome_original": {"winner": round_.winning_side, "reason": round_.end_reason},
        "outcome_replay": {
            "winner": outcome.winner if outcome else None,
            "reason": outcome.reason if outcome else None,
        },
        "frames": int(round_.num_frames),
        "frame_rate": describe_frame_rate(round_.frame_seconds),
        "wall_seconds": round(seconds, 3),
        "stuck_episodes": int(players["stuck"].sum()),
        "recoveries": int(players["recoveries"].sum()),
        "relocations": int(players["relocations"].sum()),
        "warnings": list(result.warnings),
        "contradictions": list(result.contradictions),
        "inferred": list(result.inferred),
        "utility": result.utility or "none in the data, or no shooting",
        "bomb": result.bomb_row(),
        "kills": result.kill_row(round_),
    }
