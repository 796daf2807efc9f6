"""Events-only mode: samples from a round's event rows, for files without frames (such as
`esta_dust2_events`).

There are no frames, so a 2 Hz grid of virtual frames (every tick_rate / 2 ticks from the
round's start tick, as ESTA's frames) stands in. Positives are the damage events, grouped per
(virtual frame, attacker, victim) like frames mode; the state is the one written in the group's
first event row. Negatives, an honest proxy: at the virtual frame of every damage, kill, flash
and bomb event, each player seen in an event row (damage, kill, flash: attacker or
victim/flashed player) within `window_s` seconds stands where its nearest such row puts it
(position and view yaw); every ordered enemy pair of such players, both alive, whose attacker
has a known firearm and dealt the victim no damage of any kind within the window, is a negative
(by direction, as frames mode labels ordered pairs: a player who was shot and missed back is a
negative attacker). Bomb events carry no view yaw: they give anchor times, not states. The
attacker's weapon is the firearm of its nearest-in-time damage or kill row of the round (a
player who never hits or kills with a firearm in the round is never an attacker). HP is 100
minus the player's hpDamageTaken in the round before the tick. Armor and helmet, not in events,
are inferred per round and player by the game's armour rules: armor if any hit on the player
removed armor; helmet if a head hit removed armor, no helmet if a head hit removed none or, where
the data records no hit group, a hit removed no armour from the armoured player yet cost more HP
than a leg shot of its weapon at its distance and than any body shot that takes no armour (a
few weapons' body shots take none at some ranges) can: only a bare head takes that; else helmet
= armor, but none in a pistol round (`is_pistol_round`: its start money buys no helmet); a
player never hit counts as armored, with a helmet but in a pistol round (so that the helmet
does not tell the hit from the never hit). A vest worn out earlier in the round (its body hits
then take no armour) is not followed. The biases of this proxy are stated in
models/DIP_CARD.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, is_pistol_round
from decoy_cli.damage.rules import ARMORED_GROUPS, WEAPON_RULES, shot_damage
from decoy_cli.esta import Round
from decoy_cli.modeling.damage_rows import (
    VOCABULARY,
    DamageRows,
    aggregate,
    damage_rows,
    group_id,
    ints,
    player_keys,
    step_clock,
    strings,
)
from decoy_cli.modeling.filled_views import redraw_filled_views
from decoy_cli.modeling.sample_set import Samples, SampleStats, samples_from_rows
from decoy_cli.sim.combat import NO_HIT


@dataclass(frozen=True)
class _Sightings:
    """Where event rows place players: tick, key, side, position (metres) and view yaw."""

    tick: np.ndarray
    key: np.ndarray
    side: np.ndarray
    position: np.ndarray
    yaw: np.ndarray


def _sightings(round_: Round) -> _Sightings:
    """Every (player, tick) an event row places with a position and a view yaw."""
    ticks, keys, sides, positions, yaws = [], [], [], [], []
    for table, owners in (
        (round_.damages, ("attacker", "victim")),
        (round_.kills, ("attacker", "victim")),
        (round_.flashes, ("attacker", "player")),
    ):
        if len(table) == 0:
            continue
        tick = ints(table, "tick")
        for owner in owners:
            ticks.append(tick)
            keys.append(player_keys(table, owner))
            sides.append(strings(table, f"{owner}Side"))
            positions.append(
                np.column_stack([table[f"{owner}{axis}_m"].to_numpy() for axis in "XYZ"])
            )
            yaws.append(table[f"{owner}ViewX"].to_numpy(dtype=np.float64))
    if not ticks:
        empty = np.zeros(0)
        return _Sightings(empty, np.zeros(0, object), np.zeros(0, object), np.zeros((0, 3)), empty)
    tick = np.concatenate(ticks)
    key = np.concatenate(keys)
    side = np.concatenate(sides)
    position = np.concatenate(positions)
    yaw = np.concatenate(yaws)
    known = (
        np.isfinite(tick)
        & np.array([k is not None for k in key], dtype=bool)
        & np.isin(side, ["T", "CT"])
        & np.isfinite(position).all(axis=1)
        & np.isfinite(yaw)
    )
    return _Sightings(tick[known], key[known], side[known], position[known], yaw[known])


class _EventRound:
    """What the event rows of one round say about its players over time (events-only mode)."""

    def __init__(self, round_: Round, damages: DamageRows) -> None:
        self.round = round_
        self.damages = damages
        self.origin, self.step_ticks = step_clock(round_)
        kills = round_.kills
        self.kill_tick = ints(kills, "tick")
        self.kill_victim = player_keys(kills, "victim")
        ticks, keys, names = [], [], []
        for table in (round_.damages, kills):
            weapon = strings(table, "weapon")
            armed = np.isin(weapon, list(VOCABULARY)) & np.isfinite(ints(table, "tick"))
            ticks.append(ints(table, "tick")[armed])
            keys.append(player_keys(table, "attacker")[armed])
            names.append(weapon[armed])
        self.weapon_tick = np.concatenate(ticks)
        self.weapon_key = np.concatenate(keys)
        self.weapon_name = np.concatenate(names)
        self.pistol_round = is_pistol_round(round_.round_num, round_.tick_rate)
        self.armor = self._infer_armor()

    def frame(self, ticks: np.ndarray) -> np.ndarray:
        """The virtual 2 Hz frame nearest each tick."""
        return np.rint((ticks - self.origin) / self.step_ticks).astype(np.int64)

    def frame_tick(self, frame: int) -> int:
        """The tick of a virtual frame."""
        return int(self.origin + frame * self.step_ticks)

    def hp_before(self, player: object, tick: float) -> int:
        """100 minus the player's hpDamageTaken in the round before `tick` (at least 1: the
        player is alive)."""
        rows = (self.damages.victim == player) & (self.damages.tick < tick)
        return int(max(1.0, 100.0 - float(self.damages.hp_taken[rows].sum())))

    def dead_at(self, player: object, tick: float) -> bool:
        """True when a kill row has the player die at or before `tick`."""
        return bool(np.any((self.kill_victim == player) & (self.kill_tick <= tick)))

    def weapon_at(self, player: object, tick: float) -> str | None:
        """The firearm of the player's damage or kill row nearest `tick`; None without one."""
        rows = np.flatnonzero(self.weapon_key == player)
        if len(rows) == 0:
            return None
        return str(self.weapon_name[rows[np.argmin(np.abs(self.weapon_tick[rows] - tick))]])

    def armor_of(self, player: object) -> tuple[int, bool]:
        """(armor as 100 or 0, helmet) as inferred; armored, with a helmet but in a pistol
        round, when never hit."""
        has_armor, helmet = self.armor.get(player, (True, not self.pistol_round))
        return (100 if has_armor else 0), helmet

    def _infer_armor(self) -> dict[object, tuple[bool, bool]]:
        """Per player hit in the round: (armor, helmet) from what its hits say (module doc)."""
        hit_group = strings(self.round.damages, "hitGroup")
        bare_head = self._bare_head_hits(hit_group)
        out: dict[object, tuple[bool, bool]] = {}
        for player in {k for k in self.damages.victim if k is not None}:
            rows = self.damages.victim == player
            armor = bool(np.any(self.damages.armor_damage[rows] > 0))
            head = rows & (hit_group == "Head")
            if head.any():
                helmet = bool(np.any(self.damages.armor_damage[head] > 0))
            else:
                helmet = armor and not self.pistol_round and not np.any(bare_head[rows])
            out[player] = (armor or helmet, helmet)
        return out

    def _bare_head_hits(self, hit_group: np.ndarray) -> np.ndarray:
        """(D,) bool: hits without a recorded group that took no armour and more HP than a leg
        shot of their weapon at their distance does, or a body shot on a full vest that takes no
        armour: only a bare head does that."""
        table, rows = self.round.damages, self.damages
        ends = [
            table[[f"{who}{axis}_m" for axis in "XYZ"]].to_numpy(np.float64)
            for who in ("attacker", "victim")
        ]
        distance = np.linalg.norm(ends[1] - ends[0], axis=1) / HAMMER_TO_M
        bare = np.zeros(len(distance), dtype=bool)
        for d in np.flatnonzero((hit_group == "") & rows.usable & (rows.armor_damage <= 0)):
            weapon = str(rows.weapon[d])
            if weapon in WEAPON_RULES and np.isfinite(distance[d]):
                bare[d] = rows.hp_taken[d] > _most_without_armour(weapon, float(distance[d])) + 1
        return bare


def _most_without_armour(weapon: str, distance_u: float) -> int:
    """The most HP a leg shot, or a body shot on a full vest that takes none of it, of the
    weapon at the distance costs: what a hit that took no armour can cost but from a bare head."""
    most = shot_damage(weapon, "Leg", distance_u, armor=0, helmet=False).health
    for group in ARMORED_GROUPS:
        hit = shot_damage(weapon, group, distance_u, armor=100, helmet=False)
        if hit.armor == 0:
            most = max(most, hit.health)
    return most


def event_samples(round_: Round, window_s: float, stats: SampleStats) -> Samples:
    """Events-only mode (module docstring): positives from the damage rows, then negatives."""
    round_ = redraw_filled_views(round_, stats)
    events = _EventRound(round_, damage_rows(round_, stats))
    rows: list[dict[str, object]] = []
    rows += _event_positives(events, stats)
    rows += _event_negatives(events, window_s * round_.tick_rate)
    common = {
        "map_name": round_.map_name,
        "group": group_id(round_),
        "match": round_.match_id,
        "mode": "events",
    }
    return samples_from_rows([{**common, **row} for row in rows])


def hit_samples(round_: Round, stats: SampleStats) -> Samples:
    """One damaging sample per usable damage row (a hit, not a step): the unit of a model that
    draws one bullet, as `event_samples` builds its positives."""
    round_ = redraw_filled_views(round_, stats)
    events = _EventRound(round_, damage_rows(round_, stats))
    common = {
        "map_name": round_.map_name,
        "group": group_id(round_),
        "match": round_.match_id,
        "mode": "events",
    }
    rows = _event_positives(events, stats, per_hit=True)
    return samples_from_rows([{**common, **row} for row in rows])


def _event_positives(
    events: _EventRound, stats: SampleStats, per_hit: bool = False
) -> list[dict[str, object]]:
    """One sample per (virtual frame, attacker, victim) with usable damage, or per usable row
    with `per_hit`; the state of the group's first damage row."""
    damages, table = events.damages, events.round.damages
    usable = np.flatnonzero(damages.usable)
    frame = np.arange(len(damages.tick)) if per_hit else events.frame(np.nan_to_num(damages.tick))
    rows = []
    for (k, attacker, victim), step in aggregate(
        frame, damages.attacker, damages.victim, damages, usable
    ).items():
        first = step.first
        a_pos = np.array([table[f"attacker{axis}_m"].iloc[first] for axis in "XYZ"])
        v_pos = np.array([table[f"victim{axis}_m"].iloc[first] for axis in "XYZ"])
        a_yaw = float(table["attackerViewX"].iloc[first])
        v_yaw = float(table["victimViewX"].iloc[first])
        if not np.isfinite([*a_pos, *v_pos]).all():
            stats.excluded["no attacker or victim position (x, y or z)"] += 1
            continue
        if not np.isfinite([a_yaw, v_yaw]).all():
            stats.excluded["no attacker or victim view angle"] += 1
            continue
        tick = float(damages.tick[first])
        armor, helmet = events.armor_of(victim)
        rows.append(
            {
                "attacker_position": a_pos,
                "victim_position": v_pos,
                "attacker_yaw": a_yaw,
                "victim_yaw": v_yaw,
                "attacker_hp": events.hp_before(attacker, tick),
                "victim_hp": events.hp_before(victim, tick),
                "attacker_weapon": str(damages.weapon[first]),
                "victim_armor": armor,
                "victim_helmet": helmet,
                "hit": True,
                "damage": step.damage,
                "hp_lost": step.hp_lost,
                "hit_group": step.group,
                "tick": int(tick) if per_hit else events.frame_tick(k),
            }
        )
    return rows


def _event_negatives(events: _EventRound, window: float) -> list[dict[str, object]]:
    """At the virtual frame of every damage, kill, flash and bomb event: the ordered enemy pairs
    of players seen within `window` ticks, alive, the attacker with a known firearm, and the
    attacker having dealt the victim no damage of any kind within the window."""
    round_, damages = events.round, events.damages
    sightings = _sightings(round_)
    tables = (round_.damages, round_.kills, round_.flashes, round_.bomb_events)
    ticks = np.concatenate([ints(t, "tick") for t in tables])
    ticks = ticks[np.isfinite(ticks)]
    any_damage = np.isfinite(damages.tick) & np.array(
        [
            a is not None and v is not None
            for a, v in zip(damages.attacker, damages.victim, strict=True)
        ],
        dtype=bool,
    )
    rows = []
    for k in np.unique(events.frame(ticks)):
        anchor = float(events.frame_tick(int(k)))
        seen: dict[object, int] = {}  # per player, its sighting nearest the anchor
        distance = np.abs(sightings.tick - anchor)
        for s in np.flatnonzero(distance <= window):
            best = seen.get(sightings.key[s])
            if best is None or distance[s] < distance[best]:
                seen[sightings.key[s]] = int(s)
        players = [p for p in seen if not events.dead_at(p, anchor)]
        near = any_damage & (np.abs(damages.tick - anchor) <= window)
        dealt = {(damages.attacker[r], damages.victim[r]) for r in np.flatnonzero(near)}
        for attacker in players:
            weapon = events.weapon_at(attacker, anchor)
            if weapon is None:
                continue
            sa = seen[attacker]
            for victim in players:
                sv = seen[victim]
                if sightings.side[sa] == sightings.side[sv] or (attacker, victim) in dealt:
                    continue
                armor, helmet = events.armor_of(victim)
                rows.append(
                    {
                        "attacker_position": sightings.position[sa],
                        "victim_position": sightings.position[sv],
                        "attacker_yaw": float(sightings.yaw[sa]),
                        "victim_yaw": float(sightings.yaw[sv]),
                        "attacker_hp": events.hp_before(attacker, anchor),
                        "victim_hp": events.hp_before(victim, anchor),
                        "attacker_weapon": weapon,
                        "victim_armor": armor,
                        "victim_helmet": helmet,
                        "hit": False,
                        "damage": 0.0,
                        "hp_lost": 0.0,
                        "hit_group": NO_HIT,
                        "tick": int(anchor),
                    }
                )
    return rows
