"""The synthetic ESTA sample: scripted rounds played in the simulator, written as one match file.

No real ESTA file may ship with the project, so `decoy evaluate` has a built-in sample made here:
`play_match` plays `rounds` scripted 5-on-5 rounds on a built-in map's graph (de_dust2 by
default; strategies and loadouts drawn from `numpy.random.default_rng([seed, round])`, combat
through the given damage model, bomb rules on) and `write_sample` writes them as
`synthetic-<map>-seed<N>.json.xz` (map without its `de_` prefix). The file says what it is:
matchID `synthetic-<map>-seed<N>`, clientName `decoy make-sample`,
and a top-level `provenance` key (as the real T-side files have) with `"synthetic": true`, the
command that made it and what it does and does not record. Same seed and damage model, same
bytes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from decoy_cli import __version__
from decoy_cli.esta.records import MatchRecord
from decoy_cli.esta.writer import write_match
from decoy_cli.sim.combat import DamageModel
from decoy_cli.sim.rules import SiteZones
from decoy_cli.synth.corridors import corridor_plan
from decoy_cli.synth.loadouts import buy_kind, side_loadouts
from decoy_cli.synth.player import (
    DEMO_TICK_RATE,
    PlayedRound,
    RoundScript,
    Team,
    play_round,
    scripted_setup,
)
from decoy_cli.synth.routes import DUST2_PLAN, TEAM_SIZE, Places, plan_round
from decoy_cli.waypoints.build import builtin_graph, canonical_map
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import BUILTIN_MAP

SAMPLE_DIR = Path(__file__).resolve().parents[2] / "examples" / "sample"
"""The shipped synthetic sample, evaluated when no input is given. It lives in the source tree
(a checkout or an editable install), next to the README that says how `decoy make-sample`
regenerates it, rather than inside the package: it is example data, not something the library
needs, so a wheel stays small and its users pass their own data."""

MAX_ROUNDS = 30
HALF_ROUNDS = 15
CLIENT_NAME = "decoy make-sample"
TEAM = Team(
    names=tuple(f"{side}-{k}" for side in ("T", "CT") for k in range(1, TEAM_SIZE + 1)),
    steam_ids=tuple(range(11, 11 + TEAM_SIZE)) + tuple(range(21, 21 + TEAM_SIZE)),
    sides=("T",) * TEAM_SIZE + ("CT",) * TEAM_SIZE,
)
"""The ten synthetic players. Their steamIDs (11-15 T, 21-25 CT: two digits, so the reader's
order by steamID string is T-1..T-5, CT-1..CT-5) are no real account's (real steamID64s are
above 7.6e16), so nothing can be mistaken for a real player."""

TEAM_NAMES = {"T": "Synthetic T", "CT": "Synthetic CT"}


def sample_match_id(seed: int, map_name: str = BUILTIN_MAP) -> str:
    return f"synthetic-{map_name.removeprefix('de_')}-seed{seed}"


def sample_file_name(seed: int, map_name: str = BUILTIN_MAP) -> str:
    return f"{sample_match_id(seed, map_name)}.json.xz"


@dataclass
class SampleMatch:
    """The played match: what is written, and each round as played."""

    match: MatchRecord
    rounds: list[PlayedRound]


def play_match(
    rounds: int,
    seed: int,
    damage_model: DamageModel | None,
    models_label: str,
    graph: WaypointGraph | None = None,
    on_round: Callable[[PlayedRound], None] | None = None,
) -> SampleMatch:
    """Play `rounds` scripted rounds; `models_label` names the damage model in the provenance
    (e.g. "shipped" or "none"); `on_round` is called after each round (progress)."""
    if not 1 <= rounds <= MAX_ROUNDS:
        raise ValueError(f"a match has 1 to {MAX_ROUNDS} rounds, not {rounds}")
    if seed < 0:
        raise ValueError(f"the seed must be >= 0, not {seed}")
    graph = builtin_graph() if graph is None else graph
    map_name = canonical_map(str(graph.meta.get("map", BUILTIN_MAP)))
    places = Places(graph)
    map_plan = DUST2_PLAN if map_name == "de_dust2" else corridor_plan(places)
    zones = SiteZones.from_graph(graph)
    setup = scripted_setup(graph, damage_model)
    physics = setup.open_physics() if setup.needs_physics else None
    played: list[PlayedRound] = []
    cursor = 0
    previous_winner: str | None = None
    try:
        for k in range(rounds):
            rng = np.random.default_rng([seed, k + 1])
            plan = plan_round(places, zones, rng, map_plan)
            buys = {
                side: buy_kind(k, side, previous_winner, HALF_ROUNDS, rng) for side in ("T", "CT")
            }
            loadouts = side_loadouts("T", buys["T"], TEAM_SIZE, rng) + side_loadouts(
                "CT", buys["CT"], TEAM_SIZE, rng
            )
            script = RoundScript(places=places, plan=plan, loadouts=loadouts, team=TEAM, buys=buys)
            result = play_round(
                setup,
                script,
                round_num=k + 1,
                start_tick=cursor,
                seed=int(rng.integers(2**63)),
                physics=physics,
            )
            played.append(result)
            cursor = result.record.end_official_tick
            previous_winner = result.record.winning_side
            if on_round is not None:
                on_round(result)
    finally:
        if physics is not None:
            physics.close()
    match = MatchRecord(
        match_id=sample_match_id(seed, map_name),
        map_name=map_name,
        tick_rate=DEMO_TICK_RATE,
        rounds=[r.record for r in played],
        team_names=TEAM_NAMES,
        provenance=provenance(
            rounds, seed, models_label, combat=damage_model is not None, map_name=map_name
        ),
        client_name=CLIENT_NAME,
    )
    return SampleMatch(match, played)


def provenance(
    rounds: int, seed: int, models_label: str, combat: bool, map_name: str = BUILTIN_MAP
) -> dict[str, Any]:
    """The `provenance` key of a sample file: synthetic, how it was made, what it holds."""
    command = f"decoy make-sample --rounds {rounds} --seed {seed} --models {models_label}"
    if map_name != BUILTIN_MAP:
        command += f" --map {map_name.removeprefix('de_')}"
    return {
        "synthetic": True,
        "generator": CLIENT_NAME,
        "command": command,
        "decoy_version": __version__,
        "seed": seed,
        "damage_models": models_label,
        "combat": combat,
        "note": (
            f"Not real CS:GO data: scripted rounds played in decoy's simulator on the {map_name} "
            "waypoint graph (both teams on plausible routes, bomb rules on, combat "
            f"{'on' if combat else 'off'}), written in the ESTA (awpy 1.x) format."
        ),
        "recorded": (
            "both teams' players at 2 frames per second, bomb, damages, kills, bomb events, "
            "round winners and end reasons"
        ),
        "not_recorded": "grenades, weapon fires, flashes, cash, ammunition, armor damage",
    }


def write_sample(
    out_dir: str | Path,
    rounds: int,
    seed: int,
    damage_model: DamageModel | None,
    models_label: str,
    on_round: Callable[[PlayedRound], None] | None = None,
    map_name: str = BUILTIN_MAP,
) -> tuple[Path, SampleMatch]:
    """Play the sample on a built-in map and write it to
    `out_dir/synthetic-<map>-seed<seed>.json.xz`."""
    graph = builtin_graph(map_name)
    sample = play_match(rounds, seed, damage_model, models_label, graph, on_round=on_round)
    path = write_match(sample.match, Path(out_dir) / sample_file_name(seed, sample.match.map_name))
    return path, sample
