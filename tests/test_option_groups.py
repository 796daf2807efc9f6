"""`with_groups`: a dataclass of options is one parameter of a command, and Typer sees its
fields as options of their own."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Literal

import pytest
import typer
from typer.testing import CliRunner

from decoy_cli.commands._groups import with_groups


@dataclass(frozen=True)
class Pace:
    speed: Annotated[float, typer.Option("--speed", help="Metres per second.")] = 2.5
    gait: Annotated[Literal["walk", "run"], typer.Option("--gait", help="How.")] = "run"


def _app(received: list[object]) -> typer.Typer:
    app = typer.Typer()

    @app.command()
    @with_groups
    def move(
        name: str = typer.Argument(...),
        pace: Pace = Pace(),
        laps: int = typer.Option(1, "--laps"),
    ) -> None:
        received.append((name, pace, laps))

    return app


def test_a_group_reaches_the_command_filled_from_its_options() -> None:
    received: list[object] = []
    result = CliRunner().invoke(_app(received), ["ann", "--gait", "walk", "--laps", "3"])
    assert result.exit_code == 0, result.output
    assert received == [("ann", Pace(speed=2.5, gait="walk"), 3)]


def test_a_groups_options_are_in_the_help_with_their_choices() -> None:
    shown = CliRunner().invoke(_app([]), ["--help"], env={"COLUMNS": "200"}).output
    for text in ("--speed", "Metres per second.", "--gait", "walk|run", "--laps"):
        assert text in shown


def test_a_bad_choice_in_a_group_is_a_usage_error() -> None:
    result = CliRunner().invoke(_app([]), ["ann", "--gait", "crawl"])
    assert result.exit_code == 2 and "Invalid value for '--gait'" in result.output


def test_an_option_given_by_a_group_and_the_command_is_refused() -> None:
    def twice(pace: Pace = Pace(), speed: float = 1.0) -> None:
        pass

    with pytest.raises(TypeError, match="'speed' given twice"):
        with_groups(twice)


def test_a_command_called_from_python_takes_a_group_whole_or_its_fields() -> None:
    received: list[object] = []

    @with_groups
    def move(name: str, pace: Pace = Pace(gait="walk"), laps: int = 1) -> None:
        received.append((name, pace, laps))

    move("ann")
    move("bob", pace=Pace(speed=1.0), laps=2)
    move("cy", speed=4.0)  # a field alone: the rest from the group's default
    assert received == [
        ("ann", Pace(gait="walk"), 1),
        ("bob", Pace(speed=1.0), 2),
        ("cy", Pace(speed=4.0, gait="walk"), 1),
    ]
