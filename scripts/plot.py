#!/usr/bin/python3
"""Every chart of an `hnn reproduce` results folder, or Figure 2 of `hnn train` run folders.

Usage: /usr/bin/python3 scripts/plot.py RESULTS_DIR
       /usr/bin/python3 scripts/plot.py --runs RUN [RUN ...] --out DIR
--help says what each writes; the charts are drawn by scripts/charts/ (charts/paper.py).
"""

import sys

from charts import paper

if __name__ == "__main__":
    sys.exit(paper.main(sys.argv[1:]))
