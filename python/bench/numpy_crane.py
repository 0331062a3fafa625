"""A plain numpy implementation of the same crane model with smooth friction
``Dbar v + Cbar(q) tanh(1000 v)`` and fixed-step RK4 (no modes, no stiction), batched over
``m`` cranes: the baseline the benchmarks compare ``crane_twin`` against.

Equations as ``model/src/dynamics.rs`` (``M(q) qdd + h(q, qd) + G(q) = Q``); end stops as
``step_smooth`` (position clamped, velocity into the stop zeroed). Not bit-exact with the Rust
model (numpy's solver and operation order differ), but the same model to ~1e-12.
"""

from __future__ import annotations

import numpy as np

GAMMA = 1000.0  # s/m


class NumpyCrane:
    """``m`` cranes with the nominal parameters dict ``p`` (``crane_twin.Params.to_dict()``)."""

    def __init__(self, p: dict, m: int, h: float, gamma: float = GAMMA) -> None:
        ax = [p["x"], p["y"], p["rope"]]
        mp = p["payload_mass"]
        self.h, self.gamma, self.m = h, gamma, m
        self.mp = mp
        self.mpg = mp * p["gravity"]
        self.m00 = p["trolley_mass"] + p["rail_mass"] + ax[0]["inertia"] + mp
        self.m11 = p["trolley_mass"] + ax[1]["inertia"] + mp
        self.m22 = ax[2]["inertia"] + mp
        self.damp = np.array([p["damping_alpha"], p["damping_beta"]])
        self.gain = np.array([a["gain"] for a in ax])
        self.vpos = np.array([a["viscous_pos"] for a in ax])
        self.vneg = np.array([a["viscous_neg"] for a in ax])
        self.cpos = np.array([a["dry_pos"] for a in ax])  # (3, 5)
        self.cneg = np.array([a["dry_neg"] for a in ax])
        self.lo = np.array([a["min"] for a in ax])
        self.hi = np.array([a["max"] for a in ax])

    def _dry(self, c: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``Cbar(q)`` by Horner for positions ``q (m, 3)``, clamped at 0."""
        acc = np.broadcast_to(c[:, 4], q.shape)
        for k in (3, 2, 1, 0):
            acc = acc * q + c[:, k]
        return np.maximum(acc, 0.0)

    def accel(self, y: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``qdd`` for states ``y (m, 10)`` and voltages ``u (m, 3)``."""
        q, qd = y[:, :5], y[:, 5:]
        l, a, b = q[:, 2], q[:, 3], q[:, 4]
        ld, ad, bd = qd[:, 2], qd[:, 3], qd[:, 4]
        sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
        mp, mpl = self.mp, self.mp * l
        n = y.shape[0]
        M = np.zeros((n, 5, 5))
        M[:, 0, 0], M[:, 1, 1], M[:, 2, 2] = self.m00, self.m11, self.m22
        M[:, 0, 2] = M[:, 2, 0] = mp * sa * sb
        M[:, 0, 3] = M[:, 3, 0] = mpl * ca * sb
        M[:, 0, 4] = M[:, 4, 0] = mpl * sa * cb
        M[:, 1, 2] = M[:, 2, 1] = mp * ca
        M[:, 1, 3] = M[:, 3, 1] = -(mpl * sa)
        M[:, 3, 3] = mpl * l
        M[:, 4, 4] = mpl * l * sa * sa
        ad2, bd2 = ad * ad, bd * bd
        hv = np.stack(
            [
                mp * (l * (2 * ad * bd * ca * cb - (ad2 + bd2) * sa * sb) + 2 * ld * (ad * sb * ca + bd * sa * cb)),
                -(mp * ad * (l * ad * ca + 2 * ld * sa)),
                -(mpl * (ad2 + bd2 * sa * sa)),
                mpl * (2 * ld * ad - l * bd2 * sa * ca),
                mpl * bd * (2 * l * ad * sa * ca + 2 * ld * sa * sa),
            ],
            axis=1,
        )
        z = np.zeros_like(l)
        gv = np.stack([z, z, -(self.mpg * sa * cb), -(self.mpg * l * ca * cb), self.mpg * l * sa * sb], axis=1)
        v, p3 = qd[:, :3], q[:, :3]
        pos = v > 0
        visc = np.where(pos, self.vpos, self.vneg)
        dry = np.where(pos, self._dry(self.cpos, p3), self._dry(self.cneg, p3))
        f = visc * v + dry * np.tanh(self.gamma * v)
        Q = np.concatenate([self.gain * u - f, -(self.damp * qd[:, 3:])], axis=1)
        return np.linalg.solve(M, (Q - hv - gv)[..., None])[..., 0]

    def step(self, y: np.ndarray, u: np.ndarray) -> np.ndarray:
        """One RK4 step of ``h``, then the end stops."""
        h = self.h

        def f(s):
            return np.concatenate([s[:, 5:], self.accel(s, u)], axis=1)

        k1 = f(y)
        k2 = f(y + 0.5 * h * k1)
        k3 = f(y + 0.5 * h * k2)
        k4 = f(y + h * k3)
        y = y + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
        q, qd = y[:, :3], y[:, 5:8]
        over, under = q > self.hi, q < self.lo
        q[:] = np.where(over, self.hi, np.where(under, self.lo, q))
        qd[:] = np.where((over & (qd > 0)) | (under & (qd < 0)), 0.0, qd)
        return y
