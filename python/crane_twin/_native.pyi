"""Type stubs of the extension module ``crane_twin._native`` (built from ``python/src``)."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

U_MAX: float

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
#: A ``Params``, a TOML parameter file path, a nested dict (missing fields keep defaults), or None (defaults).
ParamsLike = Union["Params", str, "os.PathLike[str]", Dict[str, Any], None]
#: None (off), ``(ratio, velocity)`` for X and Y, or 3 entries (X, Y, rope) each None or ``(ratio, velocity)``.
StictionLike = Union[None, Tuple[float, float], Sequence[Optional[Tuple[float, float]]]]
#: 10 values ``[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]``, shape (2, 5), or ``{"q": 5 values, "qd": 5 values}``.
StateLike = Union[ArrayLike, Dict[str, ArrayLike], None]

class Params:
    """Validated model parameters (SI); immutable; equal by value; picklable."""

    def __init__(self, **fields: Any) -> None: ...
    @staticmethod
    def from_toml(text: str, origin: str = "<string>") -> Params: ...
    @staticmethod
    def load(path: Union[str, "os.PathLike[str]"]) -> Params: ...
    def to_toml(self) -> str: ...
    def save(self, path: Union[str, "os.PathLike[str]"]) -> None: ...
    @staticmethod
    def from_dict(d: Dict[str, Any]) -> Params: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def replace(self, changes: Dict[str, Union[float, Sequence[float]]]) -> Params: ...
    @staticmethod
    def names() -> List[str]: ...
    def __getitem__(self, name: str) -> Union[float, List[float]]: ...
    def __eq__(self, other: object) -> bool: ...

class Crane:
    """One simulator (hybrid or tanh friction, fixed step ``h`` [s])."""

    def __copy__(self) -> "Crane": ...
    def __deepcopy__(self, memo: object) -> "Crane": ...

    def __init__(
        self,
        params: ParamsLike = None,
        h: float = 1e-3,
        law: str = "hybrid",
        state: StateLike = None,
        *,
        gamma: float = 1000.0,
        stiction: StictionLike = None,
    ) -> None: ...
    def step(self, u: Sequence[float]) -> FloatArray: ...
    def advance(self, u: Sequence[float], n: int) -> FloatArray: ...
    def rollout(self, u: ArrayLike) -> Dict[str, np.ndarray]: ...
    def reset(self, state: StateLike = None) -> None: ...
    @property
    def state(self) -> FloatArray: ...
    @state.setter
    def state(self, value: StateLike) -> None: ...
    @property
    def modes(self) -> Tuple[int, int, int]: ...
    @property
    def output(self) -> Dict[str, Union[float, FloatArray]]: ...
    @property
    def time(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def h(self) -> float: ...
    @property
    def params(self) -> Params: ...

class CraneBatch:
    """Simulators stepped together in Rust (the vector environment's engine)."""

    def __copy__(self) -> "CraneBatch": ...
    def __deepcopy__(self, memo: object) -> "CraneBatch": ...

    def __init__(
        self,
        params_list: Sequence[ParamsLike],
        h: float = 1e-3,
        law: str = "hybrid",
        state: Union[StateLike, ArrayLike] = None,
        *,
        gamma: float = 1000.0,
        stiction: StictionLike = None,
    ) -> None: ...
    def __len__(self) -> int: ...
    def step(self, u: ArrayLike, substeps: int = 1) -> FloatArray: ...
    def reset_sim(
        self, i: int, params: ParamsLike = None, state: StateLike = None, stiction: StictionLike = None
    ) -> None: ...
    @property
    def states(self) -> FloatArray: ...
    @property
    def payload(self) -> FloatArray: ...
    @property
    def modes(self) -> npt.NDArray[np.int8]: ...

def rollout(
    u: ArrayLike,
    params: ParamsLike = None,
    h: float = 1e-3,
    law: str = "hybrid",
    state: StateLike = None,
    *,
    gamma: float = 1000.0,
    stiction: StictionLike = None,
) -> Dict[str, np.ndarray]:
    """Keys: ``t`` (n+1,), ``q``, ``qd`` (n+1, 5), ``modes`` int8 (n+1, 3), ``friction`` (n+1, 3),
    ``tension`` (n+1,), ``payload`` (n+1, 3)."""

def rollouts(
    params_list: Sequence[ParamsLike],
    u: ArrayLike,
    threads: Optional[int] = None,
    h: float = 1e-3,
    law: str = "hybrid",
    state: Union[StateLike, ArrayLike] = None,
    *,
    gamma: float = 1000.0,
    stiction: StictionLike = None,
) -> Dict[str, np.ndarray]:
    """As ``rollout`` with a leading simulation axis (``t`` stays (n+1,))."""
