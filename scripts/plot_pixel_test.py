#!/usr/bin/python3
"""Tests scripts/plot_pixel.py (scripts/charts/: fig4_pixel, latent, bump, reversibility) on
synthetic pixel-pendulum files.

Usage: /usr/bin/python3 scripts/plot_pixel_test.py [-v]
"""

import json
import os
import shutil
import tempfile
import unittest

import numpy as np

from plot_fixtures import MODELS, SCRIPTS, png_size, run_plot


def write_pixel_results(root):
    """The files `hnn reproduce`, `hnn bump` and `hnn reversibility --report` write for the pixel
    pendulum: rollouts of decoded frames, the latent grid and paths, the bump, the strip."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    for m in MODELS:
        folder = os.path.join(root, "pixel-pendulum", m)
        os.makedirs(folder, exist_ok=True)
        drift = 0.01 if m == "baseline" else 0.001
        with open(os.path.join(folder, "pixel_rollout.csv"), "w") as f:
            f.write("traj,frame,frame_mse,true_energy,pred_energy,pred_theta,true_theta\n")
            for k in range(3):
                for i in range(40):
                    f.write(f"{k},{i},{1e-3 * (1 + drift * 10 * i):.6g},{1 + 0.1 * k:.6g},"
                            f"{1 + 0.1 * k + drift * i:.6g},{np.sin(i / 5):.6g},"
                            f"{np.sin(i / 5):.6g}\n")
        with open(os.path.join(folder, "latent_grid.csv"), "w") as f:
            f.write("z_q,z_p,learned_h,dz_q,dz_p\n")
            for a in np.linspace(-1, 1, 10):
                for b in np.linspace(-1, 1, 10):
                    h = "" if m == "baseline" else f"{a * a + b * b:.6g}"
                    f.write(f"{a:.6g},{b:.6g},{h},{b:.6g},{-a:.6g}\n")
        with open(os.path.join(folder, "latent_paths.csv"), "w") as f:
            f.write("traj,k,z_q,z_p\n")
            for k, r in enumerate((0.3, 0.6)):
                for i in range(30):
                    f.write(f"{k},{i},{r * np.cos(i / 5):.6g},{r * np.sin(i / 5):.6g}\n")
    with open(os.path.join(root, "pixel-pendulum", "hnn", "bump.csv"), "w") as f:
        f.write("phase,t,z_q,z_p,learned_h,energy\n")
        for t in range(60):
            phase = ("symplectic", "riemann", "symplectic-after")[t // 20]
            r = 0.5 + 0.3 * min(max(t - 20, 0), 19) / 19
            f.write(f"{phase},{t},{r * np.cos(t / 5):.6g},{r * np.sin(t / 5):.6g},{r * r:.6g},"
                    f"{1.1 * r * r:.6g}\n")
    strip = np.random.default_rng(0).random((90, 5 * 58 + 2))
    plt.imsave(os.path.join(root, "pixel-pendulum", "rollout_strip.png"), strip, cmap="gray")
    with open(os.path.join(root, "reversibility.json"), "w") as f:
        json.dump([{"task": "pixel-pendulum", "model": m, "volume": {"abs_log_det_mean": 1e-6},
                    "integrators": [{"integrator": name, "return_distance_mean": 1e-7 * (j + 1)}
                                    for j, name in enumerate(["midpoint", "rk4", "dopri5"])]}
                   for m in MODELS], f)


class PixelTest(unittest.TestCase):
    def test_draws_the_pixel_figures_and_reversibility(self):
        root = tempfile.mkdtemp(prefix="plot_pixel_test_")
        try:
            write_pixel_results(root)
            run = run_plot(root, script=os.path.join(SCRIPTS, "plot_pixel.py"))
            self.assertEqual(run.returncode, 0, run.stderr)
            for stem in ("fig4_pixel_pendulum", "figC1_pixel_latent", "fig5_pixel_bump",
                         "reversibility"):
                png = os.path.join(root, stem + ".png")
                self.assertIn(png, run.stdout.split())
                self.assertGreater(png_size(png)[0], 600, png)
            os.remove(os.path.join(root, "pixel-pendulum", "hnn", "bump.csv"))
            run = run_plot(root, script=os.path.join(SCRIPTS, "plot_pixel.py"))
            self.assertEqual(run.returncode, 0, run.stderr)
            self.assertIn("bump.csv: missing (run `hnn bump`)", run.stderr)
        finally:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
