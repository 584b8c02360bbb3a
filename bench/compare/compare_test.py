"""compare.py's OpenBLAS environment (ctest bench.CompareEnvironment): which kernels the runs get,
read from OpenBLAS itself, and the --coretype it does not honour refused in one line."""
import argparse
import os
import stat
import tempfile
import unittest

import compare


def fake_hnn(folder, stderr):
    """A stand-in for hnn_train_step --fma-peak that prints `stderr` as OpenBLAS would."""
    path = os.path.join(folder, "hnn_train_step")
    with open(path, "w") as f:
        f.write(f"#!/bin/sh\nprintf '{stderr}' >&2\necho '{{\"fma_peak_gflops\": 1}}'\n")
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
    return path


class CoreTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def args(self, coretype):
        return argparse.Namespace(coretype=coretype)

    def test_auto_leaves_the_choice_to_openblas_even_when_the_machine_exports_one(self):
        os.environ["OPENBLAS_CORETYPE"] = "Haswell"
        self.addCleanup(os.environ.pop, "OPENBLAS_CORETYPE")
        self.assertNotIn("OPENBLAS_CORETYPE", compare.tuned_env(self.args("auto"), 2))
        self.assertEqual(compare.tuned_env(self.args("Zen"), 2)["OPENBLAS_CORETYPE"], "Zen")

    def test_the_core_openblas_reports_is_recorded(self):
        hnn = fake_hnn(self.dir.name, "Core: Zen\\n")
        self.assertEqual(compare.blas_core(self.args("auto"), hnn), "Zen")
        self.assertIn("OpenBLAS core Zen (its own pick)",
                      compare.env_line(self.args("auto"), "Zen"))

    def test_a_core_openblas_does_not_have_is_refused_naming_what_it_ran(self):
        hnn = fake_hnn(self.dir.name, "Core not found: Cooperlake\\nCore: Haswell\\n")
        with self.assertRaises(SystemExit) as e:
            compare.blas_core(self.args("Cooperlake"), hnn)
        self.assertIn("--coretype Cooperlake: this OpenBLAS has no such core (it ran Haswell",
                      str(e.exception))


class CasesTest(unittest.TestCase):
    def test_groups_and_names_mix_and_each_case_runs_once(self):
        cases = compare.expand_cases("spring-hnn-f64,peers,chain2-chnn-f32")
        self.assertEqual(cases[0], "spring-hnn-f64")
        self.assertEqual(cases[1:], compare.GROUPS["peers"])
        self.assertEqual(len(cases), len(set(cases)))

    def test_an_unknown_name_is_refused_naming_it(self):
        with self.assertRaises(SystemExit) as e:
            compare.expand_cases("peers,spring-hnn-f16")
        self.assertIn("unknown case spring-hnn-f16", str(e.exception))


if __name__ == "__main__":
    unittest.main()
