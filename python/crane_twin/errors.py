"""Typed exceptions of ``crane_twin``.

Every error the model or an argument check reports is one of these, so a script can
catch ``crane_twin.CraneError`` for all of them. None of them aborts the process.
"""

from __future__ import annotations

from typing import Optional

__all__ = ["CraneError", "ParameterError", "ParamsFileError", "StepError", "InputError"]


class CraneError(Exception):
    """Base class of every ``crane_twin`` error."""


class ParameterError(CraneError, ValueError):
    """A rejected parameter, configuration or state field.

    Attributes: ``field`` (dotted name, e.g. ``"x.viscous_pos"``, ``"config.h"``,
    ``"state.q[3]"``, ``"stiction[0].ratio"``), ``problem`` (``"not_finite"``,
    ``"not_positive"``, ``"negative"``, ``"empty_range"``, ``"out_of_limits"``,
    ``"angle_out_of_range"``, ``"below_one"``, ``"too_large"``) and ``value``.
    """

    def __init__(self, message: str, field: str, problem: str, value: float) -> None:
        super().__init__(message)
        self.field = field
        self.problem = problem
        self.value = value


class ParamsFileError(CraneError, ValueError):
    """A parameter file that cannot be read, parsed or validated; the message names the file
    and, for TOML syntax or type errors, the line and column."""


class StepError(CraneError, RuntimeError):
    """A rejected step; the simulator stays at its last accepted state.

    Attributes: ``kind`` (``"input_not_finite"``, ``"singular"``, ``"non_finite"``,
    ``"out_of_domain"``), ``step`` (index within the call), ``sim`` (index in a batch, or
    None), ``axis`` (for a non-finite input: 0 X, 1 Y, 2 rope; else None).
    """

    def __init__(
        self,
        message: str,
        kind: str,
        step: int,
        sim: Optional[int] = None,
        axis: Optional[int] = None,
    ) -> None:
        super().__init__(message)
        self.kind = kind
        self.step = step
        self.sim = sim
        self.axis = axis


class InputError(CraneError, ValueError):
    """An argument of the wrong type, shape or value (a non-finite voltage, ``u`` not of
    shape ``(n, 3)``, an unknown friction law or parameter name)."""
