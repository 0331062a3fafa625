"""Type stubs of the extension module ``crane_twin._native`` (built from ``python/src``)."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt
from typing_extensions import TypeAlias, final

__all__ = ["Params", "Crane", "CraneBatch", "rollout", "rollouts", "linearize", "U_MAX"]

#: The saturation of every input voltage [V] (12).
U_MAX: float

# The aliases below exist in the stub only (private names: no runtime counterpart).
_ArrayLike: TypeAlias = npt.ArrayLike
_FloatArray: TypeAlias = npt.NDArray[np.float64]
#: A ``Params``, a TOML parameter file path, a nested dict (missing fields keep defaults), or None (defaults).
_ParamsLike: TypeAlias = Union["Params", str, "os.PathLike[str]", Dict[str, Any], None]
#: None (off), ``(ratio, velocity)`` for X and Y, or 3 entries (X, Y, rope) each None or ``(ratio, velocity)``.
_StictionLike: TypeAlias = Union[None, Tuple[float, float], Sequence[Optional[Tuple[float, float]]]]
#: 10 values ``[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]``, shape (2, 5), or ``{"q": 5 values, "qd": 5 values}``.
_StateLike: TypeAlias = Union[_ArrayLike, Dict[str, _ArrayLike], None]

@final
class Params:
    """Validated model parameters (SI); immutable; equal by value; picklable."""

    def __new__(cls, **fields: Any) -> Params: ...
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
    def __getitem__(self, name: str, /) -> Union[float, List[float]]: ...
    def __eq__(self, other: object, /) -> bool: ...

@final
class Crane:
    """One simulator (hybrid or tanh friction, fixed step ``h`` [s]).

    With ``law="tanh"``, a large ``gamma`` [s/m] is stiff at rest: the fixed-step RK4 is stable
    only for ``h`` below about ``2.785 M / (Dbar + gamma Cbar)`` of the stiffest axis (default
    parameters: 5.59 ms at ``gamma=1000``, 0.599 ms at 1e4, 0.060 ms at 1e5); above it the
    crane at rest creeps without an error (see ``model/NUMERICS.md``).

    Copies (``copy``, ``deepcopy``) and ``pickle`` round trips continue bit for bit.
    ``snapshot()`` / ``restore()`` are what issue 23 calls ``get_state`` / ``set_state`` (the
    ``state`` property is only the physical state vector)."""

    def __copy__(self) -> "Crane": ...
    def __deepcopy__(self, memo: object) -> "Crane": ...
    def snapshot(self) -> Dict[str, Any]:
        """The full state as a dict of plain values: ``format`` ("crane_twin.Crane"),
        ``version`` (1), ``params`` (``Params.to_dict()``), ``h`` [s], ``law``, ``gamma`` [s/m]
        or None, ``stiction`` (3 entries, None or ``[ratio, velocity m/s]``), ``init`` (the 10
        values ``reset()`` returns to), ``state`` (10 values [m, rad, m/s, rad/s]), ``modes``
        (3 of -1, 0, 1), ``steps``, ``u_last`` (the last saturated input [V])."""
    def restore(self, snapshot: Dict[str, Any]) -> None:
        """Continues from ``snapshot`` bit for bit; a bad key raises ``InputError`` naming it
        (``snapshot["modes"]``), a refused value ``ParameterError``; nothing changes then."""
    @staticmethod
    def from_snapshot(snapshot: Dict[str, Any]) -> "Crane":
        """A new simulator from ``snapshot()`` (``pickle`` uses it)."""

    def __new__(
        cls,
        params: _ParamsLike = None,
        h: float = 1e-3,
        law: str = "hybrid",
        state: _StateLike = None,
        *,
        gamma: float = 1000.0,
        stiction: _StictionLike = None,
    ) -> Crane: ...
    def step(self, u: Sequence[float]) -> _FloatArray: ...
    def advance(self, u: Sequence[float], n: int) -> _FloatArray: ...
    def rollout(self, u: _ArrayLike) -> Dict[str, np.ndarray]: ...
    def reset(self, state: _StateLike = None) -> None: ...
    @property
    def state(self) -> _FloatArray: ...
    @state.setter
    def state(self, value: _StateLike) -> None: ...
    @property
    def modes(self) -> Tuple[int, int, int]: ...
    @property
    def output(self) -> Dict[str, Union[float, _FloatArray]]: ...
    @property
    def time(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def h(self) -> float: ...
    @property
    def params(self) -> Params: ...

@final
class CraneBatch:
    """Simulators stepped together in Rust (the vector environment's engine).

    Copies and ``pickle`` round trips continue bit for bit; ``snapshot()`` / ``restore()``
    are issue 23's ``get_state`` / ``set_state``."""

    def __copy__(self) -> "CraneBatch": ...
    def __deepcopy__(self, memo: object) -> "CraneBatch": ...
    def snapshot(self) -> Dict[str, Any]:
        """``{"format": "crane_twin.CraneBatch", "version": 1, "sims": [Crane.snapshot() dict
        per simulator]}``."""
    def restore(self, snapshot: Dict[str, Any]) -> None:
        """Replaces every simulator (the batch takes the snapshot's length); errors name the
        key (``snapshot["sims"][2]["state"]``); nothing changes on error."""
    @staticmethod
    def from_snapshot(snapshot: Dict[str, Any]) -> "CraneBatch":
        """A new batch from ``snapshot()`` (``pickle`` uses it)."""

    def __new__(
        cls,
        params_list: Sequence[_ParamsLike],
        h: float = 1e-3,
        law: str = "hybrid",
        state: Union[_StateLike, _ArrayLike] = None,
        *,
        gamma: float = 1000.0,
        stiction: _StictionLike = None,
    ) -> CraneBatch: ...
    def __len__(self) -> int: ...
    def step(self, u: _ArrayLike, substeps: int = 1) -> _FloatArray: ...
    def reset_sim(
        self, i: int, params: _ParamsLike = None, state: _StateLike = None, stiction: _StictionLike = None
    ) -> None: ...
    @property
    def states(self) -> _FloatArray: ...
    @property
    def payload(self) -> _FloatArray: ...
    @property
    def modes(self) -> npt.NDArray[np.int8]: ...

def rollout(
    u: _ArrayLike,
    params: _ParamsLike = None,
    h: float = 1e-3,
    law: str = "hybrid",
    state: _StateLike = None,
    *,
    gamma: float = 1000.0,
    stiction: _StictionLike = None,
) -> Dict[str, np.ndarray]:
    """Keys: ``t`` (n+1,), ``q``, ``qd`` (n+1, 5), ``modes`` int8 (n+1, 3), ``friction`` (n+1, 3),
    ``tension`` (n+1,), ``payload`` (n+1, 3)."""

def rollouts(
    params_list: Sequence[_ParamsLike],
    u: _ArrayLike,
    threads: Optional[int] = None,
    h: float = 1e-3,
    law: str = "hybrid",
    state: Union[_StateLike, _ArrayLike] = None,
    *,
    gamma: float = 1000.0,
    stiction: _StictionLike = None,
) -> Dict[str, np.ndarray]:
    """As ``rollout`` with a leading simulation axis (``t`` stays (n+1,))."""

def linearize(
    params: _ParamsLike,
    state: _StateLike,
    u: Sequence[float],
    *,
    law: str = "hybrid",
    gamma: float = 1000.0,
    stiction: _StictionLike = None,
    eps: float = 1e-6,
) -> Tuple[_FloatArray, _FloatArray]:
    """``(A, B)``, ``(10, 10)`` and ``(10, 3)``: the Jacobians of the model's continuous-time
    right-hand side ``dx/dt = f(x, u)`` at ``(state, u)`` by central finite differences
    (steps ``eps * max(1, |v|)``), for python-control (``control.ss(A, B, C, D)``).

    ``x = [x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]`` [m, m, m, rad, rad, m/s, m/s,
    m/s, rad/s, rad/s] (hanging: ``alpha = pi/2``, ``beta = 0``; ``Ld > 0`` lowers), ``u =
    [u_x, u_y, u_l]`` [V] strictly inside +-12 V. ``law`` and ``gamma`` [s/m] as ``Crane``.

    ``law="hybrid"``: X and Y must slide (``xd``, ``yd`` nonzero): a stopped axis raises
    ``InputError`` naming ``state.qd[i]`` (dry friction is not differentiable at zero
    velocity). The rope slides or is held by friction strictly inside its breakaway band
    (held: rows ``L``, ``Ld`` and column ``Ld`` are zero). A sliding point is no equilibrium:
    ``d(dx)/dt = A dx + B du`` models deviations from the nonlinear trajectory through it,
    over short horizons while no axis stops.

    ``law="tanh"``: differentiable in every velocity, so any point is accepted, at rest
    included. The hanging equilibrium is ``qd = 0``, ``alpha = pi/2``, ``beta = 0``, ``u =
    [0, 0, -payload_mass * gravity / rope.gain]`` (the rope drive carries the weight; with
    ``u_l = 0`` the rope creeps down). Friction there acts as a viscous slope ``Dbar + gamma
    Cbar(q)`` [N s/m], valid while ``|gamma qd|`` stays well below 1; where an axis' ``+`` and
    ``-`` coefficients differ, ``A`` holds the mean of the two one-sided slopes. ``eps *
    gamma`` must be at most 0.01. ``stiction`` has no effect under this law (as in ``Crane``).
    ``A``'s fastest eigenvalue bounds ``Crane``'s fixed step under this law: RK4 is stable for
    ``h < 2.785 / |lambda|`` (default parameters: 5.59 ms at ``gamma=1000``, 0.599 ms at 1e4)."""
