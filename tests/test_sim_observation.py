"""The compiled observation encoder, as the environment's steps run it (`RoundSteps.state`),
against a plain numpy statement of the layout (`DecoyParallelEnv` documents every entry), on
states of played rounds: bomb carried, dropped and planted, agents dead, plants and defuses
under way."""

from __future__ import annotations

import numpy as np
from busy_rounds import Shots, Wanderers, site_agents

from decoy_cli.env.observation import BOMB_SITES, NUM_ACTIONS, ObservationEncoder
from decoy_cli.env.step import RoundSteps
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.quiet_play import Choices
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.state import BombStatus
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import STOP_ACTION


def reference(encoder: ObservationEncoder, sim: Simulator, due: np.ndarray) -> np.ndarray:
    """The observation vectors, entry by entry, in numpy."""
    agents, bomb, cfg, layout = sim.agents, sim.bomb, encoder.rules, encoder.layout
    n, pos = agents.count, agents.position
    centre, half = encoder._centre, encoder._half
    obs = np.zeros((n, encoder.size))
    obs[:, layout["position"]] = np.clip((pos - centre) / half, -1.0, 1.0)
    yaw = np.radians(agents.yaw)
    obs[:, layout["yaw"]] = np.stack([np.sin(yaw), np.cos(yaw)], axis=1)
    obs[:, layout["hp"].start] = agents.hp / 100.0
    obs[:, layout["armor"].start] = agents.armor / 100.0
    obs[:, layout["helmet"].start] = agents.helmet
    obs[:, layout["defuse_kit"].start] = agents.has_defuser
    carried = encoder.bomb and bomb.status == BombStatus.CARRIED and bomb.carrier >= 0
    if carried:
        obs[bomb.carrier, layout["has_bomb"].start] = 1.0
    obs[:, layout["is_ct"].start] = agents.side == "CT"
    obs[:, layout["needs_decision"].start] = due
    for name, table in (("teammates", encoder._mates), ("enemies", encoder._enemies)):
        idx = np.maximum(table, 0)
        valid = (table >= 0) & agents.alive[idx]
        offset = np.clip((pos[idx] - pos[:, None, :]) / (2 * half), -1.0, 1.0)
        features = np.concatenate(
            [np.ones((*idx.shape, 1)), offset, (agents.hp[idx] / 100.0)[..., None]], axis=2
        )
        obs[:, layout[name]] = (features * valid[..., None]).reshape(n, -1)
    no_bomb = not encoder.bomb or (bomb.status == BombStatus.CARRIED and bomb.carrier < 0)
    state = 0 if no_bomb else 1 + int(bomb.status)
    obs[:, layout["bomb_state"].start + state] = 1.0
    if state:
        offset = (bomb.position - pos) / (2 * half)
        obs[:, layout["bomb_offset"]] = np.clip(offset, -1.0, 1.0)
    if bomb.site in BOMB_SITES:
        obs[:, layout["bomb_site"].start + BOMB_SITES.index(bomb.site)] = 1.0
    if bomb.planter >= 0:
        obs[:, layout["plant_progress"].start] = bomb.plant_ticks / cfg.plant_ticks
    if bomb.defuser >= 0:
        kit = agents.has_defuser[bomb.defuser]
        needed = cfg.defuse_kit_ticks if kit else cfg.defuse_ticks
        obs[:, layout["defuse_progress"].start] = bomb.defuse_ticks / needed
    clock = bomb.planted_tick if bomb.planted_tick >= 0 else sim.tick
    left = (cfg.round_ticks - clock) / cfg.round_ticks
    obs[:, layout["round_time_left"].start] = np.clip(left, 0.0, 1.0)
    if bomb.status == BombStatus.PLANTED:
        left = (bomb.planted_tick + cfg.bomb_ticks - sim.tick) / cfg.bomb_ticks
        obs[:, layout["bomb_time_left"].start] = np.clip(left, 0.0, 1.0)
    return obs.astype(np.float32)


def _steps_of(sim: Simulator, encoder: ObservationEncoder) -> RoundSteps:
    """The environment's steps over a round played here (its `state` is what a step returns;
    nothing is handed in)."""
    is_t = sim.agents.side == "T"
    choices = Choices(np.full(len(is_t), -1, np.int64), np.zeros(0), 0, 30, is_t, ~is_t)
    return RoundSteps(sim, encoder, choices, list(sim.agents.names), is_t)


SEEDS = (0, 1, 4)
"""Busy rounds whose every step is checked. The encoder must match the reference on any
state; these three (of the first twelve, which the test once played) reach every kind of state
the layout has entries for, on both sites: the bomb carried, dropped, planted and exploded, a
plant and a defuse under way (seed 4 alone has a defuse), agents dead."""


def test_the_compiled_encoder_writes_every_entry_as_the_layout_says() -> None:
    graph = builtin_graph()
    setup = RoundSetup(graph=graph, damage_model=Shots())
    checked, seen = 0, set()
    for seed in SEEDS:
        agents = site_agents(graph, seed)
        encoder = ObservationEncoder(graph, list(agents.side), setup.rules_config(), bomb=True)
        with open_round(setup, agents, Wanderers(seed), bomb_carrier=seed % 5, seed=seed) as sim:
            steps = _steps_of(sim, encoder)
            while not sim.done:
                sim.step()
                due = sim.needs_decision
                state = steps.state()
                vectors, masks = state.observations, state.action_masks
                np.testing.assert_array_equal(state.needs_decision, due)
                expected = reference(encoder, sim, due)
                np.testing.assert_allclose(vectors, expected, atol=1e-7, err_msg=str(sim.tick))
                mask = np.zeros((agents.count, NUM_ACTIONS), np.int8)
                mask[:, STOP_ACTION] = 1
                for agent in np.flatnonzero(due):
                    mask[agent] = graph.action_mask(int(agents.node[agent]))
                np.testing.assert_array_equal(masks, mask)
                checked += 1
                seen |= {str(sim.bomb.status.name), "planting" * (sim.bomb.planter >= 0)}
                seen |= {"defusing" * (sim.bomb.defuser >= 0), "dead" * (not agents.alive.all())}
    assert checked > 5000
    assert not steps.state().needs_decision.any()  # nobody decides once the round is done
    assert {"CARRIED", "DROPPED", "PLANTED", "planting", "defusing", "dead"} <= seen, seen
