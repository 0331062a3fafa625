"""Parameters to and from the CLI's TOML files, dicts and pickles, exactly."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import crane_twin as ct


def test_toml_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(11)
    p = ct.Params().replace(
        {"payload_mass": float(rng.uniform(0.1, 1)), "x.dry_pos": list(rng.normal(size=5)),
         "rope.viscous_neg": float(rng.uniform(600, 800))}
    )
    path = tmp_path / "sub" / "p.toml"
    path.parent.mkdir()
    p.save(path)
    assert ct.Params.load(path) == p
    assert ct.Params.from_toml(p.to_toml()) == p
    assert not list(path.parent.glob(".*tmp*")), "the temporary file is renamed away"
    assert p != ct.Params()


def test_dict_and_pickle_round_trip():
    p = ct.Params(payload_mass=0.3, x={"gain": 3.0})
    assert p["payload_mass"] == 0.3 and p["x.gain"] == 3.0
    assert p["y.gain"] == ct.Params()["y.gain"]
    d = p.to_dict()
    assert set(d) == {"payload_mass", "trolley_mass", "rail_mass", "gravity", "x", "y", "rope",
                      "damping_alpha", "damping_beta"}
    assert ct.Params.from_dict(d) == p
    assert pickle.loads(pickle.dumps(p)) == p
    assert len(ct.Params.names()) == 4 + 3 * 8 + 2
    with pytest.raises(KeyError):
        p["x.nothing"]


def test_params_accepted_as_object_path_or_dict(tmp_path):
    p = ct.Params(payload_mass=0.2)
    p.save(tmp_path / "p.toml")
    u = np.full((50, 3), 4.0)
    a = ct.rollout(u, params=p)["q"]
    b = ct.rollout(u, params=tmp_path / "p.toml")["q"]
    c = ct.rollout(u, params=str(tmp_path / "p.toml"))["q"]
    d = ct.rollout(u, params={"payload_mass": 0.2})["q"]
    for other in (b, c, d):
        np.testing.assert_array_equal(a, other)
    assert ct.Crane(params=p).params == p


def test_output_and_modes():
    c = ct.Crane()
    assert c.modes == (0, 0, 0)
    o = c.output
    assert o["payload"].shape == (3,) and o["tension"] > 0
    # Hanging still: the rope holds the payload's weight.
    assert abs(o["tension"] - 0.457 * 9.81) < 1e-9
    c.advance([6.0, 0.0, 0.0], 100)
    assert c.modes[0] == 1
    c.reset()
    assert c.steps == 0 and c.modes == (0, 0, 0)
