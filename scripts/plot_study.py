#!/usr/bin/python3
"""The charts and tables of a study that `hnn sweep` ran from a spec of sweeps/.

Usage: /usr/bin/python3 scripts/plot_study.py STUDY SWEEP_DIR [--out DIR]
       STUDY: model_size, data_results, dhnn or rollout (sweeps/STUDY.yaml)
--help says what each draws; the charts are drawn by scripts/charts/ (charts/studies.py).
"""

import sys

from charts import studies

if __name__ == "__main__":
    sys.exit(studies.main(sys.argv[1:]))
