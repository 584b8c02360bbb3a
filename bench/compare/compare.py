#!/usr/bin/python3
"""hnn against PyTorch and LibTorch on the same training steps (bench/compare/README.md).

Builds hnn_train_step (and libtorch_step, in its own folder, when LibTorch is installed),
writes each task's data and hnn's initial parameters once, then runs every case with hnn,
PyTorch and LibTorch alternating, for N rounds, at each thread count, in the tuned environment
(OpenBLAS OpenMP build, OPENBLAS_CORETYPE, glibc malloc tunables). Prints a table of median
ms/step and torch/hnn ratios and writes it as JSON and Markdown. A separate check trains the
spring HNN for the full 2000 steps with all three on the reference data and compares the final
losses. Uses only the standard library: run it with any python3; the PyTorch side runs under
/usr/bin/python3 (Debian's python3-torch). Skips PyTorch or LibTorch (message, exit 0) when
they are missing.
"""
import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

from report import IMPLS, best_against_best, markdown, summarise

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
OPENBLAS_OPENMP = "/usr/lib/x86_64-linux-gnu/openblas-openmp"
MALLOC_TUNABLES = "glibc.malloc.mmap_threshold=16777216:glibc.malloc.trim_threshold=268435456"

# name: (task, model, dtype, timing steps[, options of every program]). Steps are short enough
# for a shared machine; the spring loss check runs the full 2000 separately.
CASES = {
    "spring-hnn-f32": ("spring", "hnn", "float32", 400),
    "spring-hnn-f64": ("spring", "hnn", "float64", 400),
    "spring-baseline-f32": ("spring", "baseline", "float32", 400),
    "twobody-hnn-f32": ("twobody", "hnn", "float32", 1000),
    "twobody-hnn-f64": ("twobody", "hnn", "float64", 1000),
    "twobody-baseline-f32": ("twobody", "baseline", "float32", 1000),
    "threebody-hnn-f32": ("threebody", "hnn", "float32", 400),
    "threebody-baseline-f32": ("threebody", "baseline", "float32", 400),
    "pixel-hnn-f32": ("pixel", "hnn", "float32", 150),
    "pixel-baseline-f32": ("pixel", "baseline", "float32", 150),
}
# The peers' models at the peers' sizes (issue 18, "Speed"); PyTorch only (torch_peers.py).
_DHNN = {"hidden": "256,256", "batch": 128, "lr": 5e-3, "weight-decay": 0}  # Sosanya & Greydanus
_LNN = {"hidden": "600,600,600", "activation": "softplus", "batch": 512, "lr": 1e-3,
        "weight-decay": 0}  # Cranmer et al.
_LNN_SMALL = dict(_LNN, hidden="128,128")  # hnn's double-pendulum widths
_ROLLOUT = {"loss": "rollout", "horizon": 4, "integrator": "leapfrog", "batch": 128, "lr": 1e-3,
            "weight-decay": 1e-4}
# Finzi et al.'s CHNN protocol (pl_trainer.py): 3 x 256, chunks of 5 states through RK4, L1,
# AdamW at 3e-3 with weight decay 1e-4, batch 200.
_CHNN = {"hidden": "256,256,256", "loss": "rollout", "horizon": 4, "integrator": "rk4",
         "norm": "l1", "optimizer": "adamw", "batch": 200, "lr": 3e-3, "weight-decay": 1e-4}
PEERS = {
    "realpend-dhnn-f32": ("realpend", "dhnn", "float32", 400, _DHNN),
    "realpend-dhnn-f64": ("realpend", "dhnn", "float64", 400, _DHNN),
    "dblpend-lnn-f32": ("dblpend", "lnn", "float32", 40, _LNN),
    "dblpend-lnn-f64": ("dblpend", "lnn", "float64", 40, _LNN),
    "dblpend-lnn-small-f32": ("dblpend", "lnn", "float32", 200, _LNN_SMALL),
    "dblpend-lnn-small-f64": ("dblpend", "lnn", "float64", 200, _LNN_SMALL),
    "spring-rollout-f32": ("spring", "hnn", "float32", 200, _ROLLOUT),
    "spring-rollout-f64": ("spring", "hnn", "float64", 200, _ROLLOUT),
    "chain2-chnn-f32": ("chain2", "chnn", "float32", 30, _CHNN),
    "chain2-chnn-f64": ("chain2", "chnn", "float64", 30, _CHNN),
}
CASES.update(PEERS)
QUICK = ["spring-hnn-f32", "spring-hnn-f64", "twobody-hnn-f32", "threebody-hnn-f32",
         "pixel-hnn-f32"]
GROUPS = {"all": list(CASES), "quick": QUICK, "peers": [c for c in PEERS if c.endswith("f32")]}


def expand_cases(names):
    """The cases of a --cases value: case names and groups mixed ('peers,spring-hnn-f64'), each
    case once, in order; exits naming an unknown one."""
    cases = list(dict.fromkeys(c for name in names.split(",") for c in GROUPS.get(name, [name])))
    for c in cases:
        if c not in CASES:
            sys.exit(f"unknown case {c}; known: {', '.join(CASES)}, and the groups "
                     f"{', '.join(GROUPS)}")
    return cases


def case_options(case):
    """The options a case passes to every program besides task, model and dtype."""
    extra = CASES[case][4] if len(CASES[case]) > 4 else {}
    return [str(v) for key, value in extra.items() for v in (f"--{key}", value)]


def log(*args):
    print(*args, file=sys.stderr, flush=True)


def tuned_env(args, threads):
    env = dict(os.environ)
    # auto: OpenBLAS picks the kernels for this CPU itself (undoing a machine's exported choice).
    env.pop("OPENBLAS_CORETYPE", None)
    if args.coretype != "auto":
        env["OPENBLAS_CORETYPE"] = args.coretype
    env.update(OMP_NUM_THREADS=str(threads),
               OPENBLAS_NUM_THREADS=str(threads), MKL_NUM_THREADS=str(threads),
               GLIBC_TUNABLES=MALLOC_TUNABLES)
    if Path(OPENBLAS_OPENMP).is_dir():
        env["LD_LIBRARY_PATH"] = OPENBLAS_OPENMP + (
            ":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    return env


def sh(cmd, **kw):
    log("+", " ".join(str(c) for c in cmd))
    return subprocess.run([str(c) for c in cmd], **kw)


# ---- building -----------------------------------------------------------------------------
def build(args):
    """hnn_train_step in build_dir; libtorch_step in build_dir/libtorch (None when absent)."""
    b = Path(args.build_dir)
    hnn = b / "bench" / "compare" / "hnn_train_step"
    if not args.no_build:
        if not (b / "CMakeCache.txt").exists():
            sh(["nice", "cmake", "-S", ROOT, "-B", b, "-DCMAKE_BUILD_TYPE=Release",
                "-DHNN_BUILD_TESTS=OFF"], check=True)
        sh(["nice", "cmake", "--build", b, "-j2", "--target", "hnn_train_step"], check=True)
    libtorch = b / "libtorch" / "libtorch_step"
    if "libtorch" in args.impls and not args.no_build:
        configured = sh(["nice", "cmake", "-S", HERE / "libtorch", "-B", b / "libtorch",
                         "-DCMAKE_BUILD_TYPE=Release"], capture_output=True, text=True)
        if configured.returncode != 0:
            log("LibTorch not found (find_package(Torch) failed; Debian: libtorch-dev): skipping it")
            return hnn, None
        sh(["nice", "cmake", "--build", b / "libtorch", "-j2"], check=True)
    return hnn, libtorch if libtorch.exists() else None


def torch_available(args):
    try:
        probe = subprocess.run([args.python, "-c", "import torch, numpy"], capture_output=True,
                               env=tuned_env(args, 1))
    except OSError:  # no such interpreter
        probe = subprocess.CompletedProcess(args.python, 1)
    if probe.returncode != 0:
        log(f"PyTorch not importable by {args.python} (Debian: python3-torch): skipping it")
    return probe.returncode == 0


# ---- data and initial parameters -----------------------------------------------------------
def run_json(cmd, env, timeout=None):
    out = sh(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    if out.returncode != 0:
        raise RuntimeError(f"{cmd[0]} failed ({out.returncode}): {out.stderr.strip()[-2000:]}")
    lines = [l for l in out.stdout.splitlines() if l.startswith("{")]
    if not lines:
        raise RuntimeError(f"{cmd[0]} printed no JSON: {out.stderr.strip()[-2000:]}")
    return json.loads(lines[-1])


def prepare(args, hnn, cases, out):
    """Per task the data file and its sizes; per case hnn's initial parameters."""
    env = tuned_env(args, 1)
    prep = out / "inputs"
    prep.mkdir(parents=True, exist_ok=True)
    data, inits = {}, {}
    for name in cases:
        task, model, dtype = CASES[name][:3]
        if task not in data:
            if task == "spring" and Path(args.spring_data).exists():
                data[task] = {"path": str(Path(args.spring_data).resolve()), "n_train": 750,
                              "n_test": 750}
            else:
                path = prep / f"{task}.f64"
                # The case's model and options: chain2 runs only its CHNN (the data do not
                # depend on them).
                r = run_json([hnn, "--task", task, "--model", model, "--steps", 2, "--warmup", 1,
                              "--window", 1, "--save-data", path] + case_options(name), env)
                data[task] = {"path": str(path), "n_train": r["n_train"], "n_test": r["n_test"]}
        init = prep / f"{name}.init"
        d = data[task]
        run_json([hnn, "--task", task, "--model", model, "--dtype", dtype, "--steps", 2,
                  "--warmup", 1, "--window", 1, "--data", d["path"], "--n-train", d["n_train"],
                  "--n-test", d["n_test"], "--save-init", init] + case_options(name), env)
        inits[name] = str(init)
    return data, inits


def command(impl, progs, args, case, data, init, threads, steps):
    task, model, dtype = CASES[case][:3]
    common = ["--task", task, "--model", model, "--dtype", dtype, "--threads", threads,
              "--steps", steps, "--data", data["path"], "--n-train", data["n_train"],
              "--n-test", data["n_test"]] + case_options(case)
    if impl == "hnn":
        return [progs["hnn"]] + common
    if impl == "pytorch":
        return [args.python, HERE / "torch_step.py"] + common + ["--init", init]
    return [progs["libtorch"]] + common + ["--init", init]


# ---- the runs -----------------------------------------------------------------------------
def time_cases(args, progs, cases, data, inits):
    """Every case at every thread count with every implementation, in alternation: within a
    round each case runs at each thread count in turn, so a change in the machine's load
    shows in both thread counts alike."""
    runs = []
    impls = [i for i in IMPLS if i in progs]
    for rnd in range(args.rounds):
        for case in cases:
            # Rotate the orders each round so no run always follows the same neighbour.
            threads_order = args.threads[rnd % len(args.threads):] + args.threads[:rnd % len(args.threads)]
            for threads in threads_order:
                order = impls[rnd % len(impls):] + impls[:rnd % len(impls)]
                steps = max(20, int(CASES[case][3] * args.steps_scale))
                for impl in order:
                    if impl == "libtorch" and case in PEERS:
                        continue
                    r = time_one(args, progs, case, data, inits, impl, threads, steps)
                    if r is not None:
                        r.update(round=rnd)
                        runs.append(r)
    return runs


def time_one(args, progs, case, data, inits, impl, threads, steps):
    cmd = command(impl, progs, args, case, data[CASES[case][0]], inits[case], threads, steps)
    load = os.getloadavg()[0]
    try:
        r = run_json(cmd, tuned_env(args, threads), timeout=args.timeout)
    except (RuntimeError, subprocess.TimeoutExpired) as error:
        log(f"  {impl} {case}: {error}")
        return None
    r.update(case=case, load_before=load)
    log(f"  {case:24s} t={threads} {impl:9s} {r['ms_per_step']:9.3f} ms/step  "
        f"train {r['train_loss']:.6g}  load {load:.1f}")
    return r


def peer_checks(cases):
    """The float64 twins of the peers' cases timed: their runs check the same computation."""
    return [c.replace("-f32", "-f64") for c in cases if c in PEERS and c.endswith("-f32")]


def peer_loss_check(args, progs, data, inits, cases):
    """Each peer case in float64 from hnn's initial parameters, its timing steps, every
    implementation once: the final losses agree to rounding (Note [Same computation])."""
    env = tuned_env(args, args.loss_threads)
    checks = []
    for case in peer_checks(cases):
        steps = max(20, int(CASES[case][3] * args.steps_scale))
        for impl in (i for i in IMPLS if i in progs and i != "libtorch"):
            cmd = command(impl, progs, args, case, data[CASES[case][0]], inits[case],
                          args.loss_threads, steps)
            try:
                r = run_json(cmd, env, timeout=args.timeout * 5)
            except (RuntimeError, subprocess.TimeoutExpired) as error:
                log(f"  loss check {impl} {case}: {error}")
                continue
            log(f"  loss check {impl:9s} {case}: train {r['train_loss']!r} test {r['test_loss']!r}")
            r.update(case=case)
            checks.append(r)
    return checks


def loss_check(args, progs, data, out, cases):
    """Spring HNN, full 2000 steps, f32 and f64, each implementation once (when a spring HNN
    case is timed)."""
    if "spring" not in data or not {"spring-hnn-f32", "spring-hnn-f64"} & set(cases):
        return []
    env = tuned_env(args, args.loss_threads)
    checks = []
    for dtype in ("float32", "float64"):
        case = f"spring-hnn-{'f32' if dtype == 'float32' else 'f64'}"
        init = out / "inputs" / f"{case}.init"
        if not init.exists():
            continue
        for impl in (i for i in IMPLS if i in progs):
            cmd = command(impl, progs, args, case, data["spring"], str(init), args.loss_threads,
                          2000)
            try:
                r = run_json(cmd, env, timeout=args.timeout * 5)
            except (RuntimeError, subprocess.TimeoutExpired) as error:
                log(f"  loss check {impl} {dtype}: {error}")
                continue
            log(f"  loss check {impl:9s} {dtype}: train {r['train_loss']:.6g} "
                f"test {r['test_loss']:.6g}")
            checks.append(r)
    return checks


def cpuinfo(field):
    """The first value of a /proc/cpuinfo field, or None."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key.strip() == field:
                    return value.strip()
    except OSError:
        pass
    return None


def machine(args):
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True).stdout.strip()
    return {"date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
            "cpu": cpuinfo("model name") or platform.processor() or "unknown CPU",
            "cpu_family": cpuinfo("cpu family"), "cpu_model": cpuinfo("model"),
            "cpus": os.cpu_count(), "commit": commit + ("+local changes" if dirty else ""),
            "load_start": os.getloadavg()[0], "rounds": args.rounds}


AVX512_CORES = {"SkylakeX", "Cooperlake", "SapphireRapids"}


def blas_core(args, hnn):
    """The kernels OpenBLAS runs in the runs' environment: the name of its OPENBLAS_VERBOSE=2
    line 'Core: NAME', None for a BLAS that prints none. Exits when OpenBLAS ignores --coretype:
    Debian's 0.3.21 answers OPENBLAS_CORETYPE=Cooperlake with 'Core not found' and runs Haswell's
    AVX2 kernels on every CPU (OpenBLAS pull request 3806 fixed that later), so a run forced to
    Cooperlake would have been recorded as AVX-512 while both sides ran AVX2."""
    env = dict(tuned_env(args, 1), OPENBLAS_VERBOSE="2")
    run = subprocess.run([str(hnn), "--fma-peak", "float32", "--threads", "1"], env=env,
                         capture_output=True, text=True)
    text = run.stdout + run.stderr
    core = re.search(r"^Core: (\S+)", text, re.M)
    if "Core not found" in text:
        sys.exit(f"compare.py: --coretype {args.coretype}: this OpenBLAS has no such core (it ran"
                 f" {core.group(1) if core else 'another'} instead); leave --coretype at auto, or"
                 " name one it has")
    core = core.group(1) if core else None
    if core in AVX512_CORES and "avx512f" not in (cpuinfo("flags") or "").split():
        sys.exit(f"compare.py: --coretype {args.coretype}: OpenBLAS's {core} kernels need AVX-512,"
                 " which this CPU has not; leave --coretype at auto")
    return core


def env_line(args, core):
    picked = "its own pick" if args.coretype == "auto" else f"OPENBLAS_CORETYPE={args.coretype}"
    return f"OpenBLAS core {core or 'not reported'} ({picked}), openblas-openmp, malloc tunables"


def fma_peaks(args, hnn):
    """The machine's FMA peak in GFLOP/s per dtype and thread count, measured by hnn_train_step
    (a register-only FMA loop, bench/fma_peak.h): the steps' fractions of peak divide by it."""
    peaks = {}
    for dtype in ("float32", "float64"):
        for threads in args.threads:
            r = run_json([hnn, "--fma-peak", dtype, "--threads", threads], tuned_env(args, threads))
            peaks.setdefault(dtype, {})[str(threads)] = r["fma_peak_gflops"]
    return peaks


def merge_peaks(start, end):
    """The peak is the higher of the reads before and after the runs (a shared machine once gave
    both threads one core for a whole read: 49 GFLOP/s for 2 threads, 98 on the next read);
    both reads are kept, so the report can say when they disagree."""
    return {dtype: {t: max(v, end[dtype][t]) for t, v in by.items()} for dtype, by in start.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir", default=str(ROOT / "build-compare"))
    ap.add_argument("--out", default=str(HERE / "results"), help="results folder")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", default="2,1", help="thread counts, e.g. 2,1")
    ap.add_argument("--cases", default="all",
                    help="comma-separated case names and groups ('all', 'quick', 'peers'): "
                    + ", ".join(CASES))
    ap.add_argument("--impls", default=",".join(IMPLS))
    ap.add_argument("--steps-scale", type=float, default=1.0, help="scales the timing steps")
    ap.add_argument("--spring-data",
                    default=str(Path(__file__).resolve().parent / "data" / "spring_seed0.f64"))
    ap.add_argument("--coretype", default="auto",
                    help="OPENBLAS_CORETYPE for the runs; auto: the one OpenBLAS picks itself")
    ap.add_argument("--python", default="/usr/bin/python3", help="interpreter with torch")
    ap.add_argument("--timeout", type=float, default=900, help="seconds per timing run")
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--no-loss-check", action="store_true")
    ap.add_argument("--loss-threads", type=int, default=1,
                    help="threads of the spring loss check (its figures are not timings)")
    args = ap.parse_args()
    args.threads = [int(t) for t in args.threads.split(",")]
    args.impls = args.impls.split(",")
    cases = expand_cases(args.cases)

    meta = machine(args)
    hnn, libtorch = build(args)
    meta["blas_core"] = blas_core(args, hnn)
    meta["env"] = env_line(args, meta["blas_core"])
    # Which BLAS each C++ program resolves in the runs' environment (Note: LD_LIBRARY_PATH picks
    # the OpenMP OpenBLAS over a linked pthreads one unless an RPATH says otherwise).
    for name, prog in (("hnn_blas", hnn), ("libtorch_blas", libtorch)):
        if prog is not None:
            ldd = subprocess.run(["ldd", prog], capture_output=True, text=True,
                                 env=tuned_env(args, 1)).stdout
            meta[name] = [l.strip() for l in ldd.splitlines() if "blas" in l.lower()]
    progs = {"hnn": hnn}
    if "pytorch" in args.impls and torch_available(args):
        progs["pytorch"] = None
    if libtorch is not None and "libtorch" in args.impls:
        progs["libtorch"] = libtorch
    if len(progs) == 1:
        log("Neither PyTorch nor LibTorch is available: nothing to compare against; skipping.")
        return 0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    checked = [] if args.no_loss_check else peer_checks(cases)
    data, inits = prepare(args, hnn, cases + [c for c in checked if c not in cases], out)
    peaks_start = fma_peaks(args, hnn)
    started = time.time()
    runs = time_cases(args, progs, cases, data, inits)
    meta["fma_peak_reads"] = {"start": peaks_start, "end": fma_peaks(args, hnn)}
    meta["fma_peak_gflops"] = merge_peaks(peaks_start, meta["fma_peak_reads"]["end"])
    checks = [] if args.no_loss_check else loss_check(args, progs, data, out, cases)
    peers_checked = [] if args.no_loss_check else peer_loss_check(args, progs, data, inits, cases)
    meta.update(load_end=os.getloadavg()[0], minutes=(time.time() - started) / 60,
                impls=[i for i in IMPLS if i in progs])
    rows = summarise(runs, cases, args.threads, meta["fma_peak_gflops"])
    best = best_against_best(rows, cases)
    report = markdown(meta, rows, best, checks, peers_checked)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    result = {"meta": meta, "summary": rows, "best": best, "loss_check": checks,
              "peer_loss_check": peers_checked, "runs": runs}
    for name in (f"compare-{stamp}", "latest"):
        (out / f"{name}.json").write_text(json.dumps(result, indent=1) + "\n")
        (out / f"{name}.md").write_text(report)
    print(report)
    log(f"written: {out}/compare-{stamp}.{{json,md}} and latest.{{json,md}}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
