"""The tables of bench/compare/compare.py: medians per case, thread count and implementation,
the ratios torch/hnn, each side at its own best thread count, hnn's fraction of the FMA peak,
and the runs where a side's 2 threads were slower than its 1."""
import statistics

IMPLS = ("hnn", "pytorch", "libtorch")
NAMES = {"hnn": "hnn", "pytorch": "PyTorch", "libtorch": "LibTorch"}


def summarise(runs, cases, threads_list, peaks=None):
    """One row per case and thread count: each implementation's median ms/step and losses,
    torch/hnn, hnn's GEMM flops per step and their fraction of the FMA peak (`peaks`:
    {dtype: {threads: GFLOP/s}}), hnn's op count per step (the nodes its step records on the
    tape, forward and backward), and `slower_than_1` for a side whose time at this thread count
    is worse than its own at 1 thread."""
    rows = []
    for threads in threads_list:
        for case in cases:
            row = {"case": case, "threads": threads}
            for impl in IMPLS:
                mine = [r for r in runs if r["case"] == case and r["threads"] == threads
                        and r["impl"] == impl]
                if mine:
                    row[impl] = {"ms": statistics.median(r["ms_per_step"] for r in mine),
                                 "runs": [round(r["ms_per_step"], 4) for r in mine],
                                 "train_loss": statistics.median(r["train_loss"] for r in mine),
                                 "test_loss": statistics.median(r["test_loss"] for r in mine)}
                    flops = [r["gemm_flops_per_step"] for r in mine if "gemm_flops_per_step" in r]
                    peak = (peaks or {}).get(mine[0]["dtype"], {}).get(str(threads))
                    if flops and peak:
                        row[impl]["gemm_gflop"] = flops[0] / 1e9
                        row[impl]["of_peak"] = flops[0] / (peak * 1e9 * row[impl]["ms"] / 1e3)
                    nodes = [r["tape_nodes_per_step"] for r in mine if "tape_nodes_per_step" in r]
                    if nodes:
                        row[impl]["tape_nodes"] = nodes[0]
            if "hnn" in row:
                for impl in ("pytorch", "libtorch"):
                    if impl in row:
                        row[f"{impl}/hnn"] = row[impl]["ms"] / row["hnn"]["ms"]
            rows.append(row)
    mark_slower(rows)
    return rows


def mark_slower(rows):
    one = {(r["case"], i): r[i]["ms"] for r in rows if r["threads"] == 1 for i in IMPLS if i in r}
    for row in rows:
        for impl in IMPLS:
            base = one.get((row["case"], impl))
            if impl in row and row["threads"] > 1 and base is not None:
                row[impl]["slower_than_1"] = row[impl]["ms"] > base


def best_against_best(rows, cases):
    """Per case, each side at its own faster thread count, and PyTorch's best / hnn's best; with
    several rounds also the lowest and highest ratio of one round's two runs (`round_ratios`):
    each round runs both sides minutes apart at most, so the spread shows how far the machine's
    load moved the ratio, which the medians hide."""
    best = []
    for case in cases:
        mine = [r for r in rows if r["case"] == case]
        entry = {"case": case}
        for impl in IMPLS:
            timed = [(r[impl]["ms"], r["threads"], r[impl]["runs"]) for r in mine if impl in r]
            if timed:
                ms, threads, runs = min(timed, key=lambda t: t[:2])
                entry[impl] = {"ms": ms, "threads": threads, "runs": runs}
        if "hnn" in entry and "pytorch" in entry:
            entry["pytorch/hnn"] = entry["pytorch"]["ms"] / entry["hnn"]["ms"]
            paired = [t / h for h, t in zip(entry["hnn"]["runs"], entry["pytorch"]["runs"])]
            if len(paired) > 1:
                entry["round_ratios"] = (min(paired), max(paired))
        best.append(entry)
    return best


def fmt_ms(row, impl):
    if impl not in row:
        return "-"
    mark = " (slower than 1 thread)" if row[impl].get("slower_than_1") else ""
    return f"{row[impl]['ms']:.3f}{mark}"


def peer_markdown(checks):
    """The peers' float64 losses side by side, with their relative difference."""
    lines = ["", "Same computation: the peers' cases in float64 from hnn's initial parameters "
             "(train and test loss after the timing steps, 1 thread):", "",
             "| case | steps | train loss hnn | train loss PyTorch | test loss hnn | "
             "test loss PyTorch | largest relative difference |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for case in dict.fromkeys(c["case"] for c in checks):
        by = {c["impl"]: c for c in checks if c["case"] == case}
        if "hnn" not in by or "pytorch" not in by:
            continue
        h, t = by["hnn"], by["pytorch"]
        rel = max(abs(h[k] - t[k]) / max(abs(h[k]), abs(t[k]), 1e-300)
                  for k in ("train_loss", "test_loss"))
        lines.append(f"| {case} | {h['steps']} | {h['train_loss']:.15g} | {t['train_loss']:.15g} "
                     f"| {h['test_loss']:.15g} | {t['test_loss']:.15g} | {rel:.1e} |")
    return lines


def machine_line(meta):
    peaks = meta.get("fma_peak_gflops", {})
    peak_text = "; ".join(f"{dtype} {', '.join(f'{v:.0f} ({t} thr)' for t, v in by.items())}"
                          for dtype, by in peaks.items())
    return (f"Measured {meta['date']} on {meta['cpu']} (family {meta.get('cpu_family', '?')}, "
            f"model {meta.get('cpu_model', '?')}; {meta['cpus']} CPUs), hnn {meta['commit']};"
            f" FMA peak GFLOP/s: {peak_text or 'not measured'};"
            f" load average {meta['load_start']:.1f} at the start, {meta['load_end']:.1f} at the"
            f" end; {meta['rounds']} rounds, medians; env: {meta['env']}.{peak_warning(meta)}")


def peak_warning(meta, tolerance=0.9):
    """A sentence when the FMA peak read before the runs and after them disagree: the machine
    did not give the runs the same cores throughout, and their times are suspect."""
    reads = meta.get("fma_peak_reads")
    if not reads:
        return ""
    odd = [f"{dtype} at {t} thr {v:.0f} before, {reads['end'][dtype][t]:.0f} after"
           for dtype, by in reads["start"].items() for t, v in by.items()
           if min(v, reads["end"][dtype][t]) < tolerance * max(v, reads["end"][dtype][t])]
    if not odd:
        return ""
    return (" **The FMA peak moved during this run** (" + "; ".join(odd) + "): the machine did"
            " not give it the same cores throughout; repeat the comparison before quoting it.")


def main_table(rows):
    lines = ["| case | threads | hnn ms/step | PyTorch ms/step | LibTorch ms/step | PyTorch/hnn |"
             " LibTorch/hnn | hnn GEMM GFLOP/step, of FMA peak | hnn tape nodes/step |"
             " train loss hnn / PyTorch / LibTorch |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for row in rows:
        ratio = lambda k: f"{row[k]:.2f}x" if k in row else "-"
        losses = " / ".join(f"{row[i]['train_loss']:.4g}" if i in row else "-" for i in IMPLS)
        h = row.get("hnn", {})
        peak = f"{h['gemm_gflop']:.3g}, {h['of_peak']:.2f}" if "of_peak" in h else "-"
        nodes = h.get("tape_nodes", "-")
        lines.append(f"| {row['case']} | {row['threads']} | {fmt_ms(row, 'hnn')} | "
                     f"{fmt_ms(row, 'pytorch')} | {fmt_ms(row, 'libtorch')} | "
                     f"{ratio('pytorch/hnn')} | {ratio('libtorch/hnn')} | {peak} | {nodes} | "
                     f"{losses} |")
    return lines


def best_table(best):
    lines = ["", "Each side at its own faster thread count (the ratio's range: its lowest and highest"
             " in one round):", "",
             "| case | hnn ms/step (threads) | PyTorch ms/step (threads) | PyTorch/hnn |"
             " range over rounds |",
             "| --- | --- | --- | --- | --- |"]
    for b in best:
        cell = lambda i: f"{b[i]['ms']:.3f} ({b[i]['threads']})" if i in b else "-"
        ratio = f"{b['pytorch/hnn']:.2f}x" if "pytorch/hnn" in b else "-"
        spread = "{:.2f}-{:.2f}x".format(*b["round_ratios"]) if "round_ratios" in b else "-"
        lines.append(f"| {b['case']} | {cell('hnn')} | {cell('pytorch')} | {ratio} | {spread} |")
    return lines


def markdown(meta, rows, best, checks, peer_checks_run=()):
    lines = [machine_line(meta), ""] + main_table(rows)
    if len({r["threads"] for r in rows}) > 1:
        lines += best_table(best)
    if checks:
        lines += ["", "Same computation: spring HNN, 2000 full-batch steps on "
                  "spring_seed0.f64 from hnn's initial parameters (reference f32: train 0.0350,"
                  " test 0.0404):", "", "| implementation | dtype | train loss | test loss |",
                  "| --- | --- | --- | --- |"]
        for c in checks:
            lines.append(f"| {c['impl']} | {c['dtype']} | {c['train_loss']:.6g} | "
                         f"{c['test_loss']:.6g} |")
    if peer_checks_run:
        lines += peer_markdown(peer_checks_run)
    return "\n".join(lines) + "\n"
