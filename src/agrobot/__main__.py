"""``python -m agrobot COMMAND ...``: the same program as the ``agrobot`` script (agrobot.orchestrator.cli)."""
import sys

from agrobot.orchestrator.cli import main

if __name__ == "__main__":
    sys.exit(main())
