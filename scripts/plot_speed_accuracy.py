#!/usr/bin/python3
"""Draws the speed-against-accuracy charts from the CSV files of bench/accuracy/.

Usage: /usr/bin/python3 scripts/plot_speed_accuracy.py DIR
--help says what it reads and writes; the charts are drawn by scripts/charts/
(charts/speed_accuracy.py).
"""

import sys

from charts import speed_accuracy

if __name__ == "__main__":
    sys.exit(speed_accuracy.main(sys.argv[1:]))
