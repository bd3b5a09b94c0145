"""The ``slax-drake`` command line: thin wrappers that parse arguments and call library functions.

Each stage's commands live in its own ``commands.py`` with ``register(subparsers)``; a registered command sets
``func`` to a callable taking the parsed arguments and returning the exit code. User errors (bad config, bad
file, impossible request) print one line on stderr and exit with code 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from slax_drake import __version__
from slax_drake.errors import UserError

COMMAND_MODULES = (
    "slax_drake.scene.commands",
    "slax_drake.perception.commands",
    "slax_drake.occupancy.commands",
    "slax_drake.dataset.commands",
    "slax_drake.systems.commands",
    "slax_drake.evaluation.commands",
    "slax_drake.evaluation.trial_commands",
    "slax_drake.evaluation.report_commands",
    "slax_drake.hardware.commands",
)


class OneLineErrorParser(argparse.ArgumentParser):
    """An ArgumentParser whose argument errors are one line, like every other user error of the command line:
    ``slax-drake COMMAND: error: MESSAGE (see slax-drake COMMAND --help)``, exit code 2 (argparse's own prints the
    whole usage block first). Subcommand parsers are of this class too."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineErrorParser(
        prog="slax-drake",
        description="Lateral-access mechanical search on shelves with the bluction tool (SLAX-RAY), on Drake.",
    )
    parser.add_argument("--version", action="version", version=f"slax-drake {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except UserError as e:
        print(f"slax-drake {args.command}: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        # An output or input path the system refuses (no such folder, permission, full disk): the user's to fix.
        from slax_drake.io import os_error_message

        print(f"slax-drake {args.command}: error: {os_error_message(e)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"slax-drake {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
