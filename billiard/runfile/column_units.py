"""The unit and a short description of every column of a run's three tables: the
impacts (``collisions.csv``), the contact phases (``contacts.csv``) and the trajectory
samples (``trajectory.csv``). DataFrames and xarray datasets of a run carry them
(:mod:`billiard.run.frames`); the README's column tables say the same in more words.

Units are SI. An empty unit marks a column without one: the impact number, a label
(``regime``, ``mode``, ``end``) or the index of a wall.
"""

from __future__ import annotations

from billiard.runfile.record import COLUMNS, CONTACT_COLUMNS, TRAJECTORY_COLUMNS

__all__ = ["COLUMN_INFO", "TABLE_COLUMNS", "TABLES", "column_info"]

#: The tables of a run, by name: impacts, contact phases, trajectory samples.
TABLES: tuple[str, ...] = ("impacts", "contacts", "samples")

#: Each table's columns, in file order.
TABLE_COLUMNS: dict[str, tuple[str, ...]] = {
    "impacts": COLUMNS,
    "contacts": CONTACT_COLUMNS,
    "samples": TRAJECTORY_COLUMNS,
}

_WALL = "wall hit: index of the boundary's smooth wall, or the lid"

#: Table name -> column name -> (unit, description).
COLUMN_INFO: dict[str, dict[str, tuple[str, str]]] = {
    "impacts": {
        "n": ("", "impact number, from 1"),
        "t": ("s", "time of the impact"),
        "q1": ("m", "ball centre, horizontal (lab frame)"),
        "q2": ("m", "ball centre, vertical (lab frame)"),
        "v1": ("m/s", "centre velocity after the impact, horizontal"),
        "v2": ("m/s", "centre velocity after the impact, vertical"),
        "omega": ("rad/s", "spin after the impact, counter-clockwise positive"),
        "u4": ("m/s", "centre velocity after the impact along the contact tangent c1"),
        "un": ("m/s", "centre velocity after the impact along the contact normal c2"),
        "tof": ("s", "time since the previous impact"),
        "regime": ("", "impact regime: stick, slip or elastic"),
        "z": ("rad", "tangent angle of the boundary at the contact"),
        "energy": ("J", "mechanical energy after the impact, zero at q2 = 0"),
        "wall": ("", _WALL),
        "Rt": ("N s", "impulse on the ball along the contact tangent c1"),
        "Rn": ("N s", "impulse on the ball along the contact normal c2"),
        "s": ("m", "abscissa of the contact point in the boundary's frame"),
        "q3": ("rad", "rotation angle of the ball, counter-clockwise positive"),
    },
    "contacts": {
        "t_start": ("s", "start of the contact phase"),
        "t_end": ("s", "end of the contact phase"),
        "wall": ("", "index of the wall the ball rolls or slides on (held: the first of two)"),
        "mode": ("", "roll, slide or held"),
        "end": ("", "how the phase ended"),
        "t_settle": ("s", "accumulation point of the chattering the phase stands for"),
        "q1_start": ("m", "ball centre at the start, horizontal"),
        "q2_start": ("m", "ball centre at the start, vertical"),
        "v1_start": ("m/s", "centre velocity at the start, horizontal"),
        "v2_start": ("m/s", "centre velocity at the start, vertical"),
        "omega_start": ("rad/s", "spin at the start"),
        "q1_end": ("m", "ball centre at the end, horizontal"),
        "q2_end": ("m", "ball centre at the end, vertical"),
        "v1_end": ("m/s", "centre velocity at the end, horizontal"),
        "v2_end": ("m/s", "centre velocity at the end, vertical"),
        "omega_end": ("rad/s", "spin at the end"),
        "wall_other": ("", "index of the second wall holding the ball (held), else -2"),
    },
    "samples": {
        "t": ("s", "sample time"),
        "q1": ("m", "ball centre, horizontal (lab frame)"),
        "q2": ("m", "ball centre, vertical (lab frame)"),
        "v1": ("m/s", "centre velocity, horizontal"),
        "v2": ("m/s", "centre velocity, vertical"),
        "omega": ("rad/s", "spin, counter-clockwise positive"),
        "energy": ("J", "mechanical energy, zero at q2 = 0"),
        "mode": ("", "motion state: flight, roll, slide or held"),
    },
}


def column_info(table: str, column: str) -> tuple[str, str]:
    """(unit, description) of ``column`` in ``table``; an extra column a file may hold
    (``read_collisions`` keeps them) has neither: ``("", "")``."""
    return COLUMN_INFO[table].get(column, ("", ""))
