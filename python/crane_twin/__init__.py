"""``crane_twin``: the overhead-crane digital twin (hybrid, exact-sticking dry friction) at
native speed.

- :class:`Crane`: one simulator, ``step(u)``, ``state``, ``modes``, ``output``, ``rollout(u)``.
- :func:`rollout`, :func:`rollouts`: whole runs in Rust, the batch in parallel (rayon, GIL
  released), results as numpy arrays.
- :class:`Params`: parameters, to and from the ``crane`` CLI's TOML files.
- :class:`CraneBatch`: simulators stepped together (the vector environment's engine).
- :func:`linearize`: the Jacobians ``A``, ``B`` of the continuous-time model (for
  python-control): at a sliding operating point with the hybrid law, at any point (at rest
  too) with ``law="tanh"``.
- Full snapshots (what issue 23 calls ``get_state`` / ``set_state``): ``snapshot()`` /
  ``restore(snapshot)`` / ``from_snapshot(snapshot)`` on :class:`Crane` and
  :class:`CraneBatch`, and on the Gymnasium environments; ``pickle`` round trips of all of
  them are exact.
- Gymnasium: ``CraneAntiSway-v0`` is registered on import when gymnasium is installed
  (:mod:`crane_twin.envs`).

Units are SI; states are ``[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]``; inputs are
the voltages ``[u_x, u_y, u_l]``, saturated to +-12 V.
"""

from __future__ import annotations

from ._native import U_MAX, Crane, CraneBatch, Params, linearize, rollout, rollouts
from .errors import CraneError, InputError, ParameterError, ParamsFileError, StepError

__all__ = [
    "Crane",
    "CraneBatch",
    "Params",
    "rollout",
    "rollouts",
    "linearize",
    "U_MAX",
    "CraneError",
    "InputError",
    "ParameterError",
    "ParamsFileError",
    "StepError",
]

def _version() -> str:
    """The installed distribution's version (python/Cargo.toml's, which maturin writes into
    the wheel's metadata), so that it cannot drift from the package; "0+unknown" when the
    module is imported from a source tree that was never installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("crane_twin")
    except PackageNotFoundError:
        return "0+unknown"


__version__ = _version()


def _register() -> None:
    try:
        import gymnasium  # noqa: F401
    except ImportError:  # the simulator works without gymnasium
        return
    from .envs import register

    register()


_register()
