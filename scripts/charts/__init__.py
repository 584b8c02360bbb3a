"""The charts and results tables of hnn's docs, one module per figure (matplotlib, Agg; every
chart as PNG and SVG, written atomically).

Commands (thin entry points in scripts/, each with --help):
  scripts/plot.py RESULTS_DIR | --runs RUN... --out DIR | --rollouts CSV... --out DIR
                                                          paper.py: Figures 2 and 3, training
                                                          curves, the Table 1 chart; runs.py:
                                                          the charts of run folders and of
                                                          rollout files
  scripts/plot_pixel.py RESULTS_DIR                       pixel.py: Figures 4, C1, 5, reversibility
  scripts/plot_speed_accuracy.py DIR                      speed_accuracy.py: bench/accuracy's charts
  scripts/plot_study.py STUDY SWEEP_DIR [--out DIR]       studies.py: a study of sweeps/ from
                                                          hnn sweep's results.csv

Modules:
  common           backend and style, errors and notes, readers, names and colours, atomic writer
  rollout          rollout.csv (and hnn rollout's files, either layout), and the coordinate-MSE
                   and energy panels of Figures 2 and 3
  runs             run folders (--runs) and rollout files (--rollouts): which charts each gets
  h_contour        the learned H beside the true one over the phase plane (one degree of freedom)
  fig2, fig3       the paper's Figures 2 (phase space, MSE, conserved H, energy) and 3 (orbits)
  training_curves  train and test loss against the step
  table1           table1.json, and ours against the paper's Table 1
  fig4_pixel       the pixel pendulum's frames, frame MSE and energy (Figure 4)
  latent           the pixel HNN's learned H over its latent plane (Figure C1)
  bump             the energy bump (Figure 5)
  reversibility    forward-then-backward return distance and |log det| of the flow map
  fd_error, fd_time              autodiff against finite differences: error, time
  work_precision, energy_drift   the integrators: work-precision, long-horizon energy error
  sweep_table      hnn sweep's results.csv, and the mean and standard error over seeds
  float_double, model_size, lean charts 3 and 4 of docs/speed_accuracy.md, the lean table
  data_table, dhnn_table, rollout_table   the results tables of docs/data_results.md and
                                          docs/families.md
"""
