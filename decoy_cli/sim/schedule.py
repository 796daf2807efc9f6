"""When agents decide next: compiled scans of the engine's per-agent decision state.

The engine asks these at every event (several times per tick with a handful of agents), where
numpy's per-call overhead on arrays of ten elements would cost more than the work. An agent is
due for a decision at a tick when it is alive and either waits at a waypoint or its STOP ends
by then (`hold_until` > 0 and tick >= hold_until).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.compiled import njit_cached

NEVER = 1 << 62
"""A tick no round reaches."""


@njit_cached
def is_due(i, waiting, alive, hold_until, tick):
    """Whether agent i is due for a decision at `tick` (module doc)."""
    return alive[i] and (waiting[i] or (hold_until[i] > 0 and tick >= hold_until[i]))


@njit_cached
def due_agents(waiting, alive, hold_until, tick):
    """Indices (ascending) of the agents due for a decision at `tick`."""
    out = np.empty(alive.shape[0], dtype=np.int64)
    count = 0
    for i in range(alive.shape[0]):
        if is_due(i, waiting, alive, hold_until, tick):
            out[count] = i
            count += 1
    return out[:count]


@njit_cached
def next_due(waiting, alive, hold_until, tick):
    """The first tick after `tick` at which an agent is due for a decision, if no agent
    arrives before (NEVER if none holds a STOP or waits)."""
    first = NEVER
    for i in range(alive.shape[0]):
        if not alive[i]:
            continue
        if waiting[i]:
            return tick + 1
        if 0 < hold_until[i] < first:
            first = hold_until[i]
    return max(first, tick + 1)
