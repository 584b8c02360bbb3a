#!/usr/bin/python3
"""Charts of the pixel pendulum (task 5) and of reversibility, from an hnn results folder.

Usage: /usr/bin/python3 scripts/plot_pixel.py RESULTS_DIR
--help says what it reads and writes; the charts are drawn by scripts/charts/ (charts/pixel.py).
"""

import sys

from charts import pixel

if __name__ == "__main__":
    sys.exit(pixel.main(sys.argv[1:]))
