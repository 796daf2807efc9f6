"""One way to set up a simulated round: what it is played with, and the bodies it needs.

`RoundSetup` (keyword-only) names everything that decides how a round is simulated: the
waypoint graph, the mover, shooting (`combat` and the damage model), the bomb rules, the combat
cadence. `open_round` is the one place that turns it into a ready `Simulator`: it opens a
pybullet client only when the round needs one (the physics mover, or line of sight for
shooting) unless the caller lends one, builds the mover, the rules, line of sight and the combat
step, and on exit releases exactly what it built. The PettingZoo environment, the replay of a
real round, the synthetic sample and the speed benchmark all start their rounds here, so a
switch means the same in each.

`combat` and `bomb` are independent: shooting happens when `combat` is on and there is a damage
model; the bomb (carrier, plant, defuse, detonation) acts when `bomb` is on. The paper's
movement-only evaluation is both off.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, ExitStack, contextmanager
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Literal, get_args

from decoy_cli.csgo import TICK_RATE
from decoy_cli.errors import DecoyError
from decoy_cli.sim.combat import CombatStep, DamageModel, LineOfSight
from decoy_cli.sim.engine import COMBAT_EVERY_TICKS, Policy, Simulator
from decoy_cli.sim.movement import KinematicMover, PhysicsMover
from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.rules import BombRules, RulesConfig, SiteZones
from decoy_cli.sim.state import Agents
from decoy_cli.sim.utility import Utility
from decoy_cli.waypoints.graph import WaypointGraph

if TYPE_CHECKING:
    from decoy_cli.world.occlusion import OcclusionScene
    from decoy_cli.world.physics import PhysicsWorld
    from decoy_cli.world.world import World

MoverName = Literal["kinematic", "physics"]
"""The movers: "kinematic" (compiled motion along the edges, agents pass through each other)
and "physics" (pybullet capsules that block each other)."""
MOVERS: tuple[MoverName, ...] = get_args(MoverName)


SIGHT_WITHOUT_SHOOTING = (
    "a sight mesh is where line of sight is tested for shooting: it needs combat and a damage "
    "model (not --no-combat or --models none)"
)


class SetupError(DecoyError, ValueError):
    """A round setup that cannot be played (an unknown mover, a combat cadence below one tick)."""


@dataclass(frozen=True, kw_only=True)
class Switches:
    """The switches of a simulated round, one meaning from the command line to the simulator:
    the mover, shooting (`combat`), the bomb rules. `RoundSetup` and every run's options
    (`RunSpec` and what extends it) are made of them; an unknown mover is refused here, once.
    The default mover is the one measured more faithful on real rounds (the README gives the
    numbers)."""

    mover: MoverName = "kinematic"
    combat: bool = True
    bomb: bool = True

    def __post_init__(self) -> None:
        if self.mover not in MOVERS:
            raise SetupError(f"unknown mover {self.mover!r} (use {' or '.join(MOVERS)})")


@dataclass(frozen=True, kw_only=True)
class RunSpec(Switches):
    """A run's switches and its seed: what the replay (`ReplayOptions`), the evaluation
    (`EvalSettings`) and the benchmark (`BenchConfig`) share."""

    seed: int = 0


@dataclass(frozen=True, kw_only=True)
class RoundSetup(Switches):
    """How rounds are simulated (see the module docstring).

    `world` is the geometry for pybullet (None: the nav world the graph was built on); it is used
    only when a client is opened here, not when the caller lends one. `rules` overrides the
    rules' durations and ranges (its `bomb_enabled` is replaced by `bomb`); `zones` the bomb
    sites (None: `SiteZones.from_graph`, the map's measured bomb-target boxes where known).
    """

    graph: WaypointGraph
    damage_model: DamageModel | None = None
    combat_every_ticks: int = COMBAT_EVERY_TICKS
    kills: bool = True
    """False: neither shooting nor a fall kills (HP stops at 1): deaths come from elsewhere, as
    in a replay whose deaths follow the data (`--deaths data`, the paper's protocol)."""
    world: World | None = None
    sight: OcclusionScene | None = None
    """Geometry line of sight is tested in (a map's own geometry, `read_sight_scene`); None:
    the pybullet client's world."""
    rules: RulesConfig | None = None
    zones: SiteZones | None = None
    utility: Utility | None = None
    """The data's smokes, fires and blinds the fight heeds (decoy_cli/sim/utility.py)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.combat_every_ticks < 1:
            raise SetupError(f"combat_every_ticks must be >= 1, got {self.combat_every_ticks}")

    @property
    def map_name(self) -> str:
        """The map of the graph ("" when the graph does not say)."""
        return str(self.graph.meta.get("map", ""))

    @property
    def shooting(self) -> bool:
        """Whether agents shoot: combat on and a damage model to decide the hits."""
        return self.combat and self.damage_model is not None

    @property
    def needs_physics(self) -> bool:
        """Whether a round needs a pybullet client: the physics mover or line of sight."""
        return self.mover == "physics" or self.shooting

    def rules_config(self) -> RulesConfig:
        """The rules' configuration with this setup's bomb switch."""
        base = self.rules if self.rules is not None else RulesConfig()
        if base.bomb_enabled == self.bomb:
            return base
        return replace(base, bomb_enabled=self.bomb)

    def site_zones(self) -> SiteZones:
        """The bomb-site zones of this setup's rounds."""
        return self.zones if self.zones is not None else SiteZones.from_graph(self.graph)

    def open_physics(self) -> PhysicsWorld:
        """A new pybullet client holding this setup's world (the caller closes it)."""
        from decoy_cli.waypoints.build import graph_world
        from decoy_cli.world.physics import PhysicsWorld

        return PhysicsWorld(self.world if self.world is not None else graph_world(self.graph))


OpenRound = Callable[..., AbstractContextManager[Simulator]]
"""The type of `open_round`: what a caller may inject in its place (a test, a recorder)."""


@contextmanager
def open_round(
    setup: RoundSetup,
    agents: Agents,
    policy: Policy,
    *,
    physics: PhysicsWorld | None = None,
    bomb_carrier: int = -1,
    start_tick: int = 0,
    record_ticks: Sequence[int] = (),
    seed: int | None = None,
) -> Iterator[Simulator]:
    """A ready `Simulator` for one round of `agents` driven by `policy`.

    `physics` lends a pybullet client (kept open); without it one is opened when the round
    needs it and closed on exit. The mover's and line of sight's bodies are always removed on
    exit, so a lent client serves many rounds.
    """
    with ExitStack() as stack:
        if setup.needs_physics and physics is None:
            physics = setup.open_physics()
            stack.callback(physics.close)
        mover: MoverBase
        if setup.mover == "physics":
            assert physics is not None
            physical = PhysicsMover(physics)
            stack.callback(physical.close)
            mover = physical
        else:
            mover = KinematicMover()
        combat = None
        if setup.shooting:
            assert physics is not None and setup.damage_model is not None
            los = LineOfSight(physics, agents.count, scene=setup.sight)
            stack.callback(los.close)
            combat = CombatStep(
                los,
                setup.damage_model,
                setup.map_name,
                kills=setup.kills,
                utility=setup.utility,
                step_s=setup.combat_every_ticks / TICK_RATE,
            )
        rules = BombRules(setup.site_zones(), setup.rules_config())
        yield Simulator(
            setup.graph,
            agents,
            mover,
            policy,
            rules,
            bomb_carrier=bomb_carrier if setup.bomb else -1,
            combat=combat,
            combat_every_ticks=setup.combat_every_ticks,
            kills=setup.kills,
            start_tick=start_tick,
            record_ticks=record_ticks,
            seed=seed,
        )
