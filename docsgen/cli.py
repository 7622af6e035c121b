"""The command-line reference, generated from the click commands typer builds from
:mod:`ocgroupoid.cli`: every command and subcommand with its usage, its help and one row per
argument and option (type, default, help).

Typer builds its commands on its own copy of click, so commands and parameters are told apart
by what they do (a group lists commands, an argument's ``param_type_name``), not by click's
classes.
"""

from __future__ import annotations

import inspect
from typing import Any, Iterator

import typer

from ocgroupoid import cli as ocgroupoid_cli


def command() -> Any:
    """The ``ocgroupoid`` command as click sees it."""
    return typer.main.get_command(ocgroupoid_cli.app)


def is_group(cmd: Any) -> bool:
    """Whether a command holds subcommands."""
    return hasattr(cmd, "list_commands")


def context(cmd: Any, name: str) -> Any:
    """A click context of ``cmd`` (for its usage line and parameters)."""
    return cmd.context_class(cmd, info_name=name)


def walk(cmd: Any, path: str = "ocgroupoid") -> Iterator[tuple[str, Any]]:
    """Every command below ``cmd`` (``cmd`` itself first), with its full name."""
    yield path, cmd
    if is_group(cmd):
        ctx = context(cmd, path)
        for name in cmd.list_commands(ctx):
            sub = cmd.get_command(ctx, name)
            if sub is not None and not sub.hidden:
                yield from walk(sub, f"{path} {name}")


def _type(param: Any, ctx: Any) -> str:
    """The type of a parameter as ``--help`` shows it (``path``, ``int``; ``flag``)."""
    if getattr(param, "is_flag", False):
        return "flag"
    if param.multiple:
        return "text, repeatable"
    return str(param.display_type(ctx)).strip("<>")


def _default(param: Any) -> str:
    if param.required:
        return "required"
    value = param.default
    if value is None or value == [] or value == ():
        return "-"
    if isinstance(value, bool):
        return "on" if value else "off"
    return f"`{value}`"


def _names(param: Any) -> str:
    if param.param_type_name == "argument":
        return f"`{param.name.upper()}`"
    return ", ".join(f"`{o}`" for o in [*param.opts, *param.secondary_opts])


def usage(cmd: Any, name: str, ctx: Any) -> str:
    """The usage line: the command, ``[OPTIONS]``, its arguments, or its subcommands."""
    params = [p for p in cmd.get_params(ctx) if p.name != "help"]
    args = [p.name.upper() + ("..." if p.nargs == -1 else "") for p in params
            if p.param_type_name == "argument"]
    tail = ["COMMAND [ARGS]..."] if is_group(cmd) else args
    return " ".join([name, "[OPTIONS]", *tail])


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def markdown() -> str:
    """The reference as Markdown: one section per command."""
    out: list[str] = [inspect.cleandoc(ocgroupoid_cli.__doc__ or ""), ""]
    for name, cmd in walk(command()):
        ctx = context(cmd, name)
        heading = "#" * min(2 + name.count(" "), 4)
        out += [f"{heading} `{name}`", "", inspect.cleandoc(cmd.help or ""), "",
                f"```text\n{usage(cmd, name, ctx)}\n```", ""]
        params = [p for p in cmd.get_params(ctx) if p.name != "help"]
        if params and not is_group(cmd):
            out += ["| argument or option | type | default | help |", "|---|---|---|---|"]
            out += [f"| {_names(p)} | {_type(p, ctx)} | {_default(p)} | "
                    f"{_cell(getattr(p, 'help', None) or '')} |" for p in params]
            out.append("")
        elif is_group(cmd):
            subs = cmd.list_commands(ctx)
            out += ["Commands: " + ", ".join(f"`{name} {s}`" for s in subs) + ".", ""]
    return "\n".join(out)
