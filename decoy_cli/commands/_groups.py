"""Option groups: options several commands share, defined once as a dataclass.

Each field of a group is one command-line option, written in Typer's `Annotated` style with a
plain default::

    @dataclass(frozen=True)
    class Split:
        seed: Annotated[int, typer.Option("--seed", help="...")] = 0

A command takes the group as one parameter (`split: Split`) under `@with_groups`: Typer sees
each field as an option of its own, in the group's place, and the command receives the filled
dataclass. Typer has no such grouping of its own (fastapi/typer#153, #264), and without it the
same options were written out, with their help, in every command that has them.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import typing
from collections.abc import Callable
from typing import Any, TypeVar

Command = TypeVar("Command", bound=Callable[..., None])


def with_groups(command: Command) -> Command:
    """`command` as Typer should see it: every dataclass-typed parameter replaced by its fields
    (keyword options, in the group's place); called, it builds each group from them. Called
    from Python it takes its own parameters too: a group given whole, or its fields, each
    missing field from the group's default."""
    hints = typing.get_type_hints(command, include_extras=True)
    groups: dict[str, Any] = {}  # parameter name -> the group's default instance
    parameters: list[inspect.Parameter] = []
    for parameter in inspect.signature(command).parameters.values():
        kind = hints[parameter.name]
        if not (isinstance(kind, type) and dataclasses.is_dataclass(kind)):
            parameters.append(parameter.replace(annotation=kind, kind=_KEYWORD))
            continue
        default = parameter.default
        groups[parameter.name] = default if isinstance(default, kind) else kind()
        fields = typing.get_type_hints(kind, include_extras=True)
        for field in dataclasses.fields(kind):
            if field.name in hints:
                raise TypeError(f"{command.__name__}: option {field.name!r} given twice")
            parameters.append(
                inspect.Parameter(
                    field.name, _KEYWORD, default=field.default, annotation=fields[field.name]
                )
            )

    @functools.wraps(command)
    def run(*args: Any, **options: Any) -> None:
        for name, default in groups.items():
            if name not in options:
                names = [field.name for field in dataclasses.fields(default)]
                given = {field: options.pop(field) for field in names if field in options}
                options[name] = dataclasses.replace(default, **given)
        command(*args, **options)

    run.__signature__ = inspect.Signature(parameters)  # type: ignore[attr-defined]
    run.__annotations__ = {p.name: p.annotation for p in parameters}
    return typing.cast(Command, run)


_KEYWORD = inspect.Parameter.KEYWORD_ONLY
