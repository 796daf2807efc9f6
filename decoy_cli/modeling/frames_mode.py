"""Frames mode, the paper's: samples from a round with the frames of both teams.

Per frame, every ordered pair of alive, present enemies with a position, a view yaw and a
firearm of the vocabulary in hand (the simulator never asks DIP about other attackers). Damage
events are aligned to the frame nearest their tick (the reader's `frame_index`) and summed per
(frame, attacker, victim): label 1 for those pairs, 0 for the others. When the nearest frame no
longer shows both players alive (a lethal hit aligned to the frame after the kill), the hit goes
to the frame before, where both were alive. A pair-frame that got only excluded damage (a
grenade, a knife) is dropped, neither positive nor negative.
"""

from __future__ import annotations

import numpy as np

from decoy_cli.esta import Round
from decoy_cli.modeling.damage_rows import VOCABULARY, aggregate, damage_rows, group_id
from decoy_cli.modeling.sample_set import Samples, SampleStats
from decoy_cli.sim.combat import NO_HIT


def has_both_teams(round_: Round) -> bool:
    """True when the round's frames hold players of both sides (frames mode is possible)."""
    sides = {p.side for p in round_.players}
    return round_.num_frames > 0 and sides == {"T", "CT"}


def frame_samples(round_: Round, stats: SampleStats) -> Samples:
    """Frames mode (module docstring)."""
    damages = damage_rows(round_, stats)
    row_of = {p.key: i for i, p in enumerate(round_.players)}
    side = np.array([p.side for p in round_.players])
    players, frames = len(round_.players), round_.num_frames
    valid = (
        round_.present
        & round_.alive
        & (round_.hp > 0)
        & np.isfinite(round_.position).all(axis=2)
        & np.isfinite(round_.yaw)
    )
    armed = np.isin(round_.weapon, list(VOCABULARY))

    def code(f: np.ndarray, a: np.ndarray, v: np.ndarray) -> np.ndarray:
        """One integer per (frame, attacker row, victim row)."""
        return (np.asarray(f, np.int64) * players + a) * players + v

    frame_index = round_.damages["frame_index"].to_numpy()
    a_row = np.array([row_of.get(k, -1) if k is not None else -1 for k in damages.attacker], int)
    v_row = np.array([row_of.get(k, -1) if k is not None else -1 for k in damages.victim], int)
    placed = (a_row >= 0) & (v_row >= 0) & (frame_index >= 0)
    unplaced = int((damages.usable & ~placed).sum())
    if unplaced:
        stats.excluded["players not in the frames"] += unplaced
    step = frame_index.copy()
    for r in np.flatnonzero(placed & damages.usable):
        f, a, v = step[r], a_row[r], v_row[r]
        if not (valid[a, f] and valid[v, f]) and f > 0 and valid[a, f - 1] and valid[v, f - 1]:
            step[r] = f - 1
            stats.realigned += 1
    hits = aggregate(step, a_row, v_row, damages, np.flatnonzero(damages.usable & placed))
    other = np.flatnonzero(placed & ~damages.usable)
    ambiguous = code(step[other], a_row[other], v_row[other])

    t_rows, ct_rows = np.flatnonzero(side == "T"), np.flatnonzero(side == "CT")
    one, two = np.meshgrid(t_rows, ct_rows, indexing="ij")
    pair_a = np.concatenate([one.ravel(), two.ravel()])
    pair_v = np.concatenate([two.ravel(), one.ravel()])
    f_idx = np.repeat(np.arange(frames), len(pair_a))
    a = np.tile(pair_a, frames)
    v = np.tile(pair_v, frames)
    hit_keys = list(hits)
    hit_codes = code(
        np.array([h[0] for h in hit_keys], np.int64),
        np.array([h[1] for h in hit_keys], np.int64),
        np.array([h[2] for h in hit_keys], np.int64),
    )
    codes = code(f_idx, a, v)
    is_hit = np.isin(codes, hit_codes)
    keep = valid[a, f_idx] & valid[v, f_idx] & (armed[a, f_idx] | is_hit)
    keep &= ~np.isin(codes, ambiguous) | is_hit
    f_idx, a, v, codes = f_idx[keep], a[keep], v[keep], codes[keep]
    k = len(f_idx)
    hit = np.zeros(k, dtype=bool)
    damage = np.zeros(k, dtype=np.float32)
    hp_lost = np.zeros(k, dtype=np.float32)
    group = np.full(k, NO_HIT, dtype=np.int8)
    weapon = round_.weapon[a, f_idx].astype(object)
    position_of = {int(c): i for i, c in enumerate(codes)}
    for key, hit_code in zip(hit_keys, hit_codes, strict=True):
        i = position_of.get(int(hit_code))
        if i is None:
            stats.excluded["hit on a pair not alive in its frame"] += 1
            continue
        step = hits[key]
        hit[i], damage[i], hp_lost[i], group[i] = True, step.damage, step.hp_lost, step.group
        weapon[i] = damages.weapon[step.first]  # the gun that fired, not the one in hand
    return Samples(
        map_name=np.full(k, round_.map_name, dtype=object),
        attacker_position=round_.position[a, f_idx],
        victim_position=round_.position[v, f_idx],
        attacker_yaw=round_.yaw[a, f_idx],
        victim_yaw=round_.yaw[v, f_idx],
        attacker_hp=round_.hp[a, f_idx].astype(np.int16),
        victim_hp=round_.hp[v, f_idx].astype(np.int16),
        attacker_weapon=weapon,
        victim_armor=round_.armor[v, f_idx].astype(np.int16),
        victim_helmet=round_.helmet[v, f_idx].astype(bool),
        hit=hit,
        damage=damage,
        hp_lost=hp_lost,
        hit_group=group,
        group=np.full(k, group_id(round_), dtype=object),
        match=np.full(k, round_.match_id, dtype=object),
        tick=round_.frame_ticks[f_idx].astype(np.int64),
        mode=np.full(k, "frames", dtype=object),
    )
