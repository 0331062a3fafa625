"""The Ray example runs locally with 2 workers and returns a sane Monte Carlo summary."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("ray")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ray_sweep.py"


def test_ray_sweep_two_workers():
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    p = subprocess.run(
        [sys.executable, str(EXAMPLE), "--workers", "2", "--sims", "40", "--chunk", "10",
         "--seconds", "2", "--json"],
        capture_output=True, text=True, timeout=300, env=env,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["sims"] == 40 and out["workers"] == 2 and out["sims_per_s"] > 0
    # The move ends with the trolley displaced, and parameter uncertainty spreads it.
    assert out["x_end_mean"] > 0.26 and out["x_end_std"] > 0
    assert 0 < out["peak_swing_p95_rad"] < 1.4
