"""FMPy simulation time of case 1 of the paper's study through the FMU, against the native run.

  cargo run --release -p crane-fmu --example case1 > case1.json
  $VENV/bin/python fmu/tests/bench_case1.py case1.json crane.fmu

Prints the times (fastest of 3 FMPy runs; the native figure is the example's fastest of 5)
and checks that the FMU's final state equals the native final state bit for bit. Two FMPy
runs: communication step = h (30,000 doStep calls, FMPy records every step) and one doStep
over the whole 30 s (the FMU's own cost plus FMPy's set-up).
"""

import json
import struct
import sys
import time

from fmpy import simulate_fmu

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
