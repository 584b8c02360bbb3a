#!/usr/bin/python3
"""Tests of `hnn sweep` (issue 19), run by ctest as sweep.<Case> with HNN_EXE (the hnn program)
and HNN_SOURCE_DIR in the environment:  /usr/bin/python3 tests/sweep/sweep_test.py -v Cluster

Cluster starts a real `dask scheduler` and two `dask worker`s on 127.0.0.1, kills one of them in
the middle of a run, and checks that every run finishes once, the killed one and one other with
the metrics of the same runs trained alone by `hnn train`. The others: bad specs, the lock,
--emit slurm, a run's own failure on a local cluster, and the shipped specs against the runs
they replace."""

import csv
import fcntl
import json
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

HNN = os.environ.get("HNN_EXE", "build/apps/hnn")
SOURCE = os.environ.get("HNN_SOURCE_DIR", os.getcwd())
TIMINGS = ("train_seconds", "curve_seconds", "eval_seconds", "data_seconds")  # reliability_util.h without_timings


def hnn(*args, **kwargs):
    return subprocess.run([HNN, *args], capture_output=True, text=True, timeout=600, **kwargs)


def without_timings(metrics):
    return {k: v for k, v in metrics.items() if k not in TIMINGS}


def read_json(path):
    with open(path) as f:
        return json.load(f)


def events(out):
    path = os.path.join(out, "events.jsonl")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


def read_text(path):
    with open(path) as f:
        return f.read()


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


class SweepCase(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="hnn-sweep-test-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, *parts):
        return os.path.join(self.dir, *parts)

    def assert_one_line_error(self, result, *needles):
        self.assertEqual(result.returncode, 1, result.stderr)
        lines = result.stderr.splitlines()
        self.assertEqual(len(lines), 1, result.stderr)
        self.assertTrue(lines[0].startswith("hnn: error: "), lines[0])
        for needle in needles:
            self.assertIn(needle, lines[0])


class SpecErrors(SweepCase):
    """Every bad spec: one line naming the key, exit 1, before anything runs or is written."""

    CASES = [
        ('{"task": ["sprin"]}', "json", "key 'task': unknown task 'sprin'"),
        ('{"task": ["spring"], "stepz": [10]}', "json", "key 'stepz': not an option of hnn train"),
        ('{"task": ["spring"], "seed": []}', "json", "key 'seed': an empty list"),
        ('{"task": ["spring"], "steps": ["200"]}', "json", "key 'steps': expected an integer"),
        ('{"task": ["spring"], "steps": 200}', "json", "key 'steps': expected a list of values"),
        ('{"task": ["spring"], "lr": [0]}', "json", "key 'lr': expected a finite number > 0"),
        ('{"task": ["spring"], "hidden": [16, 16]}', "json",
         "key 'hidden': the value 16 is listed"),
        ('{"task": ["spring"], "hidden": [["a"]]}', "json", "key 'hidden': expected hidden widths"),
        ('{"task": ["spring"], "model": ["mlp"]}', "json", "key 'model': unknown model 'mlp'"),
        ('{"task": ["spring"], "integrator": ["euler"]}', "json",
         "key 'integrator': unknown integrator 'euler'"),
        ('{"task": ["spring"], "horizon": [5000]}', "json",
         "key 'horizon': expected an integer from 1 to 1000"),
        ('{"task": ["spring"], "dt": [0]}', "json", "key 'dt': expected a finite number > 0"),
        ('{"task": ["spring"], "dtype": [32]}', "json", "key 'dtype': expected a dtype"),
        ('{"task": ["spring"], "threads": [4]}', "json", "key 'threads': set by hnn sweep"),
        ('{"task": ["spring"], "coords": ["q"]}', "json", "key 'coords': applies to the data task"),
        ('{"model": ["hnn"]}', "json", "key 'task': missing"),
        ('{}', "json", "no keys"),
        ('{"grids": []}', "json", "key 'grids': expected a non-empty list"),
        ('{"task": ["spring"], "grids": [{"task": ["pendulum"]}]}', "json",
         "key 'task': given both beside \"grids\" and in grid 1"),
        ('{"task": ["spring"], "charts": [{"x": "seed", "y": "test_loss"}]}', "json",
         "key 'charts': chart 1: 'x' must be one of the spec's keys"),
        ('{"task": ["spring"], "charts": [{"x": "seed", "x_metric": "train_seconds", '
         '"y": "test_loss"}]}', "json",
         "key 'charts': chart 1: expected an object with \"y\" and one of \"x\""),
        ('{"task": ["spring"],', "json", "not valid JSON"),
        ("task: [spring]\nseed: [0, x]\n", "yaml", "key 'seed': expected an integer"),
        ("task: [spring]\n  seed: [0\n", "yaml", "not valid YAML"),
        ('{"task": ["spring"], "settings": [{"trials": 3}]}', "json",
         "run 'spring/hnn/settings=trials-3': task 'spring' has no setting 'trials'"),
        ('{"task": ["spring"], "fit": ["adam", "sampled"], "steps": [10]}', "json",
         "run 'spring/hnn/steps=10,fit=sampled': --steps does not apply to --fit sampled (it "
         "takes no training steps): put the sampled runs in a grid of their own, without --steps"),
    ]

    def test_each_bad_spec_is_one_line_naming_its_key(self):
        for i, (text, ext, needle) in enumerate(self.CASES):
            with self.subTest(spec=text):
                spec = write(self.path(f"bad{i}.{ext}"), text)
                out = self.path(f"out{i}")
                result = hnn("sweep", spec, "--out", out)
                self.assert_one_line_error(result, f"sweep spec {spec}: ", needle)
                self.assertFalse(os.path.exists(out), "a bad spec must write nothing")

    def test_bad_options(self):
        self.assert_one_line_error(hnn("sweep", self.path("none.json"), "--out", self.path("o")),
                                   "spec: File does not exist: ")
        spec = write(self.path("ok.json"), '{"task": ["spring"]}')
        self.assert_one_line_error(hnn("sweep", spec, "--out", self.path("o"), "--emit", "pbs"),
                                   "--emit")
        self.assert_one_line_error(
            hnn("sweep", spec, "--out", self.path("o"), "--scheduler", "localhost"),
            "--scheduler expects a Dask scheduler's address")


class Lock(SweepCase):
    def test_a_second_sweep_on_a_locked_folder_is_refused(self):
        spec = write(self.path("s.json"), '{"task": ["spring"], "steps": [5]}')
        out = self.path("out")
        os.makedirs(out)
        with open(os.path.join(out, "sweep.lock"), "w") as lock:
            lock.write("pid 4242 on host elsewhere since 2024-01-01T00:00:00Z\n")
            lock.flush()
            fcntl.flock(lock, fcntl.LOCK_EX)
            result = hnn("sweep", spec, "--out", out)
            self.assert_one_line_error(result, f"sweep folder '{out}' is in use by another sweep",
                                       "pid 4242 on host elsewhere")
            self.assertFalse(os.path.exists(os.path.join(out, "plan.json")))
            self.assertFalse(os.path.exists(os.path.join(out, "runs")))
        # Released (the holder exited): the folder is free again, whatever the file says.
        result = hnn("sweep", spec, "--out", out, "--emit", "slurm")
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertRegex(read_text(os.path.join(out, "sweep.lock")),
                         rf"^pid \d+ on host {re.escape(socket.gethostname())} since ")


class Slurm(SweepCase):
    def test_emit_slurm_writes_a_job_array_of_the_runs(self):
        spec = write(self.path("s.json"), json.dumps(
            {"task": ["spring"], "model": ["hnn", "baseline"], "seed": [0, 1],
             "hidden": [[8]], "steps": [20], "settings": [{}]}))
        out = self.path("out")
        result = hnn("sweep", spec, "--out", out, "--emit", "slurm", "--threads-per-run", "2")
        self.assertEqual(result.returncode, 0, result.stderr)
        script = os.path.join(out, "sweep.slurm")
        text = read_text(script)
        self.assertTrue(text.startswith("#!/bin/bash\n"))
        for line in ("#SBATCH --array=0-3", "#SBATCH --cpus-per-task=2",
                     f"#SBATCH --output={out}/slurm/%A_%a.log", f"hnn={out}/hnn",
                     f"hnn sweep {spec} --out {out} --collect"):
            self.assertIn(line, text)
        self.assertTrue(os.path.isdir(os.path.join(out, "slurm")))
        plan = read_json(os.path.join(out, "plan.json"))
        listed = hnn("sweep", spec, "--out", out, "--list").stdout.splitlines()
        for i, run in enumerate(plan["runs"]):
            arm = f"  {i}) train {shlex.quote(os.path.join(out, 'runs', run['name']))} " \
                  f"{' '.join(shlex.quote(a) for a in run['args'])} ;;"
            self.assertIn(arm, text)
            self.assertIn(" ".join(shlex.quote(a) for a in run["args"]), listed[i])
        self.assertEqual(subprocess.run(["bash", "-n", script]).returncode, 0)

        # One array task, run here as Slurm would: trains its run; again, finds it finished.
        env = dict(os.environ, SLURM_ARRAY_TASK_ID="1", SLURM_CPUS_PER_TASK="1")
        first = subprocess.run(["bash", script], env=env, capture_output=True, text=True)
        self.assertEqual(first.returncode, 0, first.stderr)
        run1 = os.path.join(out, "runs", plan["runs"][1]["name"])
        self.assertEqual(read_json(os.path.join(run1, "metrics.json"))["seed"], 1)
        again = subprocess.run(["bash", script], env=env, capture_output=True, text=True)
        self.assertIn("is finished", again.stdout)
        beyond = subprocess.run(["bash", script], capture_output=True, text=True,
                                env=dict(os.environ, SLURM_ARRAY_TASK_ID="4"))
        self.assertEqual(beyond.returncode, 1)

        collected = hnn("sweep", spec, "--out", out, "--collect")
        self.assertEqual(collected.returncode, 0, collected.stderr)
        table = read_json(os.path.join(out, "results.json"))
        self.assertEqual(table["counts"], {"done": 1, "failed": 0, "pending": 3})
        self.assertEqual(table["runs"][1]["status"], "done")


class LocalCluster(SweepCase):
    def test_a_failing_run_is_reported_in_one_line_and_the_rest_finish(self):
        bad_data = write(self.path("bad.txt"), "not a measured pendulum\n")
        spec = write(self.path("s.yaml"), f"""
grids:
  - {{task: [spring], seed: [0, 1], hidden: [[8]], steps: [50]}}
  - {{task: [real-pendulum], data: ["{bad_data}"], steps: [50]}}
charts:
  - {{x: seed, y: test_loss}}
  - {{x_metric: train_seconds, y: test_loss, log_x: true}}
""")
        out = self.path("out")
        result = hnn("sweep", spec, "--out", out, "--workers", "2")
        self.assertEqual(result.returncode, 1, result.stderr)
        self.assertEqual(result.stderr.splitlines()[-1],
                         "hnn: error: sweep: 1 of 3 runs failed (their reasons above and in "
                         "results.csv)")
        table = read_json(os.path.join(out, "results.json"))
        self.assertEqual(table["counts"], {"done": 2, "failed": 1, "pending": 0})
        failed = table["runs"][2]
        direct = hnn("train", "real-pendulum", "--data", bad_data, "--steps", "50", "--quiet",
                     "--out", self.path("direct"))
        self.assertEqual(direct.returncode, 1)
        self.assertEqual("hnn: error: " + failed["reason"], direct.stderr.strip())
        self.assertIn(f"failed: {failed['run']}: {failed['reason']}", result.stdout)
        self.assertTrue(os.path.exists(os.path.join(out, "chart-1.png")))
        self.assertTrue(os.path.exists(os.path.join(out, "chart-2.png")))
        self.assertTrue(
            read_text(os.path.join(out, "results.csv")).startswith("run,status,reason,"))

        # Again: nothing runs (the failure is reported, not retried), still exit 1.
        before = events(out)
        again = hnn("sweep", spec, "--out", out)
        self.assertEqual(again.returncode, 1)
        self.assertIn("all 3 runs are finished (1 failed): nothing to run", again.stdout)
        self.assertEqual(events(out), before)
        # --retry-failed runs that one again, and only that one.
        retried = hnn("sweep", spec, "--out", out, "--retry-failed")
        self.assertEqual(retried.returncode, 1)
        self.assertEqual([(e["event"], e["run"]) for e in events(out)[len(before):]],
                         [("start", failed["run"]), ("failed", failed["run"])])


    def test_a_folder_holding_another_run_is_refused_before_anything_runs(self):
        spec = write(self.path("s.json"), '{"task": ["spring"], "hidden": [[8]]}')
        out = self.path("out")
        held = os.path.join(out, "runs", "spring", "hnn", "hidden=8")
        trained = hnn("train", "spring", "--hidden", "8", "--steps", "5", "--quiet", "--out", held)
        self.assertEqual(trained.returncode, 0, trained.stderr)
        result = hnn("sweep", spec, "--out", out)
        self.assert_one_line_error(
            result, f"sweep: run folder '{held}' holds another run (steps 5, the spec's 2000): "
            "delete it, or give another --out")
        self.assertEqual(events(out), [])

    def test_an_unreachable_scheduler_is_one_line(self):
        spec = write(self.path("s.json"), '{"task": ["spring"], "steps": [5]}')
        address = f"tcp://127.0.0.1:{free_port()}"
        result = hnn("sweep", spec, "--out", self.path("out"), "--scheduler", address)
        self.assert_one_line_error(result, f"sweep: cannot reach the Dask scheduler {address}: ")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Cluster(SweepCase):
    """A real scheduler and two workers; one is killed while it trains a run."""

    def start(self, *args):
        with open(self.path(f"{args[0]}-{len(self.procs)}.log"), "w") as log:
            proc = subprocess.Popen(["dask", *args], cwd=self.dir, stdout=subprocess.DEVNULL,
                                    stderr=log, start_new_session=True)
        self.procs.append(proc)
        return proc

    def setUp(self):
        super().setUp()
        self.procs = []
        port = free_port()
        self.address = f"tcp://127.0.0.1:{port}"
        self.start("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")
        self.workers = {name: self.start("worker", self.address, "--name", name, "--nthreads",
                                         "1", "--no-nanny", "--local-directory", self.path(name))
                        for name in ("w1", "w2")}
        from distributed import Client
        with Client(self.address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)

    def tearDown(self):
        for proc in reversed(self.procs):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
                try:
                    proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()
        super().tearDown()

    def steps_for(self, seconds):
        """Training steps of a run of about `seconds` on this machine (sanitized builds are
        slower): measured on one short run."""
        hnn("train", "spring", "--hidden", "32", "32", "--steps", "300", "--threads", "1",
            "--quiet", "--out", self.path("calibrate"))
        per_step = read_json(self.path("calibrate", "metrics.json"))["train_seconds"] / 300
        return max(600, min(20000, int(seconds / per_step) // 100 * 100))

    def kill_mid_run(self, out, name):
        """SIGKILLs worker `name` once it trains a run that has checkpointed; returns that run."""
        deadline = time.time() + 120
        while time.time() < deadline:
            for e in events(out):
                if e["worker"] == name and e["event"] in ("start", "resume"):
                    state = os.path.join(out, "runs", e["run"], "checkpoint", "state.json")
                    done = any(d["run"] == e["run"] and d["event"] == "done" for d in events(out))
                    if os.path.exists(state) and not done:
                        os.kill(self.workers[name].pid, signal.SIGKILL)
                        return e["run"]
            time.sleep(0.02)
        self.fail(f"worker {name} never trained a run")

    def test_a_killed_worker_s_run_resumes_elsewhere_and_every_run_finishes_once(self):
        steps = self.steps_for(1.5)
        seeds = list(range(3))
        spec = write(self.path("s.json"), json.dumps(
            {"task": ["spring"], "model": ["hnn", "baseline"], "seed": seeds,
             "hidden": [[32, 32]], "steps": [steps], "checkpoint-every": [steps // 10]}))
        out = self.path("out")
        sweep = subprocess.Popen([HNN, "sweep", spec, "--out", out, "--scheduler", self.address],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        killed = self.kill_mid_run(out, "w1")
        stdout, stderr = sweep.communicate(timeout=600)
        print(f"\n{stdout}killed worker w1 while it trained {killed} ({steps} steps)",
              file=sys.stderr)
        self.assertEqual(sweep.returncode, 0, stderr)
        self.assertIn("6/6 done, 0 running, 0 failed", stdout)

        log = events(out)
        runs = read_json(os.path.join(out, "plan.json"))["runs"]
        self.assertEqual(len(runs), 6)
        for run in runs:
            done = [e for e in log if e["run"] == run["name"] and e["event"] == "done"]
            self.assertEqual(len(done), 1, f"{run['name']} finished {len(done)} times")
        resumed = [e for e in log if e["run"] == killed and e["event"] == "resume"]
        self.assertEqual([e["worker"] for e in resumed], ["w2"], log)
        self.assertTrue(read_json(os.path.join(out, "runs", killed, "sweep.json"))["resumed"])

        # The killed run and one of the other model, trained alone: the same metrics.
        table = read_json(os.path.join(out, "results.json"))
        self.assertEqual(table["counts"], {"done": 6, "failed": 0, "pending": 0})
        killed_row = next(r for r in table["runs"] if r["run"] == killed)
        other = next(r for r in table["runs"]
                     if r["values"]["model"] != killed_row["values"]["model"])
        for row in (killed_row, other):
            v = row["values"]
            ref = self.path("ref", row["run"])
            direct = hnn("train", "spring", "--model", v["model"], "--seed", str(v["seed"]),
                         "--hidden", "32", "32", "--steps", str(steps), "--threads", "1",
                         "--quiet", "--out", ref)
            self.assertEqual(direct.returncode, 0, direct.stderr)
            self.assertEqual(without_timings(row["metrics"]),
                             without_timings(read_json(os.path.join(ref, "metrics.json"))),
                             row["run"])

        # A finished sweep, run again: nothing runs.
        start = time.time()
        again = hnn("sweep", spec, "--out", out, "--scheduler", self.address)
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertIn("all 6 runs are finished (0 failed): nothing to run", again.stdout)
        self.assertEqual(events(out), log)
        self.assertLess(time.time() - start, 30)


class Charts(unittest.TestCase):
    """The x_metric chart's points: seeds pooled per setting, labelled by what varies."""

    def test_metric_points_pool_seeds_and_label_the_varying_keys(self):
        sys.path.insert(0, os.path.join(SOURCE, "apps", "hnn", "sweep"))
        import sweep_report

        def run(hidden, seed, secs, err):
            return {"values": {"task": "spring", "fit": "sampled", "hidden": hidden,
                               "seed": seed},
                    "metrics": {"train_seconds": secs, "test_loss": err}}
        rows = [run(100, 0, 1.0, 4.0), run(100, 1, 3.0, 2.0), run(10, 0, 0.5, 9.0),
                {"values": {"hidden": 5, "seed": 0}, "metrics": {"test_loss": 1.0}}]
        points = sweep_report.metric_points(rows, "train_seconds", "test_loss", "fit", None)
        self.assertEqual([p[4] for p in points], ["10", "100"])  # ordered by time
        mx, my, ex, ey, _ = points[1]
        self.assertEqual((mx, my), (2.0, 3.0))
        self.assertAlmostEqual(ex, 1.0)
        self.assertAlmostEqual(ey, 1.0)
        self.assertEqual(points[0][2:4], (0.0, 0.0))  # one seed: no error bar

    def test_the_fit_block_has_columns_of_its_own_beside_the_fit_key(self):
        # results.csv: the spec's `fit` (the fit asked for) and metrics.json's "fit" block (how
        # it went) both readable, the block flattened to fit_* columns; results.json keeps both.
        sys.path.insert(0, os.path.join(SOURCE, "apps", "hnn", "sweep"))
        import sweep_report
        out = tempfile.mkdtemp(prefix="hnn-sweep-table-")
        self.addCleanup(shutil.rmtree, out, ignore_errors=True)
        block = {"method": "sampled", "solver": "qr", "solve_seconds": 0.25}
        runs = {"spring/hnn/fit=sampled": {"test_loss": 1e-4, "fit": block},
                "spring/hnn/fit=adam": {"test_loss": 1e-3}}
        for name, metrics in runs.items():
            os.makedirs(os.path.join(out, "runs", name))
            write(os.path.join(out, "runs", name, "metrics.json"), json.dumps(metrics))
        plan = {"spec": "s.yaml", "out": out, "keys": ["task", "fit"],
                "runs": [{"name": n, "values": {"task": "spring", "fit": n.split("=")[1]}}
                         for n in runs]}
        rows = sweep_report.write_table(plan)
        with open(os.path.join(out, "results.csv")) as f:
            table = list(csv.DictReader(f))
        self.assertEqual([r["fit"] for r in table], ["sampled", "adam"])
        self.assertEqual([r["fit_method"] for r in table], ["sampled", ""])
        self.assertEqual([r["fit_solver"] for r in table], ["qr", ""])
        self.assertEqual(table[0]["fit_solve_seconds"], "0.25")
        self.assertEqual(read_json(os.path.join(out, "results.json"))["runs"][0]["metrics"]["fit"],
                         block)
        # A chart may name a column of the block.
        plan["charts"] = [{"x_metric": "fit_solve_seconds", "y": "test_loss", "file": "c.png"}]
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            return
        self.assertEqual(sweep_report.write_charts(plan, rows), [os.path.join(out, "c.png")])


class Expansion(SweepCase):
    """How a spec becomes runs: hnn train's arguments, folder names, grids, duplicates."""

    def listed(self, spec_text, ext="json"):
        spec = write(self.path(f"s.{ext}"), spec_text)
        result = hnn("sweep", spec, "--out", self.path("out"), "--list", cwd=self.dir)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertFalse(os.path.exists(self.path("out")), "--list writes nothing")
        return [shlex.split(line) for line in result.stdout.splitlines()]

    def test_values_become_hnn_train_arguments_and_folder_names(self):
        runs = self.listed(json.dumps({
            "task": ["data"], "data": ["sub/my data.csv"], "coords": ["q1,q2", ["a", "b"]],
            "momenta": [["p1", "p2"]], "test-fraction": [0.25], "lr": [0.001, 1e-05],
            "settings": [{"threshold": 0.2}]}))
        self.assertEqual(len(runs), 4)
        data = os.path.join(self.dir, "sub", "my data.csv")
        self.assertEqual(runs[0][:3], ["hnn", "train", "data"])
        self.assertEqual(runs[0][3:], [
            "--lr", "0.001", "--data", data, "--settings", '{"threshold":0.2}', "--coords", "q1,q2",
            "--momenta", "p1,p2", "--test-fraction", "0.25", "--threads", "1", "--quiet",
            "--out", self.path("out", "runs", "data", "hnn",
                               "lr=0.001,data=my-data.csv,settings=threshold-0.2,coords=q1+q2,"
                               "momenta=p1+p2,test-fraction=0.25")])
        self.assertEqual(runs[1][runs[1].index("--lr") + 1], "1e-05")
        self.assertEqual(runs[2][runs[2].index("--coords") + 1], "a,b")

    def test_grids_share_keys_and_a_run_asked_twice_is_one_run(self):
        runs = self.listed("""
steps: [10]
grids:
  - {task: [spring], hidden: [[16, 16], 8]}
  - {task: [spring], hidden: [[16, 16]], seed: [0]}
  - {task: [pendulum]}
""", ext="yaml")
        folders = [r[r.index("--out") + 1].split("/runs/")[1] for r in runs]
        # seed 0 is the default: the second grid's run is the first grid's first run.
        self.assertEqual(folders, ["spring/hnn/hidden=16-16,steps=10",
                                   "spring/hnn/hidden=8,steps=10", "pendulum/hnn/steps=10"])

    def test_runs_that_read_alike_get_a_tag_each(self):
        os.makedirs(self.path("a"))
        os.makedirs(self.path("b"))
        runs = self.listed('{"task": ["real-pendulum"], "data": ["a/x.txt", "b/x.txt"]}')
        folders = [r[r.index("--out") + 1].rsplit("/", 1)[1] for r in runs]
        self.assertEqual(len(set(folders)), 2)
        for f in folders:
            self.assertRegex(f, r"^data=x\.txt~[0-9a-f]{8}$")


class ShippedSpecs(SweepCase):
    """sweeps/*.{json,yaml} expand to the runs of what they replace."""

    @staticmethod
    def runs_of(lines):
        """(task, model, dtype, hidden, seed, other options) of each `... train ...` line."""
        runs = []
        for line in lines:
            words = shlex.split(line)
            if "train" not in words or "--out" not in words:
                continue
            words = words[words.index("train") + 1:]
            run = {"task": words[0], "model": "hnn", "dtype": "double", "hidden": "", "seed": "0",
                   "other": []}
            i = 1
            while i < len(words):
                option, i = words[i], i + 1
                values = []
                while i < len(words) and not words[i].startswith("--"):
                    values.append(words[i])
                    i += 1
                key = option[2:]
                if key in ("model", "dtype", "seed"):
                    run[key] = values[0]
                elif key == "hidden":
                    run["hidden"] = "-".join(values)
                elif key not in ("threads", "quiet", "out"):
                    run["other"].append(option)
            runs.append((run["task"], run["model"], run["dtype"], run["hidden"], run["seed"],
                         tuple(run["other"])))
        return runs

    def test_model_size_is_the_four_parts_of_charts_3_and_4(self):
        # The runs of charts 3 and 4 (docs/speed_accuracy.md, sections 3 and 4), declared part
        # by part: float_double, width, depth, seeds; the width part's double 200-200 is
        # float_double's.
        state_tasks = ["spring", "pendulum", "real-pendulum", "two-body", "three-body"]
        lean_candidates = {"spring": ["16-16", "32-32"], "pendulum": ["32-32", "64-64"],
                           "real-pendulum": ["16-16", "32-32"], "two-body": ["32-32", "64-64"],
                           "three-body": ["32-32", "64-64"]}
        expected = {(task, model, dtype, "200-200", "0", ())
                    for task in state_tasks + ["pixel-pendulum"] for model in ("hnn", "baseline")
                    for dtype in ("float", "double")}
        expected |= {(task, model, "double", hidden, "0", ()) for task in state_tasks
                     for model in ("hnn", "baseline")
                     for hidden in ("16-16", "32-32", "64-64", "128-128", "200-200", "256-256",
                                    "200", "200-200-200")}
        expected |= {(task, "hnn", "double", hidden, seed, ()) for task in state_tasks
                     for seed in ("1", "2") for hidden in ["200-200"] + lean_candidates[task]}
        new = hnn("sweep", os.path.join(SOURCE, "sweeps", "model_size.yaml"), "--out",
                  self.path("new"), "--list")
        self.assertEqual(new.returncode, 0, new.stderr)
        new_runs = self.runs_of(new.stdout.splitlines())
        self.assertEqual(len(new_runs), 124)
        self.assertEqual(len(set(new_runs)), 124)
        self.assertEqual(set(new_runs), expected)

    def test_sampled_is_adam_at_the_defaults_and_sampled_at_several_widths(self):
        # Issue 29's speed against accuracy: Adam at each task's defaults, the sampled fit at
        # widths each task's data can support; seeds 0-2; the sampled runs take no steps.
        seeds = ("0", "1", "2")
        paper = ("spring", "pendulum", "two-body")
        expected = {(t, m, "double", "", s, ("--fit",)) for t in paper
                    for m in ("hnn", "baseline") for s in seeds}
        expected |= {(t, m, "double", w, s, ("--fit",))
                     for t in ("spring", "pendulum") for m in ("hnn", "baseline") for s in seeds
                     for w in ("25", "50", "100", "200", "400")}
        expected |= {("two-body", m, "double", w, s, ("--fit",)) for m in ("hnn", "baseline")
                     for s in seeds for w in ("100", "200", "400", "800", "1600")}
        expected |= {("pendulum-scattered", "hnn", "double", "", s, ("--steps", "--fit"))
                     for s in seeds}
        expected |= {("pendulum-scattered", "hnn", "double", w, s, ("--fit",)) for s in seeds
                     for w in ("100", "200", "400", "1000")}
        listed = hnn("sweep", os.path.join(SOURCE, "sweeps", "sampled.yaml"), "--out",
                     self.path("new"), "--list")
        self.assertEqual(listed.returncode, 0, listed.stderr)
        lines = listed.stdout.splitlines()
        runs = self.runs_of(lines)
        self.assertEqual(len(runs), 123)
        self.assertEqual(set(runs), expected)

    def test_table1_is_the_runs_of_hnn_reproduce(self):
        # reproduce's own list of its tasks, from its refusal of another.
        refusal = hnn("reproduce", "--tasks", "data", "--out", self.path("r")).stderr
        paper = re.search(r"runs the paper's tasks \(([^)]*)\)", refusal).group(1).split(", ")
        new = hnn("sweep", os.path.join(SOURCE, "sweeps", "table1.json"), "--out",
                  self.path("new"), "--list")
        self.assertEqual(new.returncode, 0, new.stderr)
        expected = [(task, model, "double", "", "0", ()) for task in paper
                    for model in ("baseline", "hnn")]
        self.assertEqual(self.runs_of(new.stdout.splitlines()), expected)


if __name__ == "__main__":
    unittest.main()
