"""How a round ends (`round_outcome`, asked through `BombRules.outcome`), checked in this order:

1. bomb exploded -> T "TargetBombed"; bomb defused -> CT "BombDefused";
2. both sides eliminated on the same tick (damage is applied simultaneously) -> "TerroristsWin"
   if the bomb is planted (a planted bomb denies the CT any elimination win), else CT "CTWin"
   (the T side failed its objective, as when only the T are eliminated);
3. all CT dead -> T "TerroristsWin" (before or after a plant);
4. all T dead and no bomb planted -> CT "CTWin" (after a plant the round goes on until the
   detonation or a defuse);
5. tick >= round_ticks (115 s = 6900 ticks) and no bomb planted -> CT "TargetSaved": a planted
   bomb stops the round clock. A plant that completes on the last tick beats the clock, because
   the engine advances the rules before it asks for the outcome.

A side with no agent at all is never "eliminated": a T-only round (the paper's T-side replay)
ends by detonation, by all T dying (CTWin, or the detonation after a plant) or by time. With
`bomb_enabled=False` (the paper's movement-only evaluation) the bomb plays no part and a round
ends by elimination or time only.
"""

from __future__ import annotations

import numpy as np

from decoy_cli.sim.rules_config import RulesConfig
from decoy_cli.sim.state import Agents, Bomb, BombStatus, RoundOutcome


def round_outcome(
    tick: int, agents: Agents, bomb: Bomb, config: RulesConfig
) -> RoundOutcome | None:
    """How the round ended at this tick, or None while it goes on."""
    planted = False
    if config.bomb_enabled:
        if bomb.status == BombStatus.EXPLODED:
            return RoundOutcome("T", "TargetBombed", tick)
        if bomb.status == BombStatus.DEFUSED:
            return RoundOutcome("CT", "BombDefused", tick)
        planted = bomb.status == BombStatus.PLANTED
    t_out = bool(np.any(agents.side == "T")) and agents.alive_of_side("T") == 0
    ct_out = bool(np.any(agents.side == "CT")) and agents.alive_of_side("CT") == 0
    if t_out and ct_out:
        return (
            RoundOutcome("T", "TerroristsWin", tick)
            if planted
            else RoundOutcome("CT", "CTWin", tick)
        )
    if ct_out:
        return RoundOutcome("T", "TerroristsWin", tick)
    if t_out and not planted:
        return RoundOutcome("CT", "CTWin", tick)
    if not planted and tick >= config.round_ticks:
        return RoundOutcome("CT", "TargetSaved", tick)
    return None
