"""Where real players look, and how much the DIP leans on it.

    python benchmarks/studies/aim_study.py [--models rules]

1. On the round of both teams with the real view (`cs2_dust2_both/...-8hz-r02.json.xz`): how far
   the view is from the direction of motion (moving frames, over 0.5 s), and for every real
   kill how far the killer's view was from the victim, and the victim's from the killer, 2, 1,
   0.5 and 0 s before it. The replay's agents look along their motion until they aim. And
   for every kill whose pair is in sight (nav world, eye to eye) at the frame of the victim's
   first HP loss in the 3 s before it, or the frame before: when that run of frames in sight
   began, how long until the HP loss, and how far the killer's view was off the victim then:
   the time reality takes from sight to damage, against the replay's reaction time
   (`sim/combat.REACTION_S`, at a 0.5 s combat cadence).
2. On the real damage events (`esta_dust2_events`, `events_ancient`, as `decoy models evaluate`
   reads them): the share of damaging and other steps DIP says "hit" for, as recorded and with
   every victim's view turned 45, 90 and 180 degrees away (de_dust2's views are real;
   de_ancient's, filled by its export as facing each other, are redrawn by
   `decoy_cli/modeling/filled_views.py`).
3. The real hits' view deviations behind that redraw (de_dust2's events), and how the DIP scores
   de_dust2's real damaging steps with their real views and with views filled as facing.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from decoy_cli.damage import resolve_models
from decoy_cli.damage.model_folder import load_dip
from decoy_cli.esta import RoundFailure, collect_match_files, iter_rounds
from decoy_cli.geometry import eye_point
from decoy_cli.modeling.filled_views import QUANTILES, hit_view_deviations
from decoy_cli.modeling.network_evaluation import dip_probabilities
from decoy_cli.modeling.samples import build_samples
from decoy_cli.waypoints.build import builtin_graph, graph_world
from decoy_cli.world.physics import PhysicsWorld

DATA = Path(__file__).resolve().parents[3] / "shared" / "data"
ROUND_8HZ = DATA / "cs2_dust2_both" / "spirit-vs-falcons-m2-dust2-8hz-r02.json.xz"
BEFORE_S = (2.0, 1.0, 0.5, 0.0)
MOVING_M_S = 1.0


def _off(yaw: np.ndarray, frm: np.ndarray, to: np.ndarray) -> np.ndarray:
    """Degrees between a view yaw and the direction from `frm` to `to`, in [-180, 180)."""
    bearing = np.degrees(np.arctan2(to[..., 1] - frm[..., 1], to[..., 0] - frm[..., 0]))
    return (yaw - bearing + 180.0) % 360.0 - 180.0


def real_views() -> None:
    (round_,) = list(iter_rounds([ROUND_8HZ]))
    seconds, position, yaw = round_.frame_seconds, round_.position, round_.yaw
    back = max(1, round(0.5 / float(np.median(np.diff(seconds)))))
    moved = position[:, back:] - position[:, :-back]
    speed = np.hypot(moved[..., 0], moved[..., 1]) / (seconds[back:] - seconds[:-back])
    off = np.abs(_off(yaw[:, back:], position[:, :-back], position[:, back:]))
    moving = (speed >= MOVING_M_S) & np.isfinite(off)
    print(
        f"view against motion, {int(moving.sum())} moving player-frames: median "
        f"{np.median(off[moving]):.0f} deg, within 53 deg {np.mean(off[moving] <= 53):.3f}"
    )
    names = [p.name for p in round_.players]
    for kill in round_.kills.itertuples():
        a, v = names.index(kill.attackerName), names.index(kill.victimName)
        at = [int(np.searchsorted(seconds, kill.seconds - s)) - 1 for s in BEFORE_S]
        killer = [_off(yaw[a, f], position[a, f], position[v, f]) for f in at]
        victim = [_off(yaw[v, f], position[v, f], position[a, f]) for f in at]
        print(
            f"  {kill.seconds:6.1f} s {kill.attackerName} -> {kill.victimName}: killer's view off "
            f"the victim {[round(float(x)) for x in killer]}, victim's off the killer "
            f"{[round(float(x)) for x in victim]} deg at {BEFORE_S} s before"
        )


def sight_to_damage() -> None:
    (round_,) = list(iter_rounds([ROUND_8HZ]))
    seconds, position, yaw, hp = round_.frame_seconds, round_.position, round_.yaw, round_.hp
    names = [p.name for p in round_.players]
    with PhysicsWorld(graph_world(builtin_graph())) as world:
        for kill in round_.kills.itertuples():
            a, v = names.index(kill.attackerName), names.index(kill.victimName)
            sight = world.line_of_sight(eye_point(position[a]), eye_point(position[v]))
            lost = [
                f
                for f in range(1, len(seconds))
                if kill.seconds - 3.0 <= seconds[f] <= kill.seconds and hp[v, f] < hp[v, f - 1]
            ]
            at_kill = min(int(np.searchsorted(seconds, kill.seconds)), len(seconds) - 1)
            first = lost[0] if lost else at_kill
            end = first if sight[first] else first - 1
            if end < 0 or not sight[end]:
                print(f"  {kill.seconds:6.1f} s {kill.attackerName} -> {kill.victimName}: hidden")
                continue
            start = end
            while start > 0 and sight[start - 1]:
                start -= 1
            off = abs(float(_off(yaw[a, start], position[a, start], position[v, start])))
            print(
                f"  {kill.seconds:6.1f} s {kill.attackerName} -> {kill.victimName}: in sight "
                f"{seconds[first] - seconds[start]:.3f} s before the first HP lost, the killer's "
                f"view {off:.0f} deg off the victim at first sight"
            )


def dip_on_facing(models: str) -> None:
    samples, _ = build_samples([DATA / "esta_dust2_events", DATA / "events_ancient"])
    dip = load_dip(resolve_models(models))
    for where in sorted(set(samples.map_name.tolist())):
        for damaging in (True, False):
            part = samples.take(
                np.flatnonzero((samples.map_name == where) & (samples.hit == damaging))
            )
            shares = []
            for turn in (0, 45, 90, 180):
                turned = dataclasses.replace(part, victim_yaw=part.victim_yaw + turn)
                hit = dip_probabilities(dip, turned) >= dip.decision_threshold
                shares.append(f"{turn} deg {hit.mean():.3f}")
            label = "damaging" if damaging else "other"
            print(f"DIP says hit, {where} {label} ({len(part)}): " + ", ".join(shares))


def filled_views(models: str) -> None:
    """The real hits' view deviations behind `filled_views.py`'s tables, and how a DIP scores
    de_dust2's real damaging steps with their real views and with views filled as
    de_ancient's export fills them (facing each other exactly)."""
    files, _ = collect_match_files([DATA / "esta_dust2_events"])
    rounds = [r for r in iter_rounds(files) if not isinstance(r, RoundFailure)]
    found = [hit_view_deviations(r) for r in rounds]
    attacker = np.concatenate([a for a, _ in found])
    victim = np.concatenate([v for _, v in found])
    for name, values in (("attacker", attacker), ("victim", victim)):
        quantiles = np.round(np.quantile(values, QUANTILES), 1).tolist()
        print(f"{name} view minus facing, {len(values)} real hits, quantiles {quantiles}")
    samples, _ = build_samples([DATA / "esta_dust2_events"])
    hits = samples.take(np.flatnonzero(samples.hit))
    delta = hits.victim_position - hits.attacker_position
    facing = np.degrees(np.arctan2(delta[:, 1], delta[:, 0]))
    filled = dataclasses.replace(hits, attacker_yaw=facing, victim_yaw=facing + 180.0)
    dip = load_dip(resolve_models(models))
    for label, part in (("real views", hits), ("views filled facing", filled)):
        hit = dip_probabilities(dip, part) >= dip.decision_threshold
        print(f"DIP of {models} says hit on de_dust2's damaging steps, {label}: {hit.mean():.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", default="rules", help="a --models choice or a DIP folder")
    args = parser.parse_args()
    real_views()
    sight_to_damage()
    dip_on_facing(args.models)
    filled_views(args.models)


if __name__ == "__main__":
    main()
