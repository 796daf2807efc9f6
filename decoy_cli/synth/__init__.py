"""Synthetic ESTA data: scripted de_dust2 rounds played in the simulator, written as ESTA files.

* routes.py: nav places, T strategies and CT setups as routes of waypoint legs;
* loadouts.py: what each side buys (pistol, eco, force and full buys);
* policy.py: the scripted policy that drives the agents;
* recording.py: frames and events recorded as ESTA round data;
* player.py: one round set up, played and recorded (`play_round`);
* sample.py: the shipped sample, a match of such rounds labelled synthetic (`write_sample`).
"""

from decoy_cli.synth.player import PlayedRound, play_round
from decoy_cli.synth.sample import (
    SampleMatch,
    play_match,
    sample_file_name,
    sample_match_id,
    write_sample,
)

__all__ = [
    "PlayedRound",
    "SampleMatch",
    "play_match",
    "play_round",
    "sample_file_name",
    "sample_match_id",
    "write_sample",
]
