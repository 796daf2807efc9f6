"""The simulator's recording: the agents' state sampled at requested ticks, and the events."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.sim.schedule import NEVER
from decoy_cli.sim.state import Agents, SimEvent


@dataclass
class Recording:
    """Agent state sampled at requested ticks: arrays (S, N, ...) plus all events."""

    ticks: np.ndarray
    position: np.ndarray
    yaw: np.ndarray
    hp: np.ndarray
    alive: np.ndarray
    events: list[SimEvent] = field(default_factory=list)


class Recorder:
    """Fills a `Recording` of N agents at the requested ticks as the round passes them."""

    def __init__(self, record_ticks: Sequence[int], n: int, events: list[SimEvent]) -> None:
        ticks = np.asarray(sorted(set(int(t) for t in record_ticks)), dtype=np.int64)
        s = len(ticks)
        self.recording = Recording(
            ticks=ticks,
            position=np.full((s, n, 3), np.nan),
            yaw=np.full((s, n), np.nan),
            hp=np.zeros((s, n), dtype=np.int16),
            alive=np.zeros((s, n), dtype=bool),
            events=events,
        )
        self._next = 0  # the first sample not yet taken
        self._filled_after_end = False

    @property
    def next_tick(self) -> int:
        """The next tick to record (NEVER once all are)."""
        ticks = self.recording.ticks
        return int(ticks[self._next]) if self._next < len(ticks) else NEVER

    def take(self, tick: int, agents: Agents, done: bool) -> None:
        """Record the agents at `tick` if it is requested (passing the requested ticks before
        it). Once the round is `done`, the later samples keep its final state, unless the agents
        go on moving after the end and are recorded over them."""
        rec = self.recording
        while self._next < len(rec.ticks) and rec.ticks[self._next] <= tick:
            k = self._next
            if rec.ticks[k] == tick:
                self._fill(k, k + 1, agents)
            self._next += 1
        if done and not self._filled_after_end:
            self._fill(self._next, len(rec.ticks), agents)
            self._filled_after_end = True

    def _fill(self, start: int, stop: int, agents: Agents) -> None:
        rec = self.recording
        rec.position[start:stop] = agents.position
        rec.yaw[start:stop] = agents.yaw
        rec.hp[start:stop] = agents.hp
        rec.alive[start:stop] = agents.alive
