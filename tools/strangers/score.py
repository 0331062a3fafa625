"""Score `crane diagnose` on the stranger cases.

    python3 tools/strangers/score.py --out DIR [--cases N | --only CAUSE] [--jobs 2]
        [--markdown PATH] [--json PATH] [--timeout 300] [--no-generate [--reuse-reports]]

Generates the cases into DIR (cases.py; same master seed, same cases), runs
`$CRANE_BIN diagnose DIR/<case>/data --json DIR/<case>/report.json` on each (CRANE_BIN
defaults to target/release/crane of the repository), scores the report against
DIR/<case>/truth.json and prints a per-case line, a per-cause table (sync / async), the totals
and the honesty failures. Rules: README.md beside this file.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
REPO = os.path.dirname(os.path.dirname(HERE))

TOL = 0.25  # relative tolerance of a main parameter
NMAE_LIMIT_PCT = 1e4  # an NMAE figure above this (percent) is a diverged simulation
# a finding's text admitting that a value sits at the end of the range the tool searched
EDGE_RE = re.compile(
    r"\bedge\b|\b(largest|smallest|highest|lowest|first|last) (value|level|delay|width)s? tried"
    r"|\bat the (upper|lower) (end|bound|limit)\b",
    re.I,
)


def crane_bin() -> str:
    b = os.environ.get("CRANE_BIN", os.path.join(REPO, "target", "release", "crane"))
    if not os.path.isabs(b):
        b = os.path.join(REPO, b)
    return b


def load_run(case_dir: str) -> dict | None:
    """The tool's earlier run of this case (--reuse-reports), or None."""
    try:
        with open(os.path.join(case_dir, "tool_run.json")) as f:
            meta = json.load(f)
        with open(os.path.join(case_dir, "tool_stderr.txt")) as f:
            err = f.read()
    except (OSError, ValueError):
        return None
    report, report_error = None, ""
    if meta["rc"] == 0:
        try:
            with open(os.path.join(case_dir, "report.json")) as f:
                report = json.load(f)
        except (OSError, ValueError) as e:
            report_error = f"no readable report: {e}"
    return {"rc": meta["rc"], "timed_out": meta["timed_out"], "seconds": meta["seconds"],
            "stderr": err, "report": report, "report_error": report_error}


def run_case(case_dir: str, binary: str, timeout: float) -> dict:
    data = os.path.join(case_dir, "data")
    rep = os.path.join(case_dir, "report.json")
    if os.path.exists(rep):
        os.remove(rep)
    t0 = time.time()
    try:
        p = subprocess.run(
            [binary, "diagnose", data, "--json", rep],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        rc, out, err = p.returncode, p.stdout, p.stderr
        timed_out = False
    except subprocess.TimeoutExpired as e:
        rc, out, err, timed_out = None, e.stdout or "", e.stderr or "", True
        if isinstance(out, bytes):
            out = out.decode(errors="replace")
        if isinstance(err, bytes):
            err = err.decode(errors="replace")
    dt = time.time() - t0
    with open(os.path.join(case_dir, "tool_run.json"), "w") as f:
        json.dump({"rc": rc, "timed_out": timed_out, "seconds": dt, "timeout": timeout}, f)
    with open(os.path.join(case_dir, "tool_stdout.txt"), "w") as f:
        f.write(out)
    with open(os.path.join(case_dir, "tool_stderr.txt"), "w") as f:
        f.write(err)
    report = None
    report_error = ""
    if rc == 0:
        try:
            with open(rep) as f:
                report = json.load(f)
        except (OSError, ValueError) as e:
            report_error = f"no readable report: {e}"
    return {"rc": rc, "timed_out": timed_out, "seconds": dt, "stderr": err, "report": report,
            "report_error": report_error}


# ---------------------------------------------------------------------------------------------
# Honesty checks


def _walk(obj, path=""):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _walk(v, f"{path}.{k}" if path else str(k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _walk(v, f"{path}[{i}]")
    else:
        yield path, obj


def _num(v):
    if isinstance(v, bool) or v is None:
        return None
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, str) and v.strip().lower() in ("nan", "inf", "-inf", "infinity", "-infinity"):
        return float(v.strip().lower().replace("infinity", "inf"))
    return None


def honesty(report: dict) -> list:
    fails = []
    for path, v in _walk(report):
        key = path.rsplit(".", 1)[-1]
        if "nmae" in key.lower():
            x = _num(v)
            # null is how the report marks a diverged simulation (REPORT_SCHEMA.md: no figure,
            # `diverged_*` flags beside it); only a printed figure can be dishonest
            if x is not None and (not math.isfinite(x) or x > NMAE_LIMIT_PCT):
                fails.append(f"{path}: NMAE figure {v!r} (non-finite or above {NMAE_LIMIT_PCT:g} %)")
    for i, fnd in enumerate(report.get("findings") or []):
        for k, v in (fnd.get("parameters") or {}).items():
            x = _num(v)
            if v is None or (x is not None and not math.isfinite(x)):
                fails.append(f"findings[{i}].parameters.{k}: non-finite value {v!r}")
        for path, v in _walk(fnd):
            if isinstance(v, str) and EDGE_RE.search(v):
                fails.append(f"findings[{i}] ({fnd.get('cause')}): note at a grid edge: {v[:160]!r}")
        if fnd.get("cause") == "input_delay":
            ps = fnd.get("parameters") or {}
            if "delay_s" not in ps:
                fails.append(f"findings[{i}] input_delay: delay in samples only ({sorted(ps)})")
    for k, v in (report.get("final_model") or {}).items():
        x = _num(v)
        if x is not None and not math.isfinite(x):
            fails.append(f"final_model.{k}: non-finite value {v!r}")
    return fails


def suspicious(report: dict) -> list:
    """Findings with unphysical parameters (reported, not asserted): a stiction ratio below 1,
    a Stribeck static level below the sliding one, a negative amplitude, dead band, saturation,
    stiffness or mu."""
    out = []
    for i, fnd in enumerate(report.get("findings") or []):
        c, ps = fnd.get("cause"), fnd.get("parameters") or {}
        num = {k: _num(v) for k, v in ps.items()}
        if c == "stiction":
            for d in ("pos", "neg"):
                r = num.get(f"ratio_{d}")
                if r is not None and r < 1.0:
                    out.append(f"findings[{i}] stiction: ratio_{d} = {r:.4g} < 1")
        if c == "stribeck_friction":
            for d in ("pos", "neg"):
                st, sl = num.get(f"static_{d}"), num.get(f"sliding_{d}")
                if st is not None and sl is not None and st < sl:
                    out.append(f"findings[{i}] stribeck_friction: static_{d} {st:.4g} < sliding_{d} {sl:.4g}")
        for k in ("amplitude_n", "width_m", "deadband", "saturation", "stiffness", "mu", "delay_s",
                  "stribeck_velocity"):
            v = num.get(k)
            if v is not None and v < 0:
                out.append(f"findings[{i}] {c}: {k} = {v:.4g} < 0")
    return out


# ---------------------------------------------------------------------------------------------
# Scoring one case


def rel_ok(got, want, tol=TOL):
    if got is None or want is None:
        return False
    try:
        got = float(got)
    except (TypeError, ValueError):
        return False
    if not math.isfinite(got):
        return False
    return abs(got - want) <= tol * abs(want)


def rel_err(got, want):
    try:
        return (float(got) - want) / abs(want)
    except (TypeError, ValueError, ZeroDivisionError):
        return None


def levels_carry(truth: dict, report: dict) -> tuple:
    """Asymmetry / offset carried by the baseline's per-direction kinetic levels."""
    fm = report.get("final_model") or {}
    eff = truth["effective_kinetic"]
    kp, kn = _num(fm.get("kinetic_pos")), _num(fm.get("kinetic_neg"))
    if kp is None or kn is None:
        return False, "final model without kinetic levels"
    ok = rel_ok(abs(kp), abs(eff["kinetic_pos"])) and rel_ok(abs(kn), abs(eff["kinetic_neg"]))
    return ok, (f"kinetic +{abs(kp):.4g}/-{abs(kn):.4g} vs effective "
                f"+{abs(eff['kinetic_pos']):.4g}/-{abs(eff['kinetic_neg']):.4g}")


def score_case(truth: dict, res: dict) -> dict:
    cause = truth["cause"]
    m = truth["main"]
    out = {"case": truth["case_id"], "cause": cause, "asynchronous": truth["asynchronous"],
           "seconds": round(res["seconds"], 2), "right": False, "verdict": None, "detail": "",
           "truth_param": "", "error": None, "honesty": [], "warnings": [], "extra": {}}
    out["truth_param"] = truth_param_text(truth)
    if res["timed_out"]:
        out["error"] = "timeout"
        out["detail"] = "tool timed out"
        return out
    if res["rc"] != 0 or res["report"] is None:
        msg = (res["stderr"] or res["report_error"] or "").strip().splitlines()
        out["error"] = f"exit {res['rc']}: " + (" | ".join(msg[-3:]) if msg else "(no message)")
        out["detail"] = "tool error"
        return out
    rep = res["report"]
    out["honesty"] = honesty(rep)
    out["warnings"] = suspicious(rep)
    verdict = rep.get("verdict")
    out["verdict"] = verdict
    findings = rep.get("findings") or []
    first = findings[0] if findings else None
    ps = (first or {}).get("parameters") or {}
    named = first is not None and first.get("cause") == cause and verdict == cause
    hs = rep.get("heldout_simulation") or {}
    out["extra"]["heldout_before"] = hs.get("nmae_before")
    out["extra"]["heldout_after"] = hs.get("nmae_after")
    if first is not None:
        out["detail"] = f"{first.get('cause')} " + ", ".join(f"{k}={_fmt(v)}" for k, v in sorted(ps.items()))

    right = False
    note = ""
    if cause == "none":
        right = verdict == "none"
    elif cause == "stiction" and named:
        rs = [_num(ps.get("ratio_pos")), _num(ps.get("ratio_neg"))]
        rs = [r for r in rs if r is not None]
        if rs:
            r = sum(rs) / len(rs)
            right = rel_ok(r, m["ratio"])
            note = f"ratio {r:.3g} vs {m['ratio']:.3g}"
    elif cause == "stribeck_friction" and named:
        rs = []
        for d in ("pos", "neg"):
            st, sl = _num(ps.get(f"static_{d}")), _num(ps.get(f"sliding_{d}"))
            if st is not None and sl:
                rs.append(st / sl)
        if rs:
            r = sum(rs) / len(rs)
            right = rel_ok(r, m["ratio"])
            ve = rel_err(ps.get("stribeck_velocity"), m["stribeck_velocity"])
            out["extra"]["stribeck_velocity_rel_err"] = ve
            note = f"ratio {r:.3g} vs {m['ratio']:.3g}; vs error {_fmt(ve)}"
    elif cause == "localized_friction" and named:
        a, c = _num(ps.get("amplitude_n")), _num(ps.get("center_m"))
        right = rel_ok(a, m["amplitude"]) and c is not None and abs(c - m["center"]) <= m["width"]
        note = f"amp {_fmt(a)} vs {m['amplitude']:.4g}, centre {_fmt(c)} vs {m['center']:.4g} (sigma {m['width']:.3g})"
    elif cause == "input_deadzone" and named:
        right = rel_ok(ps.get("deadband"), m["deadband"])
    elif cause == "input_saturation" and named:
        right = rel_ok(ps.get("saturation"), m["saturation"])
    elif cause == "input_delay" and named:
        d = _num(ps.get("delay_s"))
        if d is None and _num(ps.get("delay_samples")) is not None:
            d = _num(ps.get("delay_samples")) * truth["log_period_s"]
            note = "delay converted from samples at the nominal period"
        right = d is not None and abs(d - m["delay_s"]) <= truth["log_period_s"]
        note = (note + "; " if note else "") + f"delay {_fmt(d)} s vs {m['delay_s']:.4g} s (period {truth['log_period_s']:.3g})"
    elif cause == "restoring_force" and named:
        right = rel_ok(ps.get("stiffness"), m["stiffness"])
    elif cause == "force_offset":
        if named:
            o = _num(ps.get("offset"))
            right = o is not None and o * m["offset"] > 0 and rel_ok(abs(o), abs(m["offset"]))
        if not right and verdict in ("none", "direction_asymmetry", "force_offset"):
            right, note = levels_carry(truth, rep)
            note = "by levels: " + note
    elif cause == "direction_asymmetry":
        if named:
            right = rel_ok(abs(_num(ps.get("kinetic_pos")) or 0), abs(m["kinetic_pos"])) and rel_ok(
                abs(_num(ps.get("kinetic_neg")) or 0), abs(m["kinetic_neg"]))
        if not right and verdict in ("none", "direction_asymmetry", "force_offset"):
            right, note = levels_carry(truth, rep)
            note = "by levels: " + note
    elif cause == "load_dependent_friction" and named:
        right = rel_ok(ps.get("mu"), m["mu"])
    out["right"] = bool(right)
    out["note"] = note
    out["named"] = bool(named) if cause != "none" else verdict == "none"
    return out


def _fmt(v):
    x = _num(v)
    if x is None:
        return str(v)
    return f"{x:.4g}"


def truth_param_text(truth: dict) -> str:
    m = truth["main"]
    c = truth["cause"]
    u = truth["report_force_unit"]
    if c == "none":
        return ""
    if c in ("stiction", "stribeck_friction"):
        s = f"ratio {m['ratio']:.3g}"
        if c == "stribeck_friction":
            s += f", vs {m['stribeck_velocity']:.3g}"
        return s
    if c == "localized_friction":
        return f"amp {m['amplitude']:.4g} {u} at {m['center']:.4g} (sigma {m['width']:.3g})"
    if c == "input_deadzone":
        return f"deadband {m['deadband']:.4g} {truth['input_unit']}"
    if c == "input_saturation":
        return f"saturation {m['saturation']:.4g} {u}"
    if c == "input_delay":
        return f"delay {m['delay_s']:.4g} s"
    if c == "restoring_force":
        return f"{m['kind']} k {m['stiffness']:.4g} {u}"
    if c == "force_offset":
        return f"offset {m['offset']:.4g} {u}"
    if c == "direction_asymmetry":
        return f"Fc +{m['kinetic_pos']:.4g} / -{m['kinetic_neg']:.4g} {u}"
    if c == "load_dependent_friction":
        return f"mu {m['mu']:.3g}"
    return ""


# ---------------------------------------------------------------------------------------------
# Tables


def summarise(rows: list) -> dict:
    import cases as C

    per = {}
    for c in C.CAUSES:
        rs = [r for r in rows if r["cause"] == c]
        if not rs:
            continue
        sy = [r for r in rs if not r["asynchronous"]]
        asy = [r for r in rs if r["asynchronous"]]
        per[c] = {
            "right": sum(r["right"] for r in rs), "total": len(rs),
            "sync_right": sum(r["right"] for r in sy), "sync_total": len(sy),
            "async_right": sum(r["right"] for r in asy), "async_total": len(asy),
            "named": sum(bool(r.get("named")) for r in rs),
            "verdict_none": sum(r["verdict"] == "none" for r in rs),
            "verdict_unexplained": sum(r["verdict"] == "unexplained" for r in rs),
            "verdict_other_cause": sum(r["verdict"] not in (None, "none", "unexplained", c) for r in rs),
            "errors": sum(r["error"] is not None for r in rs),
            "seconds_total": round(sum(r["seconds"] for r in rs), 1),
        }
    tot = {
        "right": sum(r["right"] for r in rows), "total": len(rows),
        "sync_right": sum(r["right"] for r in rows if not r["asynchronous"]),
        "sync_total": sum(not r["asynchronous"] for r in rows),
        "async_right": sum(r["right"] for r in rows if r["asynchronous"]),
        "async_total": sum(r["asynchronous"] for r in rows),
        "errors": sum(r["error"] is not None for r in rows),
        "timeouts": sum(r["error"] == "timeout" for r in rows),
        "honesty_failures": sum(len(r["honesty"]) for r in rows),
        "unphysical_warnings": sum(len(r.get("warnings", [])) for r in rows),
    }
    return {"per_cause": per, "total": tot}


def markdown(rows: list, summ: dict, meta: dict) -> str:
    L = ["# crane diagnose on stranger rigs", ""]
    L.append(f"binary `{meta['binary']}`, {meta['cases']} cases, generation {meta['gen_seconds']:.1f} s, "
             f"scoring {meta['score_seconds']:.1f} s with {meta['jobs']} jobs")
    L += ["", "| cause | right / total | sync | async | named first | verdict none | unexplained | other cause | tool errors | tool s |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for c, s in summ["per_cause"].items():
        L.append(f"| {c} | {s['right']} / {s['total']} | {s['sync_right']} / {s['sync_total']} | "
                 f"{s['async_right']} / {s['async_total']} | {s['named']} | {s['verdict_none']} | "
                 f"{s['verdict_unexplained']} | {s['verdict_other_cause']} | {s['errors']} | {s['seconds_total']} |")
    t = summ["total"]
    L.append(f"| **total** | **{t['right']} / {t['total']}** | {t['sync_right']} / {t['sync_total']} | "
             f"{t['async_right']} / {t['async_total']} | | | | | {t['errors']} | |")
    L.append("")
    L.append("named first: the verdict is the true cause, whatever its parameter (for `none`: verdict `none`).")
    L += ["", f"Honesty failures: {t['honesty_failures']}", ""]
    for r in rows:
        for h in r["honesty"]:
            L.append(f"- {r['case']} ({r['cause']}): {h}")
    nw = sum(len(r.get("warnings", [])) for r in rows)
    L += ["", f"Unphysical finding parameters (not asserted): {nw}", ""]
    for r in rows:
        for w in r.get("warnings", []):
            L.append(f"- {r['case']} ({r['cause']}): {w}")
    L += ["", "| case | truth | log | verdict | reported | right | s |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        rep = r["error"] or (r["detail"] + (f" ({r['note']})" if r.get("note") else ""))
        L.append(f"| {r['case']} | {r['cause']} {r['truth_param']} | {'async' if r['asynchronous'] else 'sync'} | "
                 f"{r['verdict']} | {rep} | {'yes' if r['right'] else 'NO'} | {r['seconds']} |")
    return "\n".join(L) + "\n"


def main(argv=None):
    import cases as C

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--cases", type=int, default=None)
    g.add_argument("--only", default=None, choices=C.CAUSES)
    ap.add_argument("--seed", type=int, default=None,
                    help="master seed of the cases (default: cases.py's; another one draws cases never scored before)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--markdown", default=None)
    ap.add_argument("--json", dest="json_out", default=None)
    ap.add_argument("--no-generate", action="store_true", help="score the cases already in --out")
    ap.add_argument("--reuse-reports", action="store_true",
                    help="with --no-generate: score the reports of an earlier run instead of running the tool")
    a = ap.parse_args(argv)

    C.set_seed(a.seed)
    binary = crane_bin()
    if a.reuse_reports and not a.no_generate:
        ap.error("--reuse-reports needs --no-generate")
    if not os.path.exists(binary):
        print(f"error: crane binary not found at {binary} (set CRANE_BIN)", file=sys.stderr)
        return 2
    t0 = time.time()
    if not a.no_generate:
        C.generate(a.out, a.only, a.cases)
    gen_s = time.time() - t0
    wanted = {cid for _, _, cid in C.case_list(a.only, a.cases)}
    dirs = sorted(d for d in os.listdir(a.out)
                  if d in wanted and os.path.exists(os.path.join(a.out, d, "truth.json")))
    truths = {}
    for d in dirs:
        with open(os.path.join(a.out, d, "truth.json")) as f:
            truths[d] = json.load(f)

    t1 = time.time()
    rows = []

    def one(d):
        res = load_run(os.path.join(a.out, d)) if a.reuse_reports else None
        if res is None:
            res = run_case(os.path.join(a.out, d), binary, a.timeout)
        return score_case(truths[d], res)

    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        # the likely slow ones (asynchronous, many rows) first: a shorter makespan
        order = sorted(dirs, key=lambda d: (not truths[d]["asynchronous"], -truths[d].get("rows", 0)))
        futs = [ex.submit(one, d) for d in order]
        for fut in as_completed(futs):
            r = fut.result()
            rows.append(r)
            rep = r["error"] or r["detail"]
            print(f"{r['case']}  {r['cause']:<24} {r['truth_param']:<40} -> {str(r['verdict']):<24} "
                  f"{rep[:70]:<70} {'RIGHT' if r['right'] else 'wrong'} {r['seconds']:6.2f}s"
                  + (f"  [{r['note']}]" if r.get("note") else ""), flush=True)
    score_s = time.time() - t1
    rows.sort(key=lambda r: r["case"])
    summ = summarise(rows)
    meta = {"binary": binary, "cases": len(rows), "gen_seconds": gen_s, "score_seconds": score_s,
            "jobs": a.jobs}
    md = markdown(rows, summ, meta)
    print()
    print("\n".join(md.splitlines()[2 : 6 + len(summ["per_cause"]) + 3]))
    t = summ["total"]
    print(f"\nhonesty failures: {t['honesty_failures']}")
    for r in rows:
        for h in r["honesty"]:
            print(f"  {r['case']} ({r['cause']}): {h}")
    for r in rows:
        for w in r.get("warnings", []):
            print(f"  unphysical (not asserted) {r['case']} ({r['cause']}): {w}")
    print(f"generation {gen_s:.1f} s, scoring {score_s:.1f} s")
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(md)
    if a.json_out:
        with open(a.json_out, "w") as f:
            json.dump({"meta": meta, "summary": summ, "cases": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
