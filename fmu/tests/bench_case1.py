"""FMPy simulation time of case 1 of the paper's study through the FMU, against the native run.

  cargo run --release -p crane-fmu --example case1 > case1.json
  $VENV/bin/python fmu/tests/bench_case1.py case1.json crane.fmu

Prints the times (fastest of 3 FMPy runs; the native figure is the example's fastest of 5)
and checks that the FMU's final state equals the native final state bit for bit. Two FMPy
runs: communication step = h (30,000 doStep calls, FMPy records every step) and one doStep
over the whole 30 s (the FMU's own cost plus FMPy's set-up: unzip, XML, load). Last, the
bare `fmi2DoStep` of 30 s through FMPy's low-level API (instance made once; fastest of 3).
"""

import json
import struct
import sys
import time

from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave

case = json.load(open(sys.argv[1]))
fmu = sys.argv[2]
names = ["q.x", "q.y", "q.l", "q.alpha", "q.beta", "qd.x", "qd.y", "qd.l", "qd.alpha", "qd.beta"]


def run(interval):
    best, res = float("inf"), None
    for _ in range(3):
        t0 = time.perf_counter()
        res = simulate_fmu(fmu, start_time=0.0, stop_time=case["duration"],
                           output_interval=interval, start_values=case["start_values"],
                           output=names)
        best = min(best, time.perf_counter() - t0)
    return best, res


want = case["final"]
for label, interval in [("step h (30000 doStep)", 1e-3), ("one doStep of 30 s", case["duration"])]:
    t, res = run(interval)
    got = ["%016x" % struct.unpack("<Q", struct.pack("<d", res[n][-1]))[0] for n in names]
    assert got == want, (label, got, want)
    print(f"case 1 through FMPy, {label}: {t:.4f} s; native {case['native_s']:.4f} s;"
          f" ratio {t / case['native_s']:.1f}; final state equal bit for bit")


desc = read_model_description(fmu)
slave = FMU2Slave(guid=desc.guid, unzipDirectory=extract(fmu), modelIdentifier="crane",
                  instanceName="bench")
vrs = {v.name: v.valueReference for v in desc.modelVariables}
best = float("inf")
for _ in range(3):
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for name, value in case["start_values"].items():
        slave.setReal([vrs[name]], [value])
    slave.exitInitializationMode()
    t0 = time.perf_counter()
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=case["duration"])
    best = min(best, time.perf_counter() - t0)
    got = ["%016x" % struct.unpack("<Q", struct.pack("<d", x))[0]
           for x in slave.getReal([vrs[n] for n in names])]
    assert got == want, got
    slave.fmi2FreeInstance(slave.component)
slave.freeLibrary()
print(f"case 1, bare fmi2DoStep of 30 s: {best:.4f} s; native {case['native_s']:.4f} s;"
      f" ratio {best / case['native_s']:.2f} (native stores every sample, the FMU does not)")
