"""The tables of report.py on hand-made runs (ctest bench.CompareReport)."""
import unittest

from report import best_against_best, best_table, main_table, markdown, summarise


def run(impl, threads, ms, flops=None):
    r = {"case": "c", "impl": impl, "threads": threads, "ms_per_step": ms, "dtype": "float32",
         "train_loss": 1.0, "test_loss": 2.0}
    if flops is not None:
        r["gemm_flops_per_step"] = flops
        r["tape_nodes_per_step"] = 32
    return r


class ReportTest(unittest.TestCase):
    def setUp(self):
        # hnn: 2 threads slower than 1; PyTorch: faster at 2.
        runs = [run("hnn", 2, 3.0, 2e9), run("hnn", 1, 2.0, 2e9),
                run("pytorch", 2, 5.0), run("pytorch", 1, 6.0)]
        self.peaks = {"float32": {"1": 100.0, "2": 200.0}}
        self.rows = summarise(runs, ["c"], [2, 1], self.peaks)
        self.best = best_against_best(self.rows, ["c"])

    def row(self, threads):
        return next(r for r in self.rows if r["threads"] == threads)

    def test_a_side_slower_on_two_threads_than_on_one_is_marked(self):
        self.assertTrue(self.row(2)["hnn"]["slower_than_1"])
        self.assertFalse(self.row(2)["pytorch"]["slower_than_1"])
        self.assertNotIn("slower_than_1", self.row(1)["hnn"])

    def test_best_against_best_takes_each_side_at_its_faster_thread_count(self):
        b = self.best[0]
        self.assertEqual((b["hnn"]["ms"], b["hnn"]["threads"]), (2.0, 1))
        self.assertEqual((b["pytorch"]["ms"], b["pytorch"]["threads"]), (5.0, 2))
        self.assertAlmostEqual(b["pytorch/hnn"], 2.5)

    def test_fraction_of_peak_divides_the_gemm_flops_by_the_peak_at_that_thread_count(self):
        # 2 GFLOP in 2 ms on 1 thread = 1000 GFLOP/s against a peak of 100: 10.
        self.assertAlmostEqual(self.row(1)["hnn"]["of_peak"], 2e9 / (100e9 * 2e-3))
        self.assertAlmostEqual(self.row(2)["hnn"]["of_peak"], 2e9 / (200e9 * 3e-3))

    def test_the_markdown_names_the_machine_and_marks_the_slower_side(self):
        meta = {"date": "d", "cpu": "AMD EPYC", "cpu_family": "25", "cpu_model": "17", "cpus": 2,
                "commit": "abc", "load_start": 0.1, "load_end": 0.2, "rounds": 1, "env": "e",
                "fma_peak_gflops": self.peaks}
        text = markdown(meta, self.rows, self.best, [])
        self.assertIn("AMD EPYC (family 25, model 17", text)
        self.assertIn("3.000 (slower than 1 thread)", text)
        self.assertIn("| c | 2.000 (1) | 5.000 (2) | 2.50x | - |", text)

    def test_the_best_ratio_s_range_pairs_the_two_sides_round_by_round(self):
        # Round 1: hnn 2.0, PyTorch 5.0 (2.5x); round 2: 4.0 and 6.0 (1.5x); medians 3.0, 5.5.
        runs = [run("hnn", 1, 2.0), run("pytorch", 1, 5.0), run("hnn", 1, 4.0),
                run("pytorch", 1, 6.0)]
        best = best_against_best(summarise(runs, ["c"], [1]), ["c"])[0]
        self.assertAlmostEqual(best["pytorch/hnn"], 5.5 / 3.0)
        self.assertEqual(best["round_ratios"], (1.5, 2.5))
        self.assertIn("| 1.83x | 1.50-2.50x |", "\n".join(best_table([best])))

    def test_a_peak_that_moved_between_its_reads_is_reported(self):
        meta = {"date": "d", "cpu": "AMD EPYC", "cpus": 2, "commit": "abc", "load_start": 0.1,
                "load_end": 0.2, "rounds": 1, "env": "e", "fma_peak_gflops": self.peaks,
                "fma_peak_reads": {"start": {"float64": {"2": 49.0, "1": 49.0}},
                                   "end": {"float64": {"2": 98.0, "1": 48.0}}}}
        text = markdown(meta, self.rows, self.best, [])
        self.assertIn("The FMA peak moved during this run** (float64 at 2 thr 49 before, 98 after)",
                      text)
        meta["fma_peak_reads"]["end"]["float64"]["2"] = 50.0
        self.assertNotIn("moved", markdown(meta, self.rows, self.best, []))

    def test_the_main_table_gives_hnn_s_op_count_per_step(self):
        self.assertEqual(self.row(1)["hnn"]["tape_nodes"], 32)
        self.assertNotIn("tape_nodes", self.row(1)["pytorch"])
        self.assertIn("| 2, 10.00 | 32 |", "\n".join(main_table(self.rows)))


if __name__ == "__main__":
    unittest.main()
