"""FMPy checks of the crane FMU (issue 13).

Environment (set by scripts/test.sh; the defaults fit a workspace build):
  CRANE_FMU  path of crane.fmu (scripts/build-fmu.sh)
  CRANE_BIN  path of the release `crane` binary (`cargo build --release --bin crane`)

Run: `$VENV/bin/python -m pytest -q fmu/tests/test_fmu.py`.
"""

import math
import os
import subprocess
import zipfile
from ctypes import byref, c_char, c_double, c_uint32

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Error,
)
from fmpy.validation import validate_fmu

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
FMU = os.environ.get("CRANE_FMU", os.path.join(ROOT, "crane.fmu"))
CRANE = os.environ.get("CRANE_BIN", os.path.join(TARGET, "release", "crane"))
H = 1e-3

# A scenario of `crane simulate` (format: tools/src/simulate.rs): the validation multisine of
# MODEL.md on the default crane with a 0.064 kg payload, plus voltage steps that move and
# stop X and the rope, sampled at every model step (sample_s = h) so every step is compared.
SCENARIO = """
duration_s = 12.0
h = 0.001
sample_s = 0.001
payload_kg = 0.064
q0 = [0.25, 0.3, 0.35, 1.5707963267948966, 0.0]
qd0 = [0.0, 0.0, 0.0, 0.0, 0.0]
[[input]]
axis = "x"
amplitude_v = 1.5
frequency_hz = 0.404
[[input]]
axis = "x"
offset_v = 2.5
start_s = 6.0
stop_s = 7.0
[[input]]
axis = "y"
amplitude_v = 1.5
frequency_hz = 0.314
[[input]]
axis = "y"
amplitude_v = 1.5
frequency_hz = 0.942
[[input]]
axis = "l"
amplitude_v = 0.5
frequency_hz = 0.406
[[input]]
axis = "l"
offset_v = -1.5
start_s = 3.0
stop_s = 3.5
[[input]]
axis = "l"
offset_v = 2.5
start_s = 8.0
stop_s = 8.5
"""


def bits(a):
    """The f64 bit patterns of an array (so -0.0 != 0.0 and NaN == NaN by pattern)."""
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64)).view(np.uint64)


def first_difference(name, got, want):
    g, w = bits(got), bits(want)
    i = int(np.argmax(g != w))
    x = int(g[i] ^ w[i])
    return (
        f"{name}: first difference at row {i}: FMU {got[i]!r} vs crane simulate {want[i]!r}"
        f" (xor of bits {x:#018x}, highest differing bit {x.bit_length() - 1})"
    )


@pytest.fixture(scope="module")
def description():
    assert os.path.isfile(FMU), f"{FMU} missing: run scripts/build-fmu.sh"
    return read_model_description(FMU)


def test_archive_layout_and_validation(description):
    with zipfile.ZipFile(FMU) as z:
        names = set(z.namelist())
    assert {
        "modelDescription.xml",
        "binaries/linux64/crane.so",
        "documentation/index.html",
    } <= names
    problems = validate_fmu(FMU)
    assert problems == [], problems
    assert description.fmiVersion == "2.0"
    assert description.coSimulation.modelIdentifier == "crane"
    by_name = {v.name: v for v in description.modelVariables}
    for u in ("u_x", "u_y", "u_l"):
        assert by_name[u].causality == "input" and by_name[u].unit == "V"
    for name, unit in [
        ("q.x", "m"), ("q.alpha", "rad"), ("qd.y", "m/s"), ("qd.beta", "rad/s"),
        ("friction.l", "N"), ("tension", "N"), ("payload.z", "m"),
    ]:
        assert by_name[name].causality == "output" and by_name[name].unit == unit, name
    for m in ("mode.x", "mode.y", "mode.l"):
        assert by_name[m].type == "Integer" and by_name[m].causality == "output"
    params = [v for v in description.modelVariables if v.causality == "parameter"]
    tunable = [v for v in params if v.variability == "tunable"]
    # every field of crane_model::Params, and stiction ratio and Stribeck velocity per axis
    assert len(tunable) == 54 + 6
    assert all(v.unit and v.start is not None for v in tunable)
    assert description.coSimulation.canGetAndSetFMUstate
    assert description.coSimulation.canSerializeFMUstate
    assert by_name["x.viscous_neg"].start == "101.44"
    assert by_name["rope.dry_pos[0]"].start == "8.583"
    assert by_name["config.h"].start == "0.001"


@pytest.fixture(scope="module")
def native(tmp_path_factory):
    """`crane simulate` of SCENARIO: the CSV rows as a structured array."""
    d = tmp_path_factory.mktemp("native")
    scen = d / "scenario.toml"
    scen.write_text(SCENARIO)
    out = d / "run.csv"
    assert os.path.isfile(CRANE), f"{CRANE} missing: cargo build --release --bin crane"
    subprocess.run([CRANE, "simulate", str(scen), "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL)
    lines = [l for l in out.read_text().splitlines() if not l.startswith("#")]
    header = lines[0].split(",")
    # float() reads Rust's shortest round-trip text back to the same bits.
    rows = [tuple(float(x) for x in l.split(",")) for l in lines[1:]]
    return np.array(rows, dtype=[(h, np.float64) for h in header])


def test_trajectory_equals_crane_simulate_bit_for_bit(native):
    t = native["t"]
    signals = np.zeros(len(t), dtype=[("time", np.float64), ("u_x", np.float64),
                                      ("u_y", np.float64), ("u_l", np.float64)])
    signals["time"] = t
    for u in ("u_x", "u_y", "u_l"):
        signals[u] = native[u]
    outputs = ["q.x", "q.y", "q.l", "q.alpha", "q.beta", "mode.x", "mode.y", "mode.l",
               "friction.x", "friction.y", "friction.l", "tension", "u_x", "u_y", "u_l"]
    res = simulate_fmu(
        FMU,
        start_time=0.0,
        stop_time=float(t[-1]),
        output_interval=H,
        start_values={"payload_mass": 0.064},
        input=signals,
        output=outputs,
    )
    assert len(res) == len(native), (len(res), len(native))
    assert np.array_equal(bits(res["time"]), bits(t))
    # The input the FMU held over step k (recorded after the step, at t[k+1]) is row k of
    # the CSV: FMPy applied the voltages exactly, zero-order hold.
    for u in ("u_x", "u_y", "u_l"):
        assert np.array_equal(bits(res[u][1:]), bits(native[u][:-1])), u
    # The scenario exercises the automaton: every drive axis moves and sticks.
    for m in ("mode_x", "mode_y", "mode_l"):
        assert set(np.unique(native[m])) >= {0.0}, m
        assert np.any(native[m] != 0.0), m
    pairs = [("q.x", "x"), ("q.y", "y"), ("q.l", "l"), ("q.alpha", "alpha"),
             ("q.beta", "beta"), ("friction.x", "friction_x"), ("friction.y", "friction_y"),
             ("friction.l", "friction_l"), ("tension", "tension")]
    for fmu_name, csv_name in pairs:
        got, want = res[fmu_name], native[csv_name]
        assert np.array_equal(bits(got), bits(want)), first_difference(fmu_name, got, want)
    for axis in ("x", "y", "l"):
        assert np.array_equal(res[f"mode.{axis}"].astype(np.float64), native[f"mode_{axis}"])


class Log:
    """Collects the FMU's log messages through the FMI logger callback."""

    def __init__(self):
        self.messages = []

        def logger(env, instance, status, category, message):
            self.messages.append((status, message.decode()))

        self.callback = fmi2CallbackLoggerTYPE(logger)
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self.callback


@pytest.fixture(scope="module")
def slave(description):
    unzipdir = extract(FMU)
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=unzipdir,
                    modelIdentifier="crane", instanceName="crane1")
    yield fmu
    fmu.freeLibrary()


def free(slave):
    """fmi2FreeInstance only: FMPy's `freeInstance` also unloads the library."""
    slave.fmi2FreeInstance(slave.component)


def vr(description, name):
    return next(v.valueReference for v in description.modelVariables if v.name == name)


def test_wrong_parameter_is_an_error_status_and_a_logged_message(description, slave):
    log = Log()
    slave.instantiate(callbacks=log.callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr(description, "x.gain")], [-3.2])
    with pytest.raises(FMICallException) as e:
        slave.exitInitializationMode()
    assert e.value.status == fmi2Error
    assert (fmi2Error, "invalid parameter: `x.gain` must be > 0 (got -3.2)") in log.messages
    free(slave)

    # Through simulate_fmu as a user would: an exception, no crash.
    with pytest.raises(FMICallException):
        simulate_fmu(FMU, stop_time=0.01, output_interval=H,
                     start_values={"state.q[2]": 0.9})  # rope longer than rope.max


def test_an_empty_travel_names_the_limit_the_user_set(description, slave):
    """``x.max = -1`` (below ``x.min = 0``): the message names ``x.max``, the field set, and
    the bound it violates, ``x.min = 0`` (issue 23: it named ``x.min``)."""
    for name, value, message in [
        ("x.max", -1.0, "invalid parameter: `x.max` must be above `x.min` = 0 (got -1): "
                        "the travel [x.min, x.max] is empty"),
        ("y.min", 0.7, "invalid parameter: `y.min` must be below `y.max` = 0.625 (got 0.7): "
                       "the travel [y.min, y.max] is empty"),
    ]:
        log = Log()
        slave.instantiate(callbacks=log.callbacks)
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setReal([vr(description, name)], [value])
        with pytest.raises(FMICallException):
            slave.exitInitializationMode()
        assert (fmi2Error, message) in log.messages, log.messages
        free(slave)


def test_step_not_a_multiple_of_h_is_an_error(description, slave):
    log = Log()
    slave.instantiate(callbacks=log.callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=5 * H)
    with pytest.raises(FMICallException) as e:
        slave.doStep(currentCommunicationPoint=5 * H, communicationStepSize=1.5 * H)
    assert e.value.status == fmi2Error
    assert any("not a whole multiple of the model step config.h = 0.001 s" in m
               for s, m in log.messages if s == fmi2Error), log.messages
    # Nothing moved: still at 5 ms.
    t = c_double()
    assert slave.fmi2GetRealStatus(slave.component, 2, byref(t)) == 0
    assert t.value == 5 * H
    slave.terminate()
    free(slave)


def rss_kib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024


def test_instantiate_reset_free_1000_times_leaks_nothing(description, slave):
    u_x = vr(description, "u_x")
    q_x = vr(description, "q.x")
    vrs = (c_uint32 * 1)(q_x)
    out = (c_double * 1)()

    def cycle():
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.setReal([u_x], [3.0])
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=10 * H)
        slave.fmi2GetReal(slave.component, vrs, 1, out)
        slave.reset()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=H)
        slave.terminate()
        free(slave)

    for _ in range(100):  # warm up allocator pools and ctypes caches
        cycle()
    before = rss_kib()
    for _ in range(1000):
        cycle()
    after = rss_kib()
    growth = after - before
    print(f"\nRSS before {before} KiB, after 1000 cycles {after} KiB, growth {growth} KiB")
    assert out[0] > 0.25  # the steps did run (X moved under +3 V)

    # The measurement can see a leak: 1000 instances kept alive (the simulator and its name)
    # grow RSS by about 940 KiB here (the allocator first reuses what the cycles above
    # freed), well above the 256 KiB allowed below.
    kept = []
    start = rss_kib()
    for _ in range(1000):
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        kept.append(slave.component)
    held = rss_kib() - start
    for c in kept:
        slave.fmi2FreeInstance(c)
    print(f"1000 instances kept alive: RSS growth {held} KiB")
    assert held > 256, held
    assert growth < 256, f"RSS grew by {growth} KiB over 1000 instantiate/reset/free cycles"


# ---- issue 23: declared ranges, FMU state, friction options ------------------------------

#: The model's checks (crane_model::Params::validate, Extensions::validate, Crane::new) and
#: the FMU's own (law, gamma), written out independently of the Rust table: > 0 is declared
#: as min = 5e-324, the smallest positive double (FMI's min is inclusive).
POS = 5e-324
SWING = 1.4


def expected_range(name):
    axis_field = name.split(".", 1)[1] if name.split(".")[0] in ("x", "y", "rope") else None
    if name in ("payload_mass", "trolley_mass", "config.h", "config.law.gamma", "rope.min"):
        return POS, None
    if name in ("rail_mass", "gravity", "damping_alpha", "damping_beta"):
        return 0.0, None
    if axis_field == "gain" or name.endswith("].velocity"):
        return POS, None
    if axis_field in ("inertia", "viscous_pos", "viscous_neg"):
        return 0.0, None
    if name.endswith("].ratio"):
        return 1.0, None
    if name == "state.q[3]":
        return math.pi / 2 - SWING, math.pi / 2 + SWING
    if name == "state.q[4]":
        return -SWING, SWING
    if name == "config.segment_budget":
        return 1.0, 8.0
    if name == "config.law.kind":
        return 0.0, 1.0
    return None, None  # any finite value (or a range set by other parameters)


def exit_status(slave, variable, value):
    """Status and logged messages of exitInitializationMode with one parameter set."""
    log = Log()
    slave.instantiate(callbacks=log.callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    if variable.type == "Integer":
        slave.setInteger([variable.valueReference], [int(value)])
    else:
        slave.setReal([variable.valueReference], [value])
    try:
        slave.exitInitializationMode()
        status = 0
    except FMICallException as e:
        status = e.status
    free(slave)
    return status, [m for s, m in log.messages if s == fmi2Error]


def test_every_bounded_parameter_declares_the_range_the_fmu_checks(description, slave):
    params = [v for v in description.modelVariables if v.causality == "parameter"]
    bounded = 0
    for v in params:
        lo, hi = expected_range(v.name)
        got = (None if v.min is None else float(v.min), None if v.max is None else float(v.max))
        assert got == (lo, hi), v.name
        for bound, outward in [(lo, -math.inf), (hi, math.inf)]:
            if bound is None:
                continue
            bounded += 1
            assert exit_status(slave, v, bound) == (0, []), (v.name, bound)
            beyond = bound + math.copysign(1.0, outward) if v.type == "Integer" \
                else math.nextafter(bound, outward)
            status, errors = exit_status(slave, v, beyond)
            assert status == fmi2Error, (v.name, beyond)
            assert any(f"`{v.name}`" in m for m in errors), (v.name, beyond, errors)
    assert bounded == 35
    # FMPy's validation (schema and rules) still passes with the ranges.
    assert validate_fmu(FMU) == []


OUTS = ["q.x", "q.y", "q.l", "q.alpha", "q.beta", "qd.x", "qd.y", "qd.l", "qd.alpha",
        "qd.beta", "friction.x", "friction.y", "friction.l", "tension", "payload.x",
        "payload.y", "payload.z", "u_x", "u_y", "u_l"]


def u_of(t):
    """Voltages [V] that move, reverse and stop every axis, up to 15 V (saturated to 12)."""
    return [15.0 * math.sin(7.0 * t), 5.0 * math.cos(3.0 * t), 2.0 * math.sin(5.0 * t)]


def observe(description, slave):
    """Every real output and input (as bits), the modes and the FMU's time."""
    reals = slave.getReal([vr(description, n) for n in OUTS])
    modes = slave.getInteger([vr(description, f"mode.{a}") for a in "xyl"])
    t = c_double()
    assert slave.fmi2GetRealStatus(slave.component, 2, byref(t)) == 0
    return [int(b) for b in bits(reals)] + list(modes) + [int(bits([t.value])[0])]


def advance(description, slave, start, n):
    rows = []
    u_vrs = [vr(description, n) for n in ("u_x", "u_y", "u_l")]
    for k in range(start, start + n):
        t = k * H
        slave.setReal(u_vrs, u_of(t))
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=H)
        rows.append(observe(description, slave))
    return rows


def start_with_stiction(description, slave, callbacks=None):
    slave.instantiate(callbacks=callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr(description, "stiction[0].ratio"), vr(description, "stiction[1].ratio")],
                  [1.4, 1.2])
    slave.exitInitializationMode()


def test_fmu_state_get_set_and_serialize_continue_bit_for_bit(description, slave):
    """Get the state at t1, simulate to t2, set it, simulate to t2 again: the same bits;
    serialized and read into a fresh instance: the same bits again."""
    start_with_stiction(description, slave)
    advance(description, slave, 0, 700)
    state = slave.getFMUstate()
    at_t1 = observe(description, slave)
    first = advance(description, slave, 700, 800)
    # Other inputs and a heavier payload since: undone by the state.
    slave.setReal([vr(description, "u_x"), vr(description, "payload_mass")], [7.0, 0.9])
    slave.setFMUstate(state)
    assert observe(description, slave) == at_t1
    assert advance(description, slave, 700, 800) == first
    data = slave.serializeFMUstate(state)
    assert data[:8] == b"CRANEFMU"
    slave.freeFMUstate(state)
    assert state.value is None  # fmi2FreeFMUstate set the importer's pointer to null
    c1 = slave.component

    slave.instantiate()  # a fresh instance, never initialised
    restored = slave.deSerializeFMUstate(data)
    slave.setFMUstate(restored)
    assert slave.serializeFMUstate(restored) == data
    assert observe(description, slave) == at_t1
    assert advance(description, slave, 700, 800) == first
    slave.freeFMUstate(restored)
    free(slave)
    slave.fmi2FreeInstance(c1)
    # The run moved X both ways and the rope both ways and stopped it.
    assert {r[20] for r in first} == {-1, 1}
    assert {r[22] for r in first} == {-1, 0, 1}


def test_a_corrupt_or_wrong_size_state_is_an_error_with_a_message(description, slave):
    log = Log()
    start_with_stiction(description, slave, log.callbacks)
    advance(description, slave, 0, 50)
    state = slave.getFMUstate()
    data = slave.serializeFMUstate(state)
    flipped = bytearray(data)
    flipped[len(data) // 2] ^= 0x01
    cases = [
        (data[:-1], f"serialized FMU state: {len(data) - 1} bytes, but its header says {len(data)}"),
        (data + b"\0", f"serialized FMU state: {len(data) + 1} bytes, but its header says {len(data)}"),
        (bytes(flipped), "serialized FMU state: checksum mismatch (corrupt bytes)"),
        (b"not a state", "serialized FMU state: not a crane FMU state (11 bytes, no `CRANEFMU` header)"),
    ]
    for bad, message in cases:
        log.messages.clear()
        with pytest.raises(FMICallException) as e:
            slave.deSerializeFMUstate(bad)
        assert e.value.status == fmi2Error
        assert log.messages == [(fmi2Error, message)]
    # A wrong buffer size for fmi2SerializeFMUstate.
    buf = (c_char * (len(data) - 1))()
    with pytest.raises(FMICallException):
        slave.fmi2SerializeFMUstate(slave.component, state, buf, len(data) - 1)
    # The instance still works.
    slave.setFMUstate(state)
    slave.doStep(currentCommunicationPoint=50 * H, communicationStepSize=H)
    slave.freeFMUstate(state)
    free(slave)


def hold_x(description, slave, ratio, volts, steps=500):
    """X's mode after `steps` ms at `volts` on X from rest, with stiction `ratio` on X."""
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr(description, "stiction[0].ratio")], [ratio])
    slave.exitInitializationMode()
    slave.setReal([vr(description, "u_x")], [volts])
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=steps * H)
    mode, = slave.getInteger([vr(description, "mode.x")])
    x, = slave.getReal([vr(description, "q.x")])
    free(slave)
    return mode, x


def test_stiction_holds_x_between_sliding_and_breakaway_friction(description, slave):
    """X at 0.25 m has sliding dry friction Cbar+(0.25) = 1.262 N, 0.39 V of its 3.2 N/V
    gain: 0.5 V moves it without stiction; with ratio 1.5 (breakaway 0.59 V) it stays
    stuck, and 0.7 V breaks it away."""
    assert hold_x(description, slave, 1.0, 0.5)[0] == 1
    mode, x = hold_x(description, slave, 1.5, 0.5)
    assert (mode, x) == (0, 0.25)
    assert hold_x(description, slave, 1.5, 0.7)[0] == 1


def friction_options_against_crane_twin(description, slave, reals, ints, kwargs):
    """4 s of `u_of` through the FMU with options set, against `crane_twin.rollout` with the
    same options: q, qd, modes, friction and tension bit for bit at every step."""
    try:
        import crane_twin
    except ImportError:
        # in CI the package is installed before this test runs (scripts/test.sh): a skip
        # there would hide the FMU drifting from the Python model
        if os.environ.get("CI"):
            raise
        pytest.skip("the crane_twin package (python/) is not installed in this venv")
    n = 4000
    u = np.array([u_of(k * H) for k in range(n)])
    ref = crane_twin.rollout(u, **kwargs)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for name, value in reals:
        slave.setReal([vr(description, name)], [value])
    for name, value in ints:
        slave.setInteger([vr(description, name)], [value])
    slave.exitInitializationMode()
    rows = [observe(description, slave)] + advance(description, slave, 0, n)
    free(slave)
    reals = np.array([r[:20] for r in rows], dtype=np.uint64).view(np.float64)
    modes = np.array([r[20:23] for r in rows], dtype=np.int64)
    for name, got, want in [("q", reals[:, 0:5], ref["q"]),
                            ("qd", reals[:, 5:10], ref["qd"]),
                            ("friction", reals[:, 10:13], ref["friction"]),
                            ("tension", reals[:, 13], ref["tension"])]:
        assert np.array_equal(bits(got), bits(want)), first_difference(
            name, got.ravel(), np.asarray(want).ravel())
    assert np.array_equal(modes, ref["modes"].astype(np.int64))
    return ref


def test_stiction_equals_crane_twin_bit_for_bit(description, slave):
    """The FMU's stiction parameters are the Python package's `stiction=` (X, Y, rope)."""
    ref = friction_options_against_crane_twin(
        description, slave,
        reals=[("stiction[0].ratio", 1.5), ("stiction[1].ratio", 1.3),
               ("stiction[2].ratio", 1.2), ("stiction[2].velocity", 0.01)],
        ints=[],
        kwargs=dict(stiction=[(1.5, 0.005), (1.3, 0.005), (1.2, 0.01)]))
    assert set(np.unique(ref["modes"][:, 2])) == {-1, 0, 1}


def test_tanh_law_equals_crane_twin_bit_for_bit(description, slave):
    """`config.law.kind = 1` with `config.law.gamma` is the Python package's `law="tanh"`."""
    friction_options_against_crane_twin(
        description, slave, reals=[("config.law.gamma", 250.0)],
        ints=[("config.law.kind", 1)], kwargs=dict(law="tanh", gamma=250.0))
