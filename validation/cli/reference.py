"""The command-line reference, generated from the ``flexval`` argument parser itself.

:func:`cli_reference` walks :func:`flexval.validation.cli.build_parser`: the
global options, then every sub-command with its usage line, its positional
arguments and its options (metavar, default, allowed values, help text).
The documentation site renders it, so a command or option added to the
parser appears in the reference without an edit.
"""

from __future__ import annotations

import argparse


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction | None:
    """The parser's sub-command action, if it has one."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action
    return None


def commands(parser: argparse.ArgumentParser | None = None) -> dict[str, argparse.ArgumentParser]:
    """Every sub-command of ``flexval`` (or of ``parser``) by name, in the parser's order."""
    if parser is None:
        from . import build_parser

        parser = build_parser()
    sub = _subparsers(parser)
    return {} if sub is None else dict(sub.choices)


def _help_text(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The action's help with ``%(default)s``-style fields filled in, as argparse prints it."""
    if not action.help or action.help == argparse.SUPPRESS:
        return ""
    return parser._get_formatter()._expand_help(action)


def _cell(text: str) -> str:
    """``text`` safe inside a Markdown table cell."""
    text = " ".join(text.split()).replace("|", "\\|")
    return text.replace("[", "\\[").replace("]", "\\]")


def _argument(action: argparse.Action) -> str:
    """How the option's value is written: its metavar, choices or nothing (a flag, a positional)."""
    if action.nargs == 0 or not action.option_strings:
        return ""
    if action.metavar is not None:
        meta = action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar)
    elif action.choices is not None:
        meta = "{" + ",".join(map(str, action.choices)) + "}"
    else:
        meta = action.dest.upper()
    if action.nargs in ("*", "+"):
        meta = f"{meta} ..."
    elif isinstance(action.nargs, int) and action.nargs > 1 and isinstance(action.metavar, str):
        meta = " ".join([meta] * action.nargs)
    return f"`{meta}`"


def _options_table(parser: argparse.ArgumentParser) -> str:
    """The parser's arguments as a Markdown table (help and version actions left out)."""
    rows = []
    for action in parser._actions:
        if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
            continue
        if action.help == argparse.SUPPRESS:
            continue
        name = ", ".join(f"`{o}`" for o in action.option_strings) or f"`{action.dest}`"
        what = _help_text(parser, action)
        if action.required and action.option_strings:
            what = f"**required**; {what}"
        if action.choices is not None and not isinstance(action.choices, dict):
            what += f" (one of {', '.join(f'`{c}`' for c in action.choices)})"
        repeat = " (repeatable)" if isinstance(action, argparse._AppendAction) else ""
        if repeat and "repeatable" not in what:
            what += repeat
        rows.append(f"| {name} | {_argument(action)} | {_cell(what)} |")
    if not rows:
        return "No arguments.\n"
    return "| argument | value | meaning |\n|---|---|---|\n" + "\n".join(rows) + "\n"


USAGE_WIDTH = 88
"""Characters per line of the usage blocks (fixed, so the reference does not depend on the
terminal that builds it)."""


def _usage(parser: argparse.ArgumentParser) -> str:
    """The usage line as argparse prints it (``usage: `` removed), at :data:`USAGE_WIDTH`."""
    formatter = argparse.HelpFormatter(parser.prog, width=USAGE_WIDTH)
    formatter.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    lines = formatter.format_help().strip().splitlines()
    indent = len("usage: ")
    return "\n".join([lines[0][indent:], *(line[indent:] for line in lines[1:])])


def cli_reference(parser: argparse.ArgumentParser | None = None, level: int = 2) -> str:
    """The reference of every ``flexval`` command and option, as Markdown.

    Parameters
    ----------
    parser : argparse.ArgumentParser or None
        The parser to document; None: :func:`flexval.validation.cli.build_parser`.
    level : int
        Heading level of each command's section.

    Returns
    -------
    str
        The global options, a summary table of the commands, and one section
        per command (usage, description, arguments).
    """
    if parser is None:
        from . import build_parser

        parser = build_parser()
    sub = _subparsers(parser)
    helps = {a.dest: a.help or "" for a in (sub._choices_actions if sub else [])}
    h = "#" * level
    parts = [
        f"{h} Global options {{#global-options}}",
        f"```text\n{_usage(parser)}\n```",
        _cell(parser.description or ""),
        _options_table(parser),
        f"{h} Commands {{#commands}}",
        "| command | what it does |\n|---|---|\n"
        + "\n".join(
            f"| [`flexval {name}`](#flexval-{name}) | {_cell(helps.get(name, ''))} |"
            for name in commands(parser)
        )
        + "\n",
    ]
    for name, cmd in commands(parser).items():
        parts.append(f"{h} `flexval {name}` {{#flexval-{name}}}")
        parts.append(_cell(cmd.description or helps.get(name, "")))
        parts.append(f"```text\n{_usage(cmd)}\n```")
        parts.append(_options_table(cmd))
    return "\n\n".join(parts)
