#!/usr/bin/python3
"""Tests of `hnn compare` (issue 18, section 5), run by ctest as compare.<Case> with HNN_EXE and
HNN_SOURCE_DIR in the environment:  /usr/bin/python3 tests/sweep/compare_test.py -v Tiny

Tiny runs a real comparison on a local Dask cluster (2 tasks, 3 models, 2 seeds, 30 steps) and
checks its table against the runs' own metrics.json files and the peers file; Options checks bad
options and the skip reasons of --list, which runs nothing."""

import json
import math
import os
import re
import shutil
import subprocess
import tempfile
import unittest

HNN = os.environ.get("HNN_EXE", "build/apps/hnn")
SOURCE = os.environ.get("HNN_SOURCE_DIR", os.getcwd())
PEERS = os.path.join(SOURCE, "data", "peers.json")


def hnn(*args):
    return subprocess.run([HNN, *args], capture_output=True, text=True, timeout=600)


def read_json(path):
    with open(path) as f:
        return json.load(f)


def read_text(path):
    with open(path) as f:
        return f.read()


def mean_se(values):
    m = sum(values) / len(values)
    return m, math.sqrt(sum((v - m) ** 2 for v in values) / (len(values) - 1) / len(values))


class CompareCase(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="hnn-compare-test-")
        self.out = os.path.join(self.dir, "cmp")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def assert_one_line_error(self, result, *needles):
        self.assertEqual(result.returncode, 1, result.stderr)
        lines = result.stderr.splitlines()
        self.assertEqual(len(lines), 1, result.stderr)
        self.assertTrue(lines[0].startswith("hnn: error: "), lines[0])
        for needle in needles:
            self.assertIn(needle, lines[0])


class Options(CompareCase):
    def test_bad_options_are_one_line_and_nothing_is_written(self):
        cases = [
            (["--tasks", "spring", "--models", "hnn,mlp"], ["unknown model 'mlp'", "known: hnn, baseline"]),
            (["--tasks", "spring,sprung"], ["unknown task 'sprung'", "spring, pendulum"]),
            (["--tasks", "spring", "--seeds", "0"], ["--seeds", "expected an integer from 1"]),
            (["--tasks", "spring", "--loss", "energy"], ["unknown loss 'energy'", "derivative"]),
            (["--tasks", "spring", "--steps", "0"], ["--steps", "expected an integer >= 1"]),
            (["--tasks", "spring", "--scheduler", "localhost"], ["tcp://HOST:8786"]),
            (["--tasks", "spring", "--fit", "adam,sgd"], ["--fit: unknown fit 'sgd'",
                                                          "known: adam, sampled, sampled+adam"]),
        ]
        for args, needles in cases:
            with self.subTest(args=args):
                self.assert_one_line_error(hnn("compare", *args, "--out", self.out), *needles)
                self.assertFalse(os.path.exists(self.out))

    def test_a_bad_peers_file_is_one_line(self):
        bad = os.path.join(self.dir, "peers.json")
        with open(bad, "w") as f:
            json.dump({"peers": [{"peer": "x", "source": "y", "task": "spring"}]}, f)
        result = subprocess.run([HNN, "compare", "--tasks", "spring", "--out", self.out],
                                capture_output=True, text=True, env={**os.environ, "HNN_PEERS": bad})
        self.assert_one_line_error(result, f"peers file {bad}: entry 1: 'peer_model' must be")
        self.assertFalse(os.path.exists(self.out))

    def test_list_gives_each_skip_hnn_s_own_reason_and_runs_nothing(self):
        result = hnn("compare", "--tasks", "pixel-pendulum,spring", "--models", "dhnn,hnn",
                     "--loss", "derivative,rollout", "--seeds", "2", "--list", "--out", self.out)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        # The reason is the one `hnn train` and `hnn sweep` give for that run.
        train = hnn("train", "pixel-pendulum", "--model", "dhnn", "--out",
                    os.path.join(self.dir, "x"))
        reason = train.stderr.strip().replace("hnn: error: ", "")
        self.assertIn(f"pixel-pendulum dhnn derivative: skipped: {reason}", lines)
        self.assertIn("spring hnn derivative: 2 runs", lines)
        self.assertIn("spring dhnn derivative: 2 runs", lines)
        rollout = [l for l in lines if l.startswith("spring hnn rollout: ")]
        self.assertEqual(len(rollout), 1)
        if "skipped" in rollout[0]:  # the rollout loss on a task that lacks it, in hnn's words
            train = hnn("train", "spring", "--loss", "rollout", "--out", os.path.join(self.dir, "y"))
            self.assertIn(rollout[0].split("skipped: ")[1].split(":")[-1].strip(), train.stderr)
        commands = [l for l in lines if l.startswith("hnn train ")]
        runs = sum(int(l.split(": ")[1].split()[0]) for l in lines if l.endswith(" runs"))
        self.assertEqual(len(commands), runs)
        self.assertGreaterEqual(runs, 6)  # pixel-pendulum hnn, spring dhnn and hnn: 2 seeds each
        self.assertFalse(os.path.exists(self.out))

    def test_the_fit_is_an_axis_and_a_sampled_row_takes_no_steps(self):
        result = hnn("compare", "--tasks", "spring,double-pendulum", "--models", "hnn,lnn",
                     "--fit", "adam,sampled", "--seeds", "2", "--steps", "50", "--list",
                     "--out", self.out)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        self.assertIn("spring hnn derivative: 2 runs", lines)
        self.assertIn("spring hnn (sampled) derivative: 2 runs", lines)
        lnn = [l for l in lines if l.startswith("double-pendulum lnn (sampled) derivative: ")]
        self.assertEqual(len(lnn), 1, lines)
        self.assertIn("skipped: double-pendulum: --fit sampled does not fit an lnn", lnn[0])
        spring = [l for l in lines if l.startswith("hnn train spring --model hnn ")]
        sampled = [l for l in spring if "--fit sampled" in l]
        self.assertEqual(len(sampled), 2)
        self.assertTrue(all("--steps" not in l for l in sampled), sampled)
        self.assertTrue(all("--steps 50" in l for l in spring if l not in sampled), spring)
        self.assertFalse(os.path.exists(self.out))

    def test_the_default_study_says_why_a_family_hnn_lacks_is_skipped(self):
        result = hnn("compare", "--quick", "--list", "--out", self.out)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        self.assertIn("real-pendulum dhnn derivative: 3 runs", lines)
        self.assertIn("damped-spring baseline derivative: 3 runs", lines)
        lnn = [l for l in lines if l.startswith("double-pendulum lnn derivative: ")]
        self.assertEqual(len(lnn), 1)
        models = hnn("train", "--help").stdout
        if "lnn" not in models:
            self.assertIn("skipped: this hnn has no", lnn[0])
        self.assertTrue(all("--steps 100" in l for l in lines if l.startswith("hnn train ")))
        # the peers' protocols: SRNN's three-body at dt = 1 trained through leapfrog on windows
        # of 5 points; the coarse, noisy spring; --steps over the protocol's own steps
        rollout = [l for l in lines if l.startswith("hnn train three-body --model hnn --seed 0 ")
                   and "--loss rollout" in l]
        self.assertEqual(len(rollout), 1, lines)
        for option in ("--settings '{\"setup\":\"srnn\"}'", "--integrator leapfrog",
                       "--horizon 4", "--batch 32", "--steps 100"):
            self.assertIn(option, rollout[0])
        self.assertNotIn("--steps 5000", rollout[0])
        self.assertIn('spring hnn rollout {"settings":{"sample_dt":1.0,"t_end":6},'
                      '"integrator":"leapfrog","horizon":1}: 3 runs', lines)
        # the D-HNN paper's real pendulum: the shipped Lipson file through the data task
        dhnn = [l for l in lines if l.startswith("hnn train data --model dhnn --seed 0 ")]
        self.assertEqual(len(dhnn), 1, lines)
        for option in ("--hidden 256 256", "--batch 128", "--lr 0.005", "real_pend_h_1.txt",
                       "--hamiltonian '2.4*(1 - cos(o)) + v^2'"):
            self.assertIn(option, dhnn[0])

    def test_the_constrained_systems_are_a_study_of_their_own(self):
        # Finzi et al.'s systems train 8,000 steps a run: a named study, not the default's.
        result = hnn("compare", "--study", "constrained", "--list", "--out", self.out)
        self.assertEqual(result.returncode, 0, result.stderr)
        lines = result.stdout.splitlines()
        for task in ("chain-pendulum-2", "chain-pendulum-3", "chain-pendulum-5"):
            for model in ("baseline", "hnn", "hnn-mass", "lnn", "chnn", "clnn"):
                self.assertIn(f"{task} {model} rollout: 3 runs", lines)
        self.assertIn("gyroscope chnn rollout: 3 runs", lines)
        self.assertIn("rotor hnn-mass rollout: 3 runs", lines)  # their HNN, in body coordinates
        self.assertTrue(any(l.startswith("gyroscope hnn rollout: skipped: ") for l in lines))
        # their data efficiency: 10 trajectories, so a batch of all 10 chunks, 2000 steps
        self.assertIn('chain-pendulum-2 chnn rollout {"settings":{"trajectories":10},"batch":10,'
                      '"steps":2000}: 3 runs', lines)
        chnn = [l for l in lines if l.startswith("hnn train chain-pendulum-2 --model chnn ")]
        self.assertEqual(len(chnn), 6, chnn)  # 3 seeds at their defaults, 3 at 10 trajectories
        few = [l for l in chnn if "trajectories" in l]
        self.assertEqual(len(few), 3, chnn)
        self.assertTrue(all("--batch 10 " in l and "--steps 2000 " in l for l in few), few)
        self.assertTrue(all("--steps" not in l and "--batch" not in l for l in chnn
                            if l not in few), chnn)
        # --tasks without --loss: each task at its own loss (theirs is the rollout loss)
        tasks = hnn("compare", "--tasks", "chain-pendulum-2,spring", "--models", "hnn",
                    "--seeds", "1", "--list", "--out", self.out)
        self.assertEqual(tasks.returncode, 0, tasks.stderr)
        self.assertIn("chain-pendulum-2 hnn rollout: 1 runs", tasks.stdout.splitlines())
        self.assertIn("spring hnn derivative: 1 runs", tasks.stdout.splitlines())
        self.assertNotIn("--loss", tasks.stdout)
        default = hnn("compare", "--list", "--out", self.out)
        self.assertEqual(default.returncode, 0, default.stderr)
        self.assertNotIn("chain-pendulum", default.stdout)
        self.assertNotIn("gyroscope", default.stdout)
        self.assert_one_line_error(hnn("compare", "--study", "constrained", "--tasks", "spring",
                                       "--out", self.out), "--tasks excludes --study")
        self.assert_one_line_error(hnn("compare", "--study", "finzi", "--out", self.out),
                                   "--study: finzi not in {default,constrained}")
        self.assertFalse(os.path.exists(self.out))


class Report(unittest.TestCase):
    """The report's matching of a peer's protocol settings, on rows made by hand (no runs)."""

    def setUp(self):
        import sys
        sys.path.insert(0, os.path.join(SOURCE, "apps", "hnn", "sweep"))
        sys.path.insert(0, os.path.join(SOURCE, "apps", "hnn", "compare"))
        import compare_report
        self.report = compare_report

    def row(self, settings=None, **keys):
        if settings is not None:
            keys["settings"] = settings
        return {"task": "three-body", "model": "hnn", "loss": "rollout", "keys": keys}

    def test_a_peer_s_settings_must_be_the_row_s(self):
        srnn = {"task": "three-body", "model": "hnn", "loss": "rollout",
                "settings": {"setup": "srnn"}, "metric": "stretch_position_error"}
        self.assertTrue(self.report.peer_matches(srnn, self.row({"setup": "srnn"}, horizon=4)))
        self.assertFalse(self.report.peer_matches(srnn, self.row()))
        self.assertFalse(self.report.peer_matches(srnn, self.row({"setup": "paper"})))
        table1 = {"task": "three-body", "model": "hnn", "loss": "rollout",
                  "task_defaults_only": True}
        self.assertTrue(self.report.peer_matches(table1, self.row()))
        self.assertFalse(self.report.peer_matches(table1, self.row({"setup": "srnn"})))
        why = self.report.unmatched_reason(srnn, {}, [{**self.row(), "skipped": None}],
                                           ["three-body"], {"hnn"})
        self.assertIn('settings {"setup": "srnn"} are not', why)

    def test_a_peer_s_options_must_be_the_row_s(self):
        dhnn = {"task": "data", "model": "dhnn", "loss": "derivative",
                "keys": {"data": "real_pend_h_1.txt", "lr": 0.005}}
        row = {"task": "data", "model": "dhnn", "loss": "derivative",
               "keys": {"data": "/any/folder/real_pend_h_1.txt", "lr": 0.005, "batch": 128}}
        self.assertTrue(self.report.peer_matches(dhnn, row))
        self.assertFalse(self.report.peer_matches(dhnn, {**row, "keys": {"lr": 0.005}}))
        other = {**row, "keys": {"data": "/f/real_pend_h_1.txt", "lr": 0.001}}
        self.assertFalse(self.report.peer_matches(dhnn, other))
        why = self.report.unmatched_reason(dhnn, {}, [{**other, "skipped": None}], ["data"],
                                           {"dhnn"})
        self.assertIn("options", why)
        self.assertEqual(self.report.row_label(row)[0], "data real_pend_h_1.txt")

    def test_a_fit_other_than_adam_is_named_in_the_model_column(self):
        self.assertEqual(self.report.model_label({"model": "hnn", "fit": "sampled"}),
                         "hnn (sampled)")
        self.assertEqual(self.report.model_label({"model": "hnn", "fit": "adam"}), "hnn")
        self.assertEqual(self.report.model_label({"model": "hnn"}), "hnn")  # an older plan

    def test_the_row_label_shows_the_protocol(self):
        task, loss = self.report.row_label(self.row({"setup": "srnn"}, horizon=4))
        self.assertEqual(task, 'three-body {"setup": "srnn"}')
        self.assertEqual(loss, "rollout (horizon 4)")
        self.assertEqual(self.report.row_label(self.row()), ("three-body", "rollout"))
        self.assertEqual(self.report.headline_of({"headline": {"default": "energy_mse"}},
                                                 {**self.row(), "headline": "x"}), "x")

    def test_finzi_s_chnn_and_clnn_sit_beside_the_constrained_study_s_rows(self):
        peers = [p for p in read_json(PEERS)["peers"]
                 if p["peer_model"].startswith(("CHNN", "CLNN"))]
        self.assertGreaterEqual(len(peers), 10)
        defaults = lambda p: {"task": p["task"], "model": p["model"], "loss": "rollout",
                              "keys": {}}
        few = lambda p: {**defaults(p), "keys": {"settings": {"trajectories": 10}}}
        for p in peers:
            with self.subTest(task=p["task"], peer_model=p["peer_model"]):
                self.assertEqual(p["model"], p["peer_model"][:4].lower())
                self.assertEqual(p["metric"], "cartesian_error")
                if p.get("settings"):  # their data efficiency: 10 trajectories only
                    self.assertTrue(self.report.peer_matches(p, few(p)))
                    self.assertFalse(self.report.peer_matches(p, defaults(p)))
                else:  # at the task's defaults (their protocol) only
                    self.assertTrue(self.report.peer_matches(p, defaults(p)))
                    self.assertFalse(self.report.peer_matches(p, few(p)))


class Tiny(CompareCase):
    ARGS = ["--tasks", "damped-spring,spring", "--models", "baseline,dhnn,hnn",
            "--seeds", "2", "--steps", "30", "--workers", "2"]

    def test_a_tiny_comparison_tables_the_runs_beside_the_peers_and_reuses_them(self):
        result = hnn("compare", *self.ARGS, "--out", self.out)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        doc = read_json(os.path.join(self.out, "compare.json"))
        md = read_text(os.path.join(self.out, "compare.md"))
        self.assertTrue(os.path.getsize(os.path.join(self.out, "accuracy_vs_time.png")) > 1000)
        self.assertEqual(len(doc["rows"]), 6)
        peers = read_json(PEERS)["peers"]
        for row in doc["rows"]:
            self.assertEqual(row["status"], "done", row)
            self.assertEqual(len(row["runs"]), 2)
            metrics = [read_json(os.path.join(self.out, "runs", r, "metrics.json"))
                       for r in row["runs"]]
            self.assertEqual(sorted(m["seed"] for m in metrics), [0, 1])
            self.assertTrue(all(m["steps"] == 30 for m in metrics))
            for key in ("test_loss", "energy_mse", "state_mse", "train_seconds"):
                mean, se = mean_se([m[key] for m in metrics])
                got = row["metrics"][key]
                self.assertAlmostEqual(got["mean"], mean, delta=1e-12 * abs(mean))
                self.assertAlmostEqual(got["se"], se, delta=1e-12 * abs(se) + 1e-300)
                # and in the markdown, as printed
                line = f"| {key} | {mean:.3e} ± {se:.1e} |"
                self.assertIn(line, md)
            # the peers' numbers on this row: exactly the peers file's for its task and model (the
            # HNN paper's Table 1 among them: every row runs at its task's defaults)
            want = {(p["metric"], p["value"]) for p in peers
                    if p["task"] == row["task"] and p.get("model") == row["model"]
                    and (p.get("loss") or "derivative") == row["loss"]}
            got = {(l["peer"].get("metric"), l["peer"]["value"]) for l in row["lines"]
                   if l["peer"]}
            self.assertEqual(got, want, row["task"] + " " + row["model"])
        # damped spring: the D-HNN paper's state MSE beside ours, on the same line
        dhnn_state = next(p for p in peers if p["task"] == "damped-spring"
                          and p.get("model") == "dhnn" and p["metric"] == "dhnn_paper_state_mse")
        self.assertRegex(md, r"\| damped-spring \| dhnn \| derivative \| dhnn_paper_state_mse \| "
                         + r"[0-9.e+-]+ ± "
                         + r"[0-9.e+-]+ \| 2/2 \| " + re.escape(f"{dhnn_state['value']:.3e}"))
        # spring: the HNN paper's Table 1 (its entries in the peers file) beside ours
        self.assertIn("| 3.842e-04 ± 6.5e-05 | HNN (Greydanus et al. 2019): HNN", md)

        # The second invocation trains nothing and writes the same table.
        again = hnn("compare", *self.ARGS, "--out", self.out)
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertIn("all 12 runs are finished", again.stdout)
        self.assertEqual(read_json(os.path.join(self.out, "compare.json"))["rows"], doc["rows"])

    def test_a_skipped_pair_is_a_row_with_its_reason(self):
        # pixel-pendulum and dhnn: skipped by hnn's own check; its hnn runs would be too slow
        # here, so only the skipped row and one cheap task run.
        result = hnn("compare", "--tasks", "spring,pixel-pendulum", "--models", "dhnn",
                     "--seeds", "1", "--steps", "5", "--workers", "1", "--out", self.out)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        doc = read_json(os.path.join(self.out, "compare.json"))
        skipped = [r for r in doc["rows"] if r["status"] == "skipped"]
        self.assertEqual([(r["task"], r["model"]) for r in skipped], [("pixel-pendulum", "dhnn")])
        self.assertIn("does not train a dhnn model", skipped[0]["skipped"])
        md = read_text(os.path.join(self.out, "compare.md"))
        self.assertIn(f"| pixel-pendulum | dhnn | derivative | skipped: {skipped[0]['skipped']} |",
                      md)
        results = read_json(os.path.join(self.out, "results.json"))
        self.assertEqual([r["run"] for r in results["runs"]], ["spring/dhnn/seed=0,steps=5"])


if __name__ == "__main__":
    unittest.main()
