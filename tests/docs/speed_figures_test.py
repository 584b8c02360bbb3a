"""Every speed figure in the documents names the machine it was measured on (issue 32).

A figure (a number in ms/step, ms per step or GFLOP/s, or a table with such a column) must share
its block (the lines up to a blank line) with a machine's name ("AMD EPYC", "Zen", "Xeon"), or
find it in the heading and first block of its section; a table may also name it in the line
under it or in the sentence that introduces it.
"""

import pathlib
import re
import unittest

ROOT = pathlib.Path(__file__).resolve().parents[2]
UNIT = r"(ms/step|ms per step|ms a step|GFLOP/s)"
FIGURE = re.compile(r"\d\s*" + UNIT, re.IGNORECASE)
TABLE_COLUMN = re.compile(r"^\s*\|.*" + UNIT, re.IGNORECASE)
MACHINE = re.compile(r"AMD EPYC|\bZen\b|Xeon")


def documents():
    """README.md, docs/*.md, physics/README.md and the examples' READMEs."""
    return ([ROOT / "README.md", ROOT / "physics" / "README.md",
             ROOT / "bench" / "compare" / "README.md"] + sorted(ROOT.glob("docs/*.md")) +
            sorted(ROOT.glob("examples/**/README*")))


def blocks(text):
    """[heading, first line number, lines] of each run of non-blank lines outside code fences;
    heading is the section's heading line ('' before the first)."""
    found, current, heading, fenced = [], None, "", False
    for number, line in enumerate(text.splitlines(), start=1):
        fence = line.lstrip().startswith("```")
        if fence:
            fenced = not fenced
        is_heading = not fenced and line.startswith("#")
        if fence or fenced or not line.strip() or is_heading:
            current = None
            heading = line.strip() if is_heading else heading
            continue
        if current is None:
            current = [heading, number, []]
            found.append(current)
        current[2].append(line)
    return found


def names_machine(lines):
    return any(MACHINE.search(line) for line in lines)


def unattributed(text):
    """Line numbers of speed figures that name no machine where this module's docstring asks."""
    found = blocks(text)
    missing = []
    for index, (heading, start, lines) in enumerate(found):
        figures = [start + i for i, line in enumerate(lines)
                   if FIGURE.search(line) or TABLE_COLUMN.search(line)]
        if not figures:
            continue
        first = next(block for block in found if block[0] == heading)
        near = [lines, [heading], first[2]]
        is_table = lines[0].lstrip().startswith("|")
        if index > 0 and (is_table or found[index - 1][2][-1].rstrip().endswith(":")):
            near.append(found[index - 1][2])
        if is_table and index + 1 < len(found):
            near.append(found[index + 1][2])
        if not any(names_machine(block) for block in near):
            missing += figures
    return missing


class SpeedFigures(unittest.TestCase):
    def test_every_figure_names_its_machine(self):
        for path in documents():
            name = str(path.relative_to(ROOT))
            with self.subTest(path=name):
                lines = unattributed(path.read_text(encoding="utf-8"))
                self.assertEqual(lines, [], f"{name}: the speed figures on lines {lines} name "
                                 "no machine (AMD EPYC, Zen) in their block or section")

    def test_a_figure_without_a_machine_is_found(self):
        text = ("# Title\n\nIntro.\n\nThe step takes 2.4 ms/step on 2 cores.\n\n"
                "| case | ms/step |\n| --- | --- |\n| spring | 2.4 |\n\nAfter.\n")
        self.assertEqual(unattributed(text), [5, 7])

    def test_a_machine_in_the_block_section_or_under_the_table_is_enough(self):
        text = ("The step takes 2.4 ms/step\non a 2-vCPU AMD EPYC, Zen 4.\n\n"
                "| case | GFLOP/s |\n| --- | --- |\n| spring | 50 |\n\n"
                "Measured on the same AMD EPYC.\n\n```\nbench 3 ms/step\n```\n\n"
                "## On Zen 5\n\nA step of 1.5 ms per step.\n\n"
                "## Elsewhere\n\nMeasured on an AMD EPYC:\n\n- 27 GFLOP/s\n\n"
                "Each printing ms per step.\n")
        self.assertEqual(unattributed(text), [])


if __name__ == "__main__":
    unittest.main()
