"""The README's command-line reference, generated from the argument parsers so that it cannot drift.

``python -m balancer.cli_synopsis`` prints the section; ``python -m balancer.cli_synopsis --write README.md``
replaces it in the README (between the ``BEGIN``/``END`` markers). ``tests/test_first_use.py`` fails
when the README differs from what the parsers say.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["BEGIN", "END", "synopsis", "replace_section"]

BEGIN = "<!-- BEGIN generated CLI reference: python -m balancer.cli_synopsis --write README.md -->"
END = "<!-- END generated CLI reference -->"
_WIDTH = 110


def _subcommands(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            yield from action.choices.items()


def synopsis() -> str:
    """Markdown: every subcommand of ``python -m modal`` and ``python -m balancer`` with all its options."""
    from modal.cli import build_parser as modal_parser

    from .cli import build_parser as balancer_parser

    parts = [BEGIN, ""]
    for top in (modal_parser(), balancer_parser()):
        for name, sub in _subcommands(top):
            sub.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=_WIDTH, max_help_position=32)
            text = sub.format_help().rstrip()
            parts += [f"#### `{top.prog} {name}`", "", "```text", text, "```", ""]
    parts.append(END)
    return "\n".join(parts) + "\n"


def replace_section(readme: str, section: str) -> str:
    """The README text with the generated section replaced (it must hold both markers)."""
    start, end = readme.find(BEGIN), readme.find(END)
    if start < 0 or end < start:
        raise ValueError(f"README has no section between {BEGIN!r} and {END!r}")
    return readme[:start] + section + readme[end + len(END) + 1:]


def main(argv: list[str] | None = None) -> int:
    args = argparse.ArgumentParser(prog="python -m balancer.cli_synopsis", description=__doc__.splitlines()[0])
    args.add_argument("--write", metavar="README.md", help="replace the section in this file instead of printing it")
    ns = args.parse_args(argv)
    section = synopsis()
    if ns.write:
        path = Path(ns.write)
        path.write_text(replace_section(path.read_text(encoding="utf-8"), section), encoding="utf-8")
    else:
        sys.stdout.write(section)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
