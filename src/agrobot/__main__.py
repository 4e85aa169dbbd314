"""``python -m agrobot COMMAND ...`` and the ``agrobot`` script: one program (agrobot.orchestrator.cli).

Both have the working folder on the module search path, as ``python -m`` has it: a study's
``type = "module:Class"`` finds a module beside the command either way (a study's own folder of
modules is ``[study] components_path``).
"""
import os
import sys

from agrobot.extras import missing_extra_message
from agrobot.orchestrator.cli import main as cli_main


def main() -> int:
    """Run the command; a module of an optional extra that is not installed is named with the
    extra to install (exit 2, agrobot.extras)."""
    if "" not in sys.path and os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        return cli_main()
    except ModuleNotFoundError as exc:
        message = missing_extra_message(exc)
        if message is None:
            raise
        print(message, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
