"""`doctrpp` command line: one sub-command per pipeline stage, each defined beside its stage."""

from __future__ import annotations

import argparse
import sys

from doctrpp import __version__
from doctrpp.errors import CliError


def build_parser() -> argparse.ArgumentParser:
    from doctrpp.benchmarks import cli as bench_cli
    from doctrpp.bundle import cli as bundle_cli
    from doctrpp.export import cli as export_cli
    from doctrpp.quantize import cli as quantize_cli
    from doctrpp.runtime import cli as runtime_cli
    from doctrpp.training import cli as training_cli
    from doctrpp.udir import cli as udir_cli

    parser = argparse.ArgumentParser(
        prog="doctrpp",
        description="DocTr++ document-image rectification: export, quantise, run, benchmark.",
    )
    parser.add_argument("--version", action="version", version=f"doctrpp-edge {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    export_cli.add_parser(commands)
    quantize_cli.add_parser(commands)
    runtime_cli.add_parser(commands)
    udir_cli.add_parser(commands)
    training_cli.add_parser(commands)
    bench_cli.add_parser(commands)
    bundle_cli.add_parser(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except CliError as exc:
        print(f"doctrpp {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
