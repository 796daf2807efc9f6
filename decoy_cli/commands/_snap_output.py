"""The tables `decoy snap` prints: a round's players, a batch's totals, the worst intervals,
infeasible places, metrics and actions (the command parses; this module only formats)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from rich.console import Console
from rich.table import Table
from rich.text import Text

from decoy_cli.esta import Round
from decoy_cli.metrics import GROUPS, METRIC_NAMES, METRIC_NAMES_CLOCK
from decoy_cli.replay import ACTION_NAMES, PlayerPlan
from decoy_cli.replay.snapping import WITHIN_M
from decoy_cli.replay.study import (
    SEVERE_RATIO,
    RoundStudy,
    SnapStudy,
    SnapTotals,
    worst_intervals,
)
from decoy_cli.text import shortened
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph

_WITHIN = f"within_{WITHIN_M:g}m"


def show_round(
    console: Console, round_: Round, study: RoundStudy, graph: WaypointGraph, worst: int
) -> None:
    """The per-player table with a totals row, then the worst intervals."""
    seconds = round_.frame_seconds
    span = f"{seconds[0]:.1f}-{seconds[-1]:.1f} s" if round_.num_frames else "no frames"
    console.print(
        f"{round_.match_id} round {round_.round_num}: {round_.num_frames} frames ({span}), "
        f"{round_.num_players} players; graph {graph.num_nodes:,} waypoints, "
        f"{graph.num_edges:,} edges",
        highlight=False,
    )
    if not round_.num_players:
        console.print("no player appears in any frame: nothing to snap")
        return
    table = Table()
    for column in (
        "player",
        "side",
        "alive",
        "snap med m",
        "p95 m",
        "max m",
        f"≤{WITHIN_M:g} m",
        "no wp",
        "ivals",
        "too fast",
        "worst",
        "gaps",
        "path m",
        "died s",
    ):
        table.add_column(
            column, justify="left" if column in ("player", "side") else "right", overflow="fold"
        )
    for values in study.rows.to_dict("records"):
        table.add_row(
            shortened(str(values["player"])),
            str(values["side"]),
            str(values["frames_alive"]),
            _num(values["snap_median_m"]),
            _num(values["snap_p95_m"]),
            _num(values["snap_max_m"]),
            _share(values[_WITHIN]),
            str(values["unsnappable"]),
            str(values["intervals"]),
            str(values["infeasible"]),
            _num(values["worst_ratio"], 2),
            str(values["unreachable"]),
            _num(values["path_length_m"], 1),
            _num(values["died_s"], 1),
        )
    totals = study.totals
    table.add_section()
    table.add_row(
        "all",
        "",
        str(int(study.rows["frames_alive"].sum())),
        _num(totals.snap_median_m),
        _num(totals.snap_p95_m),
        _num(float(study.rows["snap_max_m"].max())),
        _share(totals.within),
        str(totals.unsnappable),
        str(totals.intervals),
        f"{totals.infeasible} ({_share(totals.infeasible_share)})",
        _num(totals.worst_ratio, 2),
        str(totals.unreachable),
        _num(float(study.rows["path_length_m"].sum()), 1),
        "",
    )
    console.print(table)
    console.print(
        "no wp: alive frames without a waypoint on their floor within the snap distance; "
        "ivals: frame intervals; too fast: intervals needing more than the player's maximum "
        "speed; worst: largest required / maximum speed ratio; gaps: unreachable intervals",
        highlight=False,
        style="dim",
    )
    if worst:
        show_worst(console, worst_intervals(study.intervals, worst))


def totals_table(totals: SnapTotals, title: str) -> Table:
    """The aggregate snap and feasibility figures of a batch."""
    table = Table(title=title)
    table.add_column("measure")
    table.add_column("value", justify="right")
    rows = [
        ("rounds snapped", f"{totals.rounds:,}"),
        ("player-rounds", f"{totals.player_rounds:,}"),
        ("alive frames with a position", f"{totals.frames_with_position:,}"),
        ("snap error median (m)", _num(totals.snap_median_m)),
        ("snap error p95 (m)", _num(totals.snap_p95_m)),
        (f"snapped within {WITHIN_M:g} m", _share(totals.within)),
        ("unsnappable frames (no waypoint on their floor)", f"{totals.unsnappable:,}"),
        ("frames in the air or on a ladder (not snapped)", f"{totals.airborne:,}"),
        ("frame intervals", f"{totals.intervals:,}"),
        (
            "intervals needing more than max speed",
            f"{totals.infeasible:,} ({_share(totals.infeasible_share)})",
        ),
        ("unreachable intervals (gap in the graph)", f"{totals.unreachable:,}"),
        ("worst speed ratio", _num(totals.worst_ratio, 2)),
    ]
    for name, value in rows:
        table.add_row(name, value)
    return table


def show_worst(console: Console, worst: pd.DataFrame, *, with_match: bool = False) -> None:
    """The intervals with the largest required / maximum speed ratio and what explains them."""
    if not len(worst):
        return
    table = Table(
        title="worst intervals: path = planned path, straight = original positions' distance"
    )
    columns = [
        *(["match"] if with_match else []),
        "round",
        "player",
        "frames",
        "s",
        "path m",
        "detour",
        "straight m",
        "orig m/s",
        "max m/s",
        "ratio",
        "dz m",
        "places",
    ]
    for column in columns:
        table.add_column(
            column,
            justify="left" if column in ("match", "player", "places") else "right",
            overflow="fold",
        )
    for row in worst.itertuples(index=False):
        places = (
            row.from_place
            if row.from_place == row.to_place
            else (f"{row.from_place or '?'} → {row.to_place or '?'}")
        )
        cells = [
            *([str(row.match)[:8]] if with_match else []),
            str(row.round),
            shortened(str(row.player)),
            f"{row.start_frame}→{row.end_frame}",
            _num(row.seconds, 2),
            _num(row.length_m, 1),
            "gap" if row.unreachable else _num(row.detour, 1),
            _num(row.original_straight_m, 2),
            _num(row.original_m_s, 2),
            _num(row.max_m_s, 2),
            _num(row.ratio, 2),
            _num(row.original_dz_m, 2),
            places or "",
        ]
        table.add_row(*cells)
    console.print(table)


def show_places(console: Console, places: pd.DataFrame) -> None:
    """The place pairs with the most too-fast intervals (a large detour: a missing edge)."""
    if not len(places):
        return
    table = Table(title="where the intervals needing more than max speed are (nav places)")
    for column in (
        "from",
        "to",
        "intervals",
        "share",
        f"ratio > {SEVERE_RATIO:g}",
        "median ratio",
        "worst",
        "median detour",
    ):
        table.add_column(column, justify="left" if column in ("from", "to") else "right")
    for row in places.itertuples(index=False):
        table.add_row(
            row.from_place or "?",
            row.to_place or "?",
            f"{row.intervals:,}",
            _share(row.share),
            f"{row.severe:,}",
            _num(row.median_ratio, 2),
            _num(row.worst_ratio, 2),
            _num(row.median_detour, 2),
        )
    console.print(table)


def show_round_metrics(console: Console, rows: pd.DataFrame) -> None:
    """Metric rows by player columns: snapped-waypoint trajectory against the original."""
    table = Table(title="fidelity of the snapped-waypoint trajectory (m)")
    table.add_column("protocol")
    table.add_column("metric")
    for player in rows["player"]:
        table.add_column(str(player), justify="right")
    for metric in METRIC_NAMES:
        table.add_row(
            _protocol(metric), metric, *(_num(v) for v in rows[metric].to_numpy(np.float64))
        )
    console.print(table)
    for row in rows.itertuples(index=False):
        if isinstance(row.reason, str):
            console.print(f"{row.player}: not evaluated ({row.reason})", highlight=False)


def show_summary(console: Console, study: SnapStudy) -> None:
    """Mean, std, median and p90 of every metric, by side and overall."""
    summary = study.metrics
    if summary is None:
        return
    groups = [g for g in GROUPS if summary.n_rows[g]]
    if not groups:
        return
    table = Table(
        title="fidelity of the snapped-waypoint trajectory (m): a first bound on a perfect "
        "replay on this graph"
    )
    table.add_column("protocol")
    table.add_column("metric")
    for group in groups:
        for stat in ("mean", "std", "median", "p90"):
            table.add_column(f"{group} {stat}", justify="right")
    stats = summary.table.set_index(["group", "metric"])
    for metric in METRIC_NAMES:
        cells = [
            _num(stats.loc[(group, metric), stat])
            for group in groups
            for stat in ("mean", "std", "median", "p90")
        ]
        table.add_row(_protocol(metric), metric, *cells)
    console.print(table)
    counts = ", ".join(f"{g}: {summary.n_evaluated[g]:,} of {summary.n_rows[g]:,}" for g in groups)
    console.print(f"player-rounds evaluated: {counts}", highlight=False)
    for row in summary.unevaluated.itertuples(index=False):
        console.print(f"  {row.group}: {row.count} not evaluated ({row.reason})", highlight=False)


def show_actions(
    console: Console, round_: Round, study: RoundStudy, chosen: list[int], limit: int
) -> None:
    """The first `limit` actions of each chosen player's plan, runs of one move grouped."""
    for p in chosen:
        plan = study.plan.plans[p]
        total = len(plan.action)
        console.print(
            Text.assemble(
                (round_.players[p].name, "bold"),
                f" ({total:,} actions, {plan.stop_seconds:.1f} s of STOP): "
                f"{_format_actions(plan, limit)}" + (" …" if total > limit else ""),
            ),
            highlight=False,
        )


def _format_actions(plan: PlayerPlan, limit: int) -> str:
    """'N×3 NE STOP×2 1.00s RELOCATE→4711': runs of one action grouped, STOPs with their time."""
    parts: list[str] = []
    actions = plan.action[:limit]
    i = 0
    while i < len(actions):
        code = int(actions[i])
        if code > STOP_ACTION:
            parts.append(f"{ACTION_NAMES[code]}→{plan.action_node[i]}")
            i += 1
            continue
        run = 1
        while i + run < len(actions) and actions[i + run] == code:
            run += 1
        text = ACTION_NAMES[code] + (f"×{run}" if run > 1 else "")
        if code == STOP_ACTION:
            text += f" {plan.action_duration_s[i : i + run].sum():.2f}s"
        parts.append(text)
        i += run
    return " ".join(parts) if parts else "(no actions)"


def _protocol(metric: str) -> str:
    return "clock" if metric in METRIC_NAMES_CLOCK else "paper"


def _num(value: float, digits: int = 3) -> str:
    """A number with fixed digits; '-' for NaN."""
    value = float(value)
    return "-" if math.isnan(value) else f"{value:.{digits}f}"


def _share(value: float) -> str:
    """A share as a percentage; '-' for NaN."""
    value = float(value)
    return "-" if math.isnan(value) else f"{value:.1%}"
