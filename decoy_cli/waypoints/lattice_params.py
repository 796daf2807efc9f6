"""What the lattice builder is asked (`LatticeParams`) and what it reports (`BuildStats`,
`LatticeResult`); decoy_cli/waypoints/lattice.py builds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np

from decoy_cli.csgo import (
    JUMP_HEIGHT_M,
    MAX_DROP_M,
    PLAYER_HEIGHT_M,
    PLAYER_RADIUS_M,
    STEP_HEIGHT_M,
)

Progress = Callable[[str, int, int], None]
"""progress(stage, done, total): called as work advances; the CLI turns it into a bar."""


@dataclass(frozen=True)
class LatticeParams:
    """Everything that shapes the lattice; stored in the graph file's metadata."""

    spacing: float = 0.7
    step_height: float = STEP_HEIGHT_M
    jump_height: float = JUMP_HEIGHT_M
    max_drop: float = MAX_DROP_M
    agent_radius: float = 0.8 * PLAYER_RADIUS_M  # see the module docstring
    agent_height: float = PLAYER_HEIGHT_M
    min_floor_normal_z: float = 0.7  # CS:GO: surfaces steeper than ~45 degrees are not floors
    profile_samples: int = 8
    ledge_threshold: float = 0.12  # a profile jump above this is a ledge, below it a ramp
    same_floor_dz: float = 0.6  # two lattice hits closer than this in height are one node
    verify_step: float = 0.1
    verify_clearance: float = 0.03  # capsule floats this much above the step height
    max_nudge: float = 0.3  # a node the capsule does not fit at moves up to this far to fit
    graze: float = 0.025  # penetration the capsule may have (the walls are approximate)
    wall_nodes: bool = True  # add nodes half a spacing toward walls (see the module docstring)


@dataclass
class BuildStats:
    """What the build did, stage by stage (the CLI prints it, the graph file stores it)."""

    seeds: int = 0
    ladders: int = 0
    ladder_seeds: int = 0
    ladders_joined: int = 0
    lattice_nodes: int = 0
    lattice_edges: dict[str, int] = field(default_factory=dict)
    drop_edges: int = 0
    drop_new_nodes: int = 0
    wall_nodes: int = 0
    nudged_nodes: int = 0
    verified_removed: dict[str, int] = field(default_factory=dict)
    components_before: int = 0
    largest_component_share: float = 0.0
    components_after: int = 0
    pruned_nodes: int = 0
    manual_added: int = 0
    manual_dropped: int = 0
    nodes: int = 0
    edges: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class LatticeResult:
    """Nodes and edges after all stages, plus what was removed (for plots and reports)."""

    positions: np.ndarray
    edge_source: np.ndarray
    edge_target: np.ndarray
    edge_kind: np.ndarray
    edge_direction: np.ndarray
    removed_segments: np.ndarray  # (R, 2, 3) start and end of edges removed by verification
    removed_kinds: np.ndarray  # (R,) EdgeKind of each removed edge
    pruned_positions: np.ndarray  # (Q, 3) nodes dropped by the component pruning
    stats: BuildStats
    climbs_joined: int = 0
    """Climbs of the world given their own edge (`climbs.py`)."""
