"""ESTA match files (awpy 1.x JSON): reading, validation and round addressing.

See decoy_cli/esta/reader.py for what is tolerated and what fails the file or only one round.
"""

from decoy_cli.esta.batch import (
    RoundFailure,
    collect_match_files,
    each_round,
    failure_from,
    iter_matches,
    iter_rounds,
    match_rounds,
)
from decoy_cli.esta.frames import MISSING, PlayerInfo, RoundClock
from decoy_cli.esta.reader import (
    Match,
    Round,
    iter_match_files,
    load_round,
    parse_round_address,
    read_match,
)

__all__ = [
    "MISSING",
    "Match",
    "PlayerInfo",
    "Round",
    "RoundClock",
    "RoundFailure",
    "collect_match_files",
    "each_round",
    "failure_from",
    "iter_match_files",
    "iter_matches",
    "iter_rounds",
    "load_round",
    "match_rounds",
    "parse_round_address",
    "read_match",
]
