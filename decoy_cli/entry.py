"""The `decoy` console script: the application, loaded so that a Ctrl-C while its libraries
load (numpy, pandas, typer: most of a second) ends in one line and exit code 130, not in
Python's traceback. Once loaded, each command handles its own interruption."""

from __future__ import annotations

import sys


def main() -> None:
    try:
        from decoy_cli.cli import app
    except KeyboardInterrupt:
        sys.stderr.write("interrupted while starting: nothing was done\n")
        raise SystemExit(130) from None
    app()


if __name__ == "__main__":
    main()
