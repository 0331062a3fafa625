"""Pickling and full snapshots (issue 23: "Snapshot and restore: get_state / set_state on
Crane, the batch and the env"; "Pickle round trips are bit-exact"): a restored or unpickled
simulator, batch or environment continues with the same bits as the original, and a bad
snapshot raises a typed error naming the key."""

from __future__ import annotations

import copy
import json
import pickle

import numpy as np
import pytest

import crane_twin as ct

PROTOCOLS = [0, pickle.DEFAULT_PROTOCOL, pickle.HIGHEST_PROTOCOL]
INPUTS = ([4.0, 0.0, 0.0], [0.0, -5.0, 1.0], [20.0, 3.0, -30.0], [0.0, 0.0, 0.0])


def _bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _same_output(a: ct.Crane, b: ct.Crane) -> None:
    oa, ob = a.output, b.output
    for k in ("qdd", "friction", "payload"):
        np.testing.assert_array_equal(_bits(oa[k]), _bits(ob[k]))
    assert _bits(np.float64(oa["tension"])) == _bits(np.float64(ob["tension"]))


def _same_crane(a: ct.Crane, b: ct.Crane) -> None:
    np.testing.assert_array_equal(_bits(a.state), _bits(b.state))
    assert a.modes == b.modes and a.steps == b.steps
    assert _bits(np.float64(a.time)) == _bits(np.float64(b.time))
    _same_output(a, b)


def _continue_alike(a: ct.Crane, b: ct.Crane) -> None:
    for u in INPUTS:
        np.testing.assert_array_equal(_bits(a.advance(u, 150)), _bits(b.advance(u, 150)))
        _same_crane(a, b)
    u = np.random.default_rng(4).uniform(-12, 12, size=(200, 3))
    ra, rb = a.rollout(u), b.rollout(u)
    assert ra.keys() == rb.keys()
    for k in ra:
        np.testing.assert_array_equal(ra[k], rb[k])
        if ra[k].dtype == np.float64:
            np.testing.assert_array_equal(_bits(ra[k]), _bits(rb[k]))


def _moved(law: str = "hybrid", **kw) -> ct.Crane:
    c = ct.Crane(law=law, stiction=(1.6, 0.01), **kw)
    c.advance([3.0, -2.0, 1.0], 400)
    c.advance([12.5, 0.0, -0.5], 7)  # a saturated last input: u_last is 12 V
    return c


@pytest.mark.parametrize("protocol", PROTOCOLS)
@pytest.mark.parametrize("law", ["hybrid", "tanh"])
def test_a_pickled_crane_continues_bit_for_bit(protocol, law):
    c = _moved(law)
    d = pickle.loads(pickle.dumps(c, protocol=protocol))
    assert type(d) is ct.Crane and d.params == c.params and d.h == c.h
    _same_crane(c, d)
    _continue_alike(c, d)
    c.advance([12.0, 0.0, 0.0], 10)
    assert not np.array_equal(c.state, d.state), "the copy is independent"


def test_a_new_crane_pickles_and_resets_to_its_initial_state():
    init = [0.1, 0.2, 0.3, 1.5, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0]
    c = ct.Crane(state=init, h=2e-3)
    d = pickle.loads(pickle.dumps(c))
    assert d.steps == 0 and d.h == 2e-3
    _same_crane(c, d)
    c.advance([5.0, 5.0, 0.0], 50)
    d.advance([5.0, 5.0, 0.0], 50)
    for x in (c, d):
        x.reset()
    np.testing.assert_array_equal(c.state, init)
    _continue_alike(c, d)


def test_snapshot_step_restore_step_gives_the_same_arrays():
    c = _moved()
    snap = c.snapshot()
    assert snap["format"] == "crane_twin.Crane" and snap["version"] == 1
    first = [c.step(u) for u in np.random.default_rng(1).uniform(-12, 12, size=(100, 3))]
    out1, t1 = c.output, c.time
    c.restore(snap)
    second = [c.step(u) for u in np.random.default_rng(1).uniform(-12, 12, size=(100, 3))]
    np.testing.assert_array_equal(_bits(first), _bits(second))
    assert c.time == t1
    np.testing.assert_array_equal(_bits(out1["friction"]), _bits(c.output["friction"]))


def test_a_snapshot_is_plain_data_and_survives_json():
    c = _moved()
    snap = c.snapshot()
    text = json.dumps(snap)  # plain values only: no numpy, no Params object
    d = ct.Crane.from_snapshot(json.loads(text))
    _same_crane(c, d)
    # restoring into a simulator of other parameters takes everything from the snapshot
    e = ct.Crane(params={"payload_mass": 0.3}, law="tanh", h=5e-4)
    e.restore(json.loads(text))
    assert e.params == c.params and e.h == c.h
    _continue_alike(c, d)
    _continue_alike(e, ct.Crane.from_snapshot(snap))


def test_a_snapshot_is_a_copy_not_a_view():
    c = _moved()
    snap = c.snapshot()
    c.advance([1.0, 1.0, 0.0], 100)
    assert snap["steps"] == 407 and c.steps == 507
    assert ct.Crane.from_snapshot(snap).steps == 407


def test_params_pickle_exactly():
    p = ct.Params(payload_mass=0.3123456789, x={"dry_pos": [1.1, 0.2, -0.3, 0.4, 1e-17]})
    for protocol in PROTOCOLS:
        assert pickle.loads(pickle.dumps(p, protocol=protocol)) == p


def _batch() -> ct.CraneBatch:
    b = ct.CraneBatch([ct.Params(), ct.Params(payload_mass=0.3), ct.Params()], stiction=(1.3, 0.005))
    b.reset_sim(2, params={"x": {"gain": 2.5}}, state=[0.2, 0.4, 0.3, 1.6, 0.1, 0, 0, 0, 0, 0])
    u = np.array([[5.0, -3.0, 0.5], [-4.0, 2.0, 0.0], [1.0, 1.0, -1.0]])
    b.step(u, substeps=250)
    return b


@pytest.mark.parametrize("protocol", PROTOCOLS)
def test_a_pickled_batch_continues_bit_for_bit(protocol):
    b = _batch()
    d = pickle.loads(pickle.dumps(b, protocol=protocol))
    assert len(d) == len(b)
    np.testing.assert_array_equal(b.modes, d.modes)
    rng = np.random.default_rng(2)
    for _ in range(30):
        u = rng.uniform(-12, 12, size=(3, 3))
        np.testing.assert_array_equal(_bits(b.step(u, 5)), _bits(d.step(u, 5)))
        np.testing.assert_array_equal(b.modes, d.modes)
    # the per-simulation setups came along: a reset without arguments goes to each one's own
    for x in (b, d):
        x.reset_sim(2)
    np.testing.assert_array_equal(_bits(b.states), _bits(d.states))
    assert b.states[2, 0] == 0.2


def test_batch_snapshot_and_restore():
    b = _batch()
    snap = b.snapshot()
    assert [s["format"] for s in snap["sims"]] == ["crane_twin.Crane"] * 3
    u = np.full((3, 3), 2.0)
    first = [b.step(u, 10) for _ in range(10)]
    b.restore(json.loads(json.dumps(snap)))
    second = [b.step(u, 10) for _ in range(10)]
    np.testing.assert_array_equal(_bits(first), _bits(second))
    # another batch takes the snapshot's length and simulators
    other = ct.CraneBatch([ct.Params()])
    other.restore(snap)
    assert len(other) == 3
    np.testing.assert_array_equal(_bits(other.step(u, 10)), _bits(first[0]))
    states = np.array([s["state"] for s in snap["sims"]])
    np.testing.assert_array_equal(_bits(ct.CraneBatch.from_snapshot(snap).states), _bits(states))


# ---- bad snapshots ------------------------------------------------------------------------


def _with(snap, **changes):
    s = copy.deepcopy(snap)
    for k, v in changes.items():
        if v is KeyError:
            del s[k]
        else:
            s[k] = v
    return s


@pytest.mark.parametrize(
    "changes, words",
    [
        ({"state": KeyError}, ['snapshot["state"]', "missing"]),
        ({"colour": "red"}, ["unknown key", "colour"]),
        ({"version": 2}, ['snapshot["version"]', "2"]),
        ({"format": "crane_twin.CraneBatch"}, ['snapshot["format"]']),
        ({"state": [0.2, 0.3]}, ['snapshot["state"]', "10"]),
        ({"state": "abc"}, ['snapshot["state"]']),
        ({"modes": [2, 0, 0]}, ['snapshot["modes"]']),
        ({"modes": [0, 0, 0]}, ['snapshot["modes"]', "velocities"]),
        ({"state": [0.505, 0.3, 0.35, 1.5, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0]}, ['snapshot["state"]', "limit"]),
        ({"steps": -1}, ['snapshot["steps"]']),
        ({"u_last": [13.0, 0.0, 0.0]}, ['snapshot["u_last"][0]']),
        ({"u_last": [float("nan"), 0.0, 0.0]}, ['snapshot["u_last"][0]']),
        ({"steps": 0}, ['snapshot["u_last"]', "steps"]),
        ({"stiction": [[1.2, 0.01]]}, ['snapshot["stiction"]']),
        ({"law": "coulomb"}, ["law"]),
        ({"law": "tanh", "gamma": None}, ['snapshot["gamma"]']),
        ({"params": 3}, ['snapshot["params"]']),
        ({"params": {"mass": 1.0}}, ['snapshot["params"]', "mass"]),
    ],
)
def test_a_bad_crane_snapshot_raises_input_error_naming_the_key(changes, words):
    c = _moved()
    before = c.snapshot()
    with pytest.raises(ct.InputError) as e:
        c.restore(_with(before, **changes))
    for w in words:
        assert w in str(e.value)
    assert c.snapshot() == before, "a failed restore changes nothing"
    with pytest.raises(ct.InputError):
        ct.Crane.from_snapshot(_with(before, **changes))


@pytest.mark.parametrize(
    "changes, field, key",
    [
        ({"params": {"payload_mass": -1.0}}, "payload_mass", "params"),
        ({"state": [0.9, 0.3, 0.35, np.pi / 2, 0, 0, 0, 0, 0, 0]}, "state.q[0]", "state"),
        ({"init": [0.2, 0.3, 0.35, 0.01, 0, 0, 0, 0, 0, 0]}, "state.q[3]", "init"),
        ({"h": -1.0}, "config.h", "h"),
        ({"stiction": [[0.5, 0.01], None, None]}, "stiction[0].ratio", "stiction"),
    ],
)
def test_a_refused_value_raises_parameter_error_naming_field_and_key(changes, field, key):
    c = _moved()
    with pytest.raises(ct.ParameterError) as e:
        c.restore(_with(c.snapshot(), **changes))
    assert e.value.field == field
    assert f'snapshot["{key}"]' in str(e.value)


def test_bad_batch_snapshots_name_the_simulation():
    b = _batch()
    snap = b.snapshot()
    bad = copy.deepcopy(snap)
    bad["sims"][1]["modes"] = [1, 1]
    with pytest.raises(ct.InputError, match=r'snapshot\["sims"\]\[1\]\["modes"\]'):
        b.restore(bad)
    with pytest.raises(ct.InputError, match="sims"):
        b.restore(_with(snap, sims="abc"))
    with pytest.raises(ct.InputError, match="format"):
        b.restore(_moved().snapshot())
    with pytest.raises(ct.InputError, match="dict"):
        ct.CraneBatch.from_snapshot([1, 2, 3])
    assert b.snapshot() == snap
