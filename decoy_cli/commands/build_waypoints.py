"""`decoy build-waypoints`: build the waypoint graph of the built-in map or of a user's mesh."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table

from decoy_cli.commands._console import make_console
from decoy_cli.commands._groups import with_groups
from decoy_cli.commands._options import MAPS_HELP
from decoy_cli.errors import GraphError
from decoy_cli.esta import collect_match_files
from decoy_cli.files import check_writable
from decoy_cli.waypoints import patch_check
from decoy_cli.waypoints.build import build_graph, canonical_map, read_manual_waypoints
from decoy_cli.waypoints.coverage import NavCoverage, nav_coverage
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.lattice import LatticeParams, LatticeResult
from decoy_cli.waypoints.plot import plot_graph
from decoy_cli.waypoints.quality import SnapQuality, alignment_quality, check_aligned
from decoy_cli.world import patch_learning
from decoy_cli.world.cs2_world import cs2_world
from decoy_cli.world.meshfile import check_extent, read_mesh
from decoy_cli.world.nav_climbs import world_climbs
from decoy_cli.world.navmesh import load_navmesh, nav_world
from decoy_cli.world.world import World

DEFAULT_OUT = Path("decoy-out") / "waypoints"


def _parse_point(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not np.all(np.isfinite(values)):
        raise GraphError(f"{option} wants three numbers x,y,z in metres, got {text!r}")
    return values


@dataclass(frozen=True)
class UserMesh:
    """A user's mesh to build on instead of the built-in nav world, and how to read it."""

    mesh: Annotated[
        Path | None,
        typer.Option(
            "--mesh",
            help="A user mesh (.obj, awpy .tri or awpy 3 .mesh) instead of the built-in nav world.",
        ),
    ] = None
    units: Annotated[Literal["hammer", "m"], typer.Option("--units", help="Mesh units.")] = "hammer"
    scale: Annotated[
        float | None, typer.Option("--scale", help="Metres per mesh unit (overrides --units).")
    ] = None
    up_axis: Annotated[
        str, typer.Option("--up-axis", help="Mesh axis that points up: z, y, -y, ...")
    ] = "z"
    offset: Annotated[
        str, typer.Option("--offset", help="Added to the mesh after scaling (m).")
    ] = "0,0,0"

    def read(self) -> World:
        """The mesh as a world in metres, refused when larger than a map."""
        if self.mesh is None:
            raise GraphError("no --mesh to read")
        offset = _parse_point(self.offset, "--offset")
        world = read_mesh(
            self.mesh, units=self.units, scale=self.scale, up_axis=self.up_axis, offset=offset
        )
        check_extent(world)
        return world


@with_groups
def build_waypoints(
    map_name: str = typer.Option(
        "dust2", "--map", help=f"Map whose places and spawns to use: {MAPS_HELP}."
    ),
    user_mesh: UserMesh = UserMesh(),
    nav_file: Path | None = typer.Option(
        None,
        "--nav",
        help="A CS2 nav mesh of the map (awpy's JSON form, plain, .xz or .gz; or a binary .nav "
        "with awpy 3 installed): build the world from it; the graph carries that world.",
    ),
    spacing: float = typer.Option(0.7, "--spacing", help="Lattice spacing in metres.", min=0.2),
    wall_nodes: bool = typer.Option(
        True,
        "--wall-nodes/--no-wall-nodes",
        help="Add nodes half a spacing toward walls, where players stand (--no-wall-nodes: the "
        "paper's pure lattice).",
    ),
    seeds: list[str] = typer.Option(
        [], "--seed", help="A seed point x,y,z in metres (repeatable; default: both spawns)."
    ),
    manual: Path | None = typer.Option(
        None, "--manual", help="CSV of manual waypoints (header x,y,z; metres)."
    ),
    out: Path | None = typer.Option(
        None, "--out", help="Graph file to write (default decoy-out/waypoints/<name>.npz)."
    ),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Write a PNG beside the graph."),
    check_esta: Path | None = typer.Option(
        None,
        "--check-esta",
        help="ESTA file or folder: report how its player positions snap to the new graph.",
    ),
    min_aligned: float = typer.Option(
        0.5,
        "--min-aligned",
        help="With --check-esta: fail when fewer positions than this share snap within 0.5 m.",
    ),
    learn_patches: Path | None = typer.Option(
        None,
        "--learn-patches",
        help="ESTA file or folder: learn floor patches from where its players stand, write them "
        "(--patches-out) and build on the nav world with them instead of the shipped ones.",
    ),
    patches_out: Path | None = typer.Option(
        None, "--patches-out", help="Learned patches file (default: beside the graph)."
    ),
    min_matches: int = typer.Option(
        patch_learning.MIN_MATCHES,
        "--min-matches",
        min=1,
        help="Fewest matches a learned patch needs.",
    ),
) -> None:
    """Build a waypoint graph: BFS lattice, drop pass, verification, pruning, manual points."""
    console = make_console()
    map_id = canonical_map(map_name)
    if learn_patches is not None and (user_mesh.mesh is not None or nav_file is not None):
        raise GraphError("--learn-patches learns on the built-in nav world; leave out --mesh/--nav")
    if user_mesh.mesh is not None and nav_file is not None:
        raise GraphError("--mesh and --nav each give the world: give one")
    if nav_file is not None:
        world = cs2_world(nav_file, map_id)
        name = f"{map_id}.cs2"
        if world.meta.get("ladder_links"):
            console.print(
                f"warning: the nav names {world.meta['ladder_links']} ladder links but no ladder "
                "positions: the world has no ladders to climb",
                style="yellow",
            )
    elif user_mesh.mesh is None:
        world = nav_world(map_id)
        name = map_id
    else:
        world = user_mesh.read()
        name = user_mesh.mesh.name.split(".")[0]
    seed_points = np.array([_parse_point(s, "--seed") for s in seeds]) if seeds else None
    manual_points = read_manual_waypoints(manual) if manual is not None else None
    out = out or DEFAULT_OUT / f"{name}.npz"
    check_writable(out)  # before the build's minutes
    if check_esta is not None:
        collect_match_files([check_esta])  # a missing or empty input fails now, not after
    params = LatticeParams(spacing=spacing, wall_nodes=wall_nodes)
    built: tuple[WaypointGraph, LatticeResult] | None = None
    if learn_patches is not None:
        patches_out = patches_out or out.with_suffix(".patches.csv")
        check_writable(patches_out)
        files, _ = collect_match_files([learn_patches])
        with console.status("learning patches, then building graphs without and with them"):
            learned = patch_check.learn_checked_patches(
                files, map_id, seed_points, params, manual_points, min_matches
            )
        _show_learned(console, learned, len(files))
        patch_learning.write_patches(patches_out, learned.kept)
        console.print(f"{_count(learned.kept)} written to {patches_out}", highlight=False)
        world, built = nav_world(map_id, tuple(b.box for b in learned.kept)), learned.built

    started = time.perf_counter()
    if built is not None:
        console.print("the graph is the one the patch check built", highlight=False)
    with Progress(
        TextColumn("{task.description:<14}"),
        BarColumn(),
        TextColumn("{task.fields[info]}"),
        TimeElapsedColumn(),
        console=console,
        transient=False,
    ) as progress:
        tasks: dict[str, TaskID] = {}

        def report(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = progress.add_task(stage, total=total or None, info="")
            info = f"{done:,} nodes" if not total else f"{done:,}/{total:,} capsule steps"
            progress.update(tasks[stage], completed=done, total=total or None, info=info)

        graph, result = built or build_graph(
            world, map_id, seed_points, params, manual_points, report
        )
        for task in tasks.values():
            progress.update(task, total=progress.tasks[task].completed or 1)
    graph.save(out)
    stats = result.stats
    elapsed = time.perf_counter() - started + (sum(stats.seconds.values()) if built else 0.0)

    table = Table(title=f"waypoints of {world.source}")
    table.add_column("stage")
    table.add_column("result", justify="right")
    table.add_column("seconds", justify="right")
    table.add_row(
        "lattice (BFS)",
        f"{stats.lattice_nodes:,} nodes; "
        + ", ".join(f"{k} {v:,}" for k, v in stats.lattice_edges.items() if k != "drop"),
        f"{stats.seconds['lattice']:.1f}",
    )
    table.add_row(
        "drop pass",
        f"{stats.drop_edges:,} drop edges, {stats.drop_new_nodes:,} new nodes",
        f"{stats.seconds['drop pass']:.1f}",
    )
    if "wall nodes" in stats.seconds:
        table.add_row(
            "wall nodes",
            f"{stats.wall_nodes:,} nodes added",
            f"{stats.seconds['wall nodes']:.1f}",
        )
    table.add_row(
        "verification",
        f"{stats.nudged_nodes:,} nodes nudged; removed "
        + ", ".join(f"{k} {v:,}" for k, v in stats.verified_removed.items()),
        f"{stats.seconds['verification']:.1f}",
    )
    table.add_row(
        "pruning",
        f"{stats.components_before:,} components -> 1; largest held "
        f"{stats.largest_component_share:.1%}; {stats.pruned_nodes:,} nodes pruned",
        f"{stats.seconds['pruning']:.1f}",
    )
    if manual_points is not None:
        table.add_row(
            "manual", f"{stats.manual_added} added, {stats.manual_dropped} unlinkable", ""
        )
    climbs = world_climbs(world)
    if climbs is not None:
        joined = f"{result.climbs_joined:,} of the nav's {len(climbs):,} joined"
        table.add_row("climbs", joined, "")
    table.add_row(
        "graph",
        f"{stats.nodes:,} nodes, {sum(stats.edges.values()):,} edges: "
        + ", ".join(f"{k} {v:,}" for k, v in stats.edges.items()),
        f"{elapsed:.1f}",
    )
    console.print(table)
    regions = ", ".join(f"{name} {len(nodes):,}" for name, nodes in graph.regions.items())
    console.print(f"region waypoints: {regions}", highlight=False)
    if user_mesh.mesh is None and nav_file is None:
        _show_coverage(console, nav_coverage(graph, load_navmesh(map_id)))
    console.print(f"graph written to {out}")
    if plot:
        png = out.with_suffix(".png")
        plot_graph(
            graph,
            png,
            nav=None if nav_file is not None else load_navmesh(map_id),
            removed_segments=result.removed_segments,
            pruned_positions=result.pruned_positions,
            title=f"{graph.num_nodes:,} waypoints, {graph.num_edges:,} edges ({world.source})",
        )
        console.print(f"plot written to {png}")
    if check_esta is not None:
        quality = alignment_quality(graph, result.pruned_positions, world, check_esta)
        _show_alignment(console, quality, check_esta)
        check_aligned(quality, min_aligned)


def _count(boxes: tuple[patch_learning.PatchBox, ...]) -> str:
    return f"{len({b.patch for b in boxes})} patches ({len(boxes)} boxes)"


def _show_learned(console: Console, learned: patch_check.LearnedPatches, files: int) -> None:
    console.print(
        f"learned {_count(learned.candidates)} from {learned.standing_positions:,} standing "
        f"positions in {files} matches",
        highlight=False,
    )
    if learned.check is None:
        return
    check = learned.check
    left_out = [v for v in check.verdicts if not v.kept]
    console.print(
        f"checked on {check.pairs:,} real consecutive-frame paths: {check.lengthened_pairs:,} "
        f"lengthened; {len(left_out)} patches left out",
        highlight=False,
    )
    if not left_out:
        return
    table = Table(title="left out: they lengthen more real paths than they give")
    table.add_column("patch", justify="right")
    table.add_column("paths lengthened", justify="right")
    table.add_column("in matches", justify="right")
    table.add_column("positions gained", justify="right")
    table.add_column("paths shortened", justify="right")
    for verdict in left_out:
        table.add_row(
            str(verdict.patch),
            f"{verdict.lengthened:,}",
            str(verdict.lengthened_matches),
            f"{verdict.gained:,}",
            f"{verdict.shortened:,}",
        )
    console.print(table)


def _show_coverage(console: Console, coverage: NavCoverage) -> None:
    worst = ", ".join(
        f"{place or '(unnamed)'} {share:.0%}" for place, share in coverage.worst_places()
    )
    console.print(
        f"nav coverage: {coverage.covered:.2%} of the nav mesh's {coverage.area_m2:,.0f} m² "
        f"within 0.5 m of a waypoint; least covered places: {worst}",
        highlight=False,
    )


def _show_alignment(console: Console, quality: SnapQuality, path: Path) -> None:
    table = Table(title=f"alignment: {quality.positions:,} alive positions of {path}")
    table.add_column("distance to waypoint")
    table.add_column("median (m)", justify="right")
    table.add_column("p95 (m)", justify="right")
    table.add_column("within 0.5 m", justify="right")
    table.add_row(
        "3-D", f"{quality.median_3d:.3f}", f"{quality.p95_3d:.3f}", f"{quality.within_3d:.2%}"
    )
    if quality.grounded_within_3d is not None and quality.airborne is not None:
        table.add_row(
            f"3-D, on the ground ({quality.positions - quality.airborne:,})",
            "",
            "",
            f"{quality.grounded_within_3d:.2%}",
        )
    table.add_row(
        "horizontal",
        f"{quality.median_horizontal:.3f}",
        f"{quality.p95_horizontal:.3f}",
        f"{quality.within_horizontal:.2%}",
    )
    console.print(table)
    console.print(
        f"no waypoint on their floor: {quality.unsnapped:,}; "
        f"nearest lattice node was pruned: {quality.on_pruned:.2%}"
    )
