#!/usr/bin/python3
"""hnn sweep's driver: runs a sweep's plan (OUT/plan.json, written by `hnn sweep`) through Dask
distributed, one `hnn train` process per run, and gathers the table.

Usage (hnn sweep runs it; it holds OUT/sweep.lock, which hnn sweep took):
  sweep_driver.py run|collect|emit-slurm OUT/plan.json

run: every run without a complete metrics.json is submitted to a Dask cluster (a LocalCluster
with one single-threaded worker per --threads-per-run cores, or the --scheduler's workers, which
must see OUT at the same path). A run with a checkpoint resumes from it (`hnn train --resume`),
so a run whose worker died goes on elsewhere from its last checkpoint; Dask resubmits it. A run
that fails for its own reasons (exit 1, "hnn: error: ...") is reported with that line and does
not stop the sweep. Each run appends its events to OUT/events.jsonl. A plan written by
A plan may name a "report_module" (`hnn compare`'s: apps/hnn/compare/compare_report.py), a Python
file whose write(plan, table) is called after the table, each path it returns printed.
"""

import json
import logging
import os
import signal
import sys
import time
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sweep_report  # noqa: E402  (beside this file, in the source tree and in share/hnn)

STATUS_EVERY = 30.0  # seconds between status lines when no run ends
STATUS_GAP = 2.0  # at least this many seconds between status lines as runs end


# ---- one run, on a worker -------------------------------------------------------------------
# run_one is pickled by value (it lives in __main__), so workers need only Python and Dask.

def run_one(hnn, out, name, args, threads):
    """Trains run `name` (or resumes it from its checkpoint) unless it is finished. Returns
    {"status": "done"|"failed", ...}; raises when the process was killed, so that Dask retries."""
    import fcntl
    import json as _json
    import os as _os
    import shutil as _shutil
    import socket as _socket
    import subprocess as _subprocess
    import time as _time
    try:
        from distributed import get_worker
        worker = get_worker().name
    except Exception:  # noqa: BLE001  (called outside a worker: the sequential fallback)
        worker = None
    run = _os.path.join(out, "runs", name)
    host = _socket.gethostname()

    def log(event, **extra):
        line = _json.dumps({"event": event, "run": name, "host": host, "worker": str(worker),
                            "pid": _os.getpid(), "time": _time.time(), **extra})
        with open(_os.path.join(out, "events.jsonl"), "a") as f:
            f.write(line + "\n")

    def finished():
        try:
            with open(_os.path.join(run, "metrics.json")) as f:
                return isinstance(_json.load(f), dict)
        except (OSError, ValueError):
            return False

    locks = _os.path.join(out, "locks")
    _os.makedirs(locks, exist_ok=True)
    with open(_os.path.join(locks, name.replace("/", "+") + ".lock"), "w") as lock:
        # Held by this task and passed to hnn train: a retry waits for any earlier attempt.
        fcntl.flock(lock, fcntl.LOCK_EX)
        if finished():
            log("found-done")
            return {"status": "done", "skipped": True, "host": host, "worker": str(worker)}
        resume = _os.path.exists(_os.path.join(run, "checkpoint", "state.json"))
        failed_file = _os.path.join(run, "sweep_failed.txt")
        if not resume and _os.path.exists(failed_file):
            _os.remove(failed_file)  # retried: hnn train starts only in a folder holding nothing
        cmd = ([hnn, "train", "--resume", run] if resume else [hnn, "train", *args, "--out", run])
        cmd += ["--threads", str(threads), "--quiet"]
        if _shutil.which("setpriv"):  # the run dies with its worker, not orphaned beside a retry
            cmd = ["setpriv", "--pdeathsig", "KILL", "--"] + cmd
        log("resume" if resume else "start")
        start = _time.time()
        proc = _subprocess.run(cmd, stdout=_subprocess.DEVNULL, stderr=_subprocess.PIPE,
                               text=True, pass_fds=(lock.fileno(),))
        seconds = _time.time() - start
        lines = [l for l in proc.stderr.splitlines() if l.strip()]
        reason = next((l for l in reversed(lines) if l.startswith("hnn: error:")),
                      lines[-1] if lines else "")
        reason = reason.replace("hnn: error: ", "", 1)
        if proc.returncode == 0 and finished():
            info = {"host": host, "worker": str(worker), "seconds": seconds, "resumed": resume}
            with open(_os.path.join(run, "sweep.json"), "w") as f:
                _json.dump(info, f)
            if _os.path.exists(failed_file):
                _os.remove(failed_file)
            log("done", seconds=seconds)
            return {"status": "done", "skipped": False, **info}
        if proc.returncode == 1:  # the run's own failure: bad settings, data or divergence
            _os.makedirs(run, exist_ok=True)
            with open(failed_file, "w") as f:
                f.write(reason + "\n")
            log("failed", reason=reason)
            return {"status": "failed", "reason": reason, "host": host, "worker": str(worker)}
        log("interrupted", code=proc.returncode, reason=reason)
        raise RuntimeError(f"hnn train exited with {proc.returncode}"
                           + (f": {reason}" if reason else " (killed)"))


# ---- the sweep, on the driver ---------------------------------------------------------------

def say(text):
    print(f"hnn sweep: {text}", flush=True)


def fail(text):
    print(f"hnn: error: sweep: {text}", file=sys.stderr, flush=True)
    sys.exit(1)


def check_folders_hold_their_runs(plan):
    """A run folder under OUT must hold the run the spec asks for (a changed default or spec
    would otherwise be skipped as finished, or resumed with the old settings)."""
    for r in plan["runs"]:
        folder = os.path.join(plan["out"], "runs", r["name"])
        held = sweep_report.read_json(os.path.join(folder, "metrics.json"))
        if held is None:
            state = sweep_report.read_json(os.path.join(folder, "checkpoint", "state.json"))
            held = state.get("run") if isinstance(state, dict) else None
        if not isinstance(held, dict):
            continue
        for key, want in r["settings"].items():
            if key in held and held[key] != want:
                fail(f"run folder '{folder}' holds another run ({key} {json.dumps(held[key])}, "
                     f"the spec's {json.dumps(want)}): delete it, or give another --out")


def work_estimate(settings):
    """A run's work, roughly: steps x the hidden layers' weights. Dask starts the larger runs
    first (its priority), so that a long run does not start last and leave the other workers
    idle at the end."""
    widths = [int(w) for w in str(settings.get("hidden", "1")).split("-")]
    weights = sum(a * b for a, b in zip(widths, widths[1:])) + 10 * sum(widths)
    return int(settings.get("steps", 1)) * weights


def start_client(plan):
    """A Dask client: of the --scheduler's cluster, or of a new LocalCluster."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        fail("Dask distributed is not installed (Debian: apt-get install python3-distributed; "
             "scripts/setup.sh installs it)")
    opts = plan["options"]
    if opts["scheduler"]:
        try:
            client = Client(opts["scheduler"], timeout="20s")
        except OSError as e:
            fail(f"cannot reach the Dask scheduler {opts['scheduler']}: {e}")
        return client, None
    cores = len(os.sched_getaffinity(0))
    workers = opts["workers"] or max(1, cores // opts["threads_per_run"])
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.ERROR,
                           local_directory=os.path.join(plan["out"], ".dask"))
    return Client(cluster), cluster


def time_left(durations, remaining, slots):
    if not durations:
        return "time left unknown until a run ends"
    seconds = sum(durations) / len(durations) * remaining / max(1, slots)
    if seconds < 120:
        return f"about {seconds:.0f} s left"
    return f"about {seconds / 60:.0f} min left" if seconds < 7200 else \
        f"about {seconds / 3600:.1f} h left"


class Progress:
    """The command line's view: runs done, running, failed, and time left."""

    def __init__(self, client, total, done_before, failed_before):
        self.client, self.total = client, total
        self.done, self.failed = done_before, failed_before
        self.durations = []
        self.last = 0.0

    def running(self):
        try:
            processing = self.client.processing()
            nthreads = self.client.nthreads()
            return sum(min(len(keys), nthreads.get(w, 1)) for w, keys in processing.items()), \
                sum(nthreads.values())
        except Exception:  # noqa: BLE001  (the scheduler is busy or going: no count this time)
            return 0, 1

    def line(self, note=""):
        running, slots = self.running()
        remaining = self.total - self.done - self.failed
        left = f", {time_left(self.durations, remaining, slots)}" if remaining else ""
        say(f"{self.done}/{self.total} done, {running} running, {self.failed} failed{left}"
            + (f"  ({note})" if note else ""))
        self.last = time.time()


def run_sweep(plan):
    runs, out = plan["runs"], plan["out"]
    check_folders_hold_their_runs(plan)
    state = {r["name"]: sweep_report.run_state(out, r["name"]) for r in runs}
    retry = plan["options"]["retry_failed"]
    todo = [r for r in runs if state[r["name"]][0] == "pending"
            or (retry and state[r["name"]][0] == "failed")]
    done_before = sum(1 for s, _ in state.values() if s == "done")
    failed_before = 0 if retry else sum(1 for s, _ in state.values() if s == "failed")
    if not todo:
        say(f"all {len(runs)} runs are finished ({failed_before} failed): nothing to run")
        return finish(plan)
    say(f"{len(runs)} runs, {done_before} finished, {len(todo)} to run"
        + (f", {failed_before} failed before (--retry-failed runs them again)"
           if failed_before else ""))

    from distributed import as_completed
    client, cluster = start_client(plan)
    link = dashboard_link(client)
    say(f"Dask scheduler {client.scheduler.address}, {len(client.nthreads())} workers; "
        + (f"dashboard {link}" if link else "no dashboard"))
    threads = plan["options"]["threads_per_run"]
    futures = {}
    # Largest first: the first runs go to the workers as soon as they are submitted.
    for r in sorted(todo, key=lambda r: -work_estimate(r["settings"])):
        f = client.submit(run_one, plan["hnn"], out, r["name"], r["args"], threads,
                          key=f"hnn-train-{r['name']}", pure=False, retries=2,
                          priority=work_estimate(r["settings"]))
        futures[f] = r["name"]
    progress = Progress(client, len(runs), done_before, failed_before)
    pending = as_completed(list(futures), with_results=False)
    try:
        while not pending.is_empty():
            finished = pending.next_batch(block=False)
            if not finished:
                if time.time() - progress.last > STATUS_EVERY:
                    progress.line()
                time.sleep(0.2)
                continue
            note = ""
            for f in finished:
                name = futures[f]
                try:
                    result = f.result()
                except Exception as e:  # noqa: BLE001  (killed too often, or crashed)
                    result = {"status": "failed", "reason": one_line(e)}
                if result["status"] == "done":
                    progress.done += 1
                    if not result.get("skipped"):
                        progress.durations.append(result["seconds"])
                    note = f"{name}: " + ("finished before" if result.get("skipped") else
                                          f"{result['seconds']:.1f} s on {result['worker']}"
                                          + (", resumed" if result["resumed"] else ""))
                else:
                    progress.failed += 1
                    progress.line(f"{name} failed: {result['reason']}")  # every failure
            if note and time.time() - progress.last > STATUS_GAP:
                progress.line(note)
        progress.line()
    except KeyboardInterrupt:
        say("interrupted: the same command resumes (finished runs are kept, the others go on "
            "from their checkpoints)")
        sys.exit(130)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return finish(plan)


def dashboard_link(client):
    """The scheduler's dashboard: its Bokeh pages when they are served (they need bokeh, which
    Debian does not package), else its plain pages of workers and their tasks."""
    import urllib.request
    try:
        if "dashboard" not in client.scheduler_info().get("services", {}):
            return None
        status = client.dashboard_link
        plain = status.rsplit("/", 1)[0] + "/info/main/workers.html"
        try:
            with urllib.request.urlopen(status, timeout=2) as page:
                return plain if b"needs bokeh" in page.read(4096) else status
        except OSError:
            return plain
    except Exception:  # noqa: BLE001  (no dashboard service)
        return None


def one_line(error):
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[-1] if text else ''}"


def load_module(path):
    """The Python file at `path` as a module (a report that the plan names)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location(os.path.splitext(os.path.basename(path))[0], path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def finish(plan):
    """Writes the table and charts; exit 1 when some run failed."""
    table = sweep_report.write_table(plan)
    for path in sweep_report.write_charts(plan, table):
        say(f"chart {path}")
    if "report_module" in plan:  # a client's report over the table (hnn compare's)
        for path in load_module(plan["report_module"]).write(plan, table):
            print(f"report {path}", flush=True)
    failed = [row for row in table if row["status"] == "failed"]
    pending = [row for row in table if row["status"] == "pending"]
    for row in failed:
        say(f"failed: {row['run']}: {row['reason']}")
    say(f"{len(table) - len(failed) - len(pending)} of {len(table)} runs done; table "
        f"{os.path.join(plan['out'], 'results.csv')} (and .json)")
    if failed:
        fail(f"{len(failed)} of {len(table)} runs failed (their reasons above and in results.csv)")
    return 0


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("run", "collect", "emit-slurm"):
        sys.exit(__doc__)
    with open(sys.argv[2]) as f:
        plan = json.load(f)
    signal.signal(signal.SIGTERM, signal.default_int_handler)  # stop as Ctrl-C does
    warnings.filterwarnings("ignore", category=DeprecationWarning)  # Tornado's, through Dask
    logging.getLogger("distributed").setLevel(logging.ERROR)  # e.g. a lost worker: Dask retries
    if sys.argv[1] == "emit-slurm":
        path = sweep_report.write_slurm(plan)
        say(f"{path}: a Slurm job array of {len(plan['runs'])} runs; submit it with "
            f"`sbatch {path}`, then gather with `hnn sweep SPEC --out {plan['out']} --collect`")
        return 0
    if sys.argv[1] == "collect":
        return finish(plan)
    return run_sweep(plan)


if __name__ == "__main__":
    sys.exit(main())
