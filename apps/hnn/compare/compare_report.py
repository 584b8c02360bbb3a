"""hnn compare's report, written by the sweep driver when its plan has a "compare" section (see
apps/hnn/compare/command.cpp): OUT/compare.json and OUT/compare.md, ours (mean ± standard error
over the seeds) beside each peer's published number, and OUT/accuracy_vs_time.png.

Everything is keyed on metrics.json's keys and the peers file: a new model family, task or
metric appears here once its runs write it and the peers file names it, without code changes."""

import json
import math
import os

import sweep_report

TIME_KEY = "train_seconds"
NOT_MEASURED = "not measured by hnn yet"


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def mean_se(values):
    """Mean and standard error (sample standard deviation / sqrt(n)); the error is None for one
    value."""
    n = len(values)
    m = sum(values) / n
    if n < 2:
        return m, None
    return m, math.sqrt(sum((v - m) ** 2 for v in values) / (n - 1) / n)


def fmt_value(mean, se=None):
    if mean is None:
        return ""
    text = f"{mean:.3e}"
    return text if se is None else f"{text} ± {se:.1e}"


def headline_of(section, row):
    """The row's own (its protocol's), else the peers file's for its task, else its default."""
    if row.get("headline"):
        return row["headline"]
    headline = section.get("headline", {})
    return headline.get(row["task"], headline.get("default", "test_loss"))


def settings_hold(peer, row):
    """A peer's protocol settings (e.g. SRNN's {"setup": "srnn"}) are all the row's; the HNN
    paper's Table 1 holds for a row at the task's own settings only."""
    mine = (row.get("keys") or {}).get("settings") or {}
    if peer.get("task_defaults_only") and mine:
        return False
    return all(mine.get(k) == v for k, v in (peer.get("settings") or {}).items())


def keys_hold(peer, row):
    """A peer's protocol options (e.g. the D-HNN paper's {"data": "real_pend_h_1.txt", "lr":
    0.005}) are all the row's; a data file is compared by its name."""
    mine = row.get("keys") or {}
    for k, v in (peer.get("keys") or {}).items():
        got = mine.get(k)
        if k == "data" and isinstance(got, str):
            got = os.path.basename(got)
        if got != v:
            return False
    return True


def same_pair(peer, row):
    return (peer.get("model") is not None and peer["task"] == row["task"]
            and peer["model"] == row["model"] and (peer.get("loss") or "derivative") == row["loss"])


def peer_matches(peer, row):
    return same_pair(peer, row) and settings_hold(peer, row) and keys_hold(peer, row)


def row_label(row):
    """The task and loss cells: the protocol's settings and rollout keys when the row has them."""
    keys = dict(row.get("keys") or {})
    task = row["task"]
    if keys.get("data"):
        task += " " + os.path.basename(keys.pop("data"))
    if keys.get("settings"):
        task += " " + json.dumps(keys.pop("settings"))
    loss = row["loss"]
    extra = ", ".join(f"{k} {json.dumps(v) if isinstance(v, (str, list)) else v}"
                      for k, v in keys.items())
    return task, f"{loss} ({extra})" if extra else loss


def geometric_mean_se(values):
    """exp(mean(log v)) and its standard error by the delta method (g times the standard error of
    the logs), for errors the peer pools geometrically; with a value <= 0, the arithmetic ones."""
    if any(v <= 0 for v in values):
        return mean_se(values)
    m, se = mean_se([math.log(v) for v in values])
    g = math.exp(m)
    return g, (None if se is None else g * se)


def summarise(row, by_run, geometric=()):
    """The row's runs: their states, and the mean and error of every numeric metric (geometric
    for the peers file's geometric_metrics)."""
    runs = [by_run[name] for name in row["runs"] if name in by_run]
    done = [r for r in runs if r["status"] == "done"]
    failed = [{"run": r["run"], "reason": r["reason"]} for r in runs if r["status"] == "failed"]
    flat = [sweep_report.table_metrics(r["metrics"]) for r in done]  # fit_solve_seconds, ...
    keys = sorted({k for m in flat for k, v in m.items() if is_number(v)})
    metrics = {}
    for k in keys:
        values = [m[k] for m in flat if is_number(m.get(k))]
        m, se = geometric_mean_se(values) if k in geometric else mean_se(values)
        metrics[k] = {"mean": m, "se": se, "n": len(values)}
    if row["skipped"]:
        status = "skipped"
    elif len(done) == len(runs):
        status = "done"
    elif done:
        status = "partial"
    else:
        status = "failed" if failed else "pending"
    return status, len(done), failed, metrics


def row_lines(row, section, metrics, peers):
    """The table lines of a row: its headline metric, the report's metrics that its runs have,
    each peer's number on its metric (or 'not measured by hnn yet'), and the training time."""
    wanted = [headline_of(section, row)]
    for k in section.get("report_metrics", []) + row.get("metrics", []):
        if k in metrics and k not in wanted:
            wanted.append(k)
    for p in peers:
        if p.get("metric") and p["metric"] not in wanted:
            wanted.append(p["metric"])
    lines = []
    for k in wanted:
        ours = metrics.get(k)
        mine = [p for p in peers if p.get("metric") == k]
        for p in mine or [None]:
            lines.append({"metric": k, "ours": ours, "peer": p})
    for p in peers:
        if not p.get("metric"):
            lines.append({"metric": None, "ours": None, "peer": p})
    lines.append({"metric": TIME_KEY, "ours": metrics.get(TIME_KEY), "peer": None})
    return lines


def unmatched_reason(peer, section, rows, hnn_tasks, models_run):
    if peer["task"] not in hnn_tasks:
        return f"hnn has no task '{peer['task']}' yet"
    if peer.get("model") is None:
        return f"no hnn model family for {peer['peer_model']}"
    for row in rows:
        if peer_matches(peer, row) and row["skipped"]:
            return f"skipped: {row['skipped']}"
    for row in rows:
        if same_pair(peer, row) and not settings_hold(peer, row):
            return ("the paper's settings are not this comparison's"
                    if peer.get("task_defaults_only") else
                    f"their protocol's settings {json.dumps(peer['settings'])} are not this "
                    "comparison's")
        if same_pair(peer, row) and not keys_hold(peer, row):
            return (f"their protocol's options {json.dumps(peer['keys'])} are not this "
                    "comparison's")
    if peer["model"] not in models_run:
        return f"model '{peer['model']}' not in this comparison"
    return f"loss '{peer.get('loss') or 'derivative'}' not in this comparison"


def model_label(row):
    """The model column: the family, and the fit where it is not Adam ("hnn (sampled)")."""
    fit = row.get("fit", "adam")
    return row["model"] if fit == "adam" else f"{row['model']} ({fit})"


def build(plan, table):
    section = plan["compare"]
    by_run = {r["run"]: r for r in table}
    peers = section["peers"]
    rows = []
    for row in section["rows"]:
        status, done, failed, metrics = summarise(row, by_run,
                                                  section.get("geometric_metrics", []))
        mine = [p for p in peers if peer_matches(p, row)] if not row["skipped"] else []
        rows.append({"task": row["task"], "model": model_label(row), "loss": row["loss"],
                     "fit": row.get("fit", "adam"),
                     "keys": row.get("keys") or {}, "status": status, "skipped": row["skipped"], "runs": row["runs"],
                     "seeds_done": done, "failed": failed,
                     "headline": headline_of(section, row), "metrics": metrics,
                     "lines": row_lines(row, section, metrics, mine) if not row["skipped"] else []})
    tasks = {r["task"] for r in section["rows"]}
    models_run = {r["model"] for r in section["rows"] if not r["skipped"]}
    matched = {id(line["peer"]) for r in rows for line in r["lines"] if line["peer"]}
    unmatched, elsewhere = [], 0
    for p in peers:
        if id(p) in matched:
            continue
        if p["task"] in tasks or p["task"] not in section["hnn_tasks"]:
            unmatched.append({**p, "why": unmatched_reason(p, section, section["rows"],
                                                          section["hnn_tasks"], models_run)})
        else:
            elsewhere += 1
    return {"command": section["command"], "seeds": section["seeds"], "steps": section["steps"],
            "peers_file": section["peers_file"], "out": plan["out"], "rows": rows,
            "unmatched_peers": unmatched, "peers_on_tasks_not_compared": elsewhere}


def peer_cells(p):
    if p is None:
        return "", ""
    number = fmt_value(p["value"], p.get("se"))
    who = f"{p['peer']}: {p['peer_model']}"
    if p.get("n"):
        who += f" ({p['n']})"
    return number, who


def markdown(doc):
    md = [f"# hnn compare\n",
          f"`{doc['command']}`\n",
          f"Ours: the mean ± standard error over the seeds that finished (of {doc['seeds']} per "
          f"row: seeds 0..{doc['seeds'] - 1}; steps: {doc['steps']}"
          + ("" if isinstance(doc["steps"], str) else
             ", not each task's default: the peers' numbers are at their own settings")
          + "), one line per metric of "
          "metrics.json. Peers: their published number on the same metric and protocol, from "
          f"`{os.path.basename(doc['peers_file'])}` (its entries name their sources; the HNN "
          "paper's Table 1 among them, as `hnn reproduce` reads it). A peer number whose "
          f"protocol hnn does not measure yet says \"{NOT_MEASURED}\" rather than sit beside "
          "another quantity. Footnotes give each peer's protocol.\n",
          "| task | model | loss | metric | ours | seeds | peer's number | peer |",
          "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    notes = []

    def note_of(p):
        if p is None:
            return ""
        text = p.get("protocol", "")
        if p.get("note"):
            text += ("; " if text else "") + p["note"]
        text = f"{text} (source: {p['source']})"
        if text not in notes:
            notes.append(text)
        return f" [{notes.index(text) + 1}]"

    for r in doc["rows"]:
        task, loss = row_label(r)
        head = f"| {task} | {r['model']} | {loss} |"
        if r["skipped"]:
            md.append(f"{head} skipped: {r['skipped']} | | | | |")
            continue
        seeds = f"{r['seeds_done']}/{len(r['runs'])}"
        if r["failed"]:
            seeds += f" ({len(r['failed'])} failed: {r['failed'][0]['reason']})"
        for line in r["lines"]:
            p, ours = line["peer"], line["ours"]
            if not r["seeds_done"]:
                ours_text = f"no finished run ({r['status']})"
            elif line["metric"] is None or ours is None:
                ours_text = NOT_MEASURED if p is not None else "n/a"
            else:
                ours_text = fmt_value(ours["mean"], ours["se"])
            number, who = peer_cells(p)
            metric = line["metric"] or "(their protocol)"
            md.append(f"{head} {metric} | {ours_text} | {seeds} | {number} | {who}{note_of(p)} |")
            head = "| | | |"
    if doc["unmatched_peers"]:
        md += ["\n## Published numbers with no row above\n",
               "| task | peer | their model | number | why no row |",
               "| --- | --- | --- | --- | --- |"]
        for p in doc["unmatched_peers"]:
            number, _ = peer_cells(p)
            md.append(f"| {p['task']} | {p['peer']} | {p['peer_model']} | {number} | "
                      f"{p['why']}{note_of(p)} |")
    if doc["peers_on_tasks_not_compared"]:
        md.append(f"\n{doc['peers_on_tasks_not_compared']} more published numbers are on hnn tasks "
                  f"this comparison leaves out (`{os.path.basename(doc['peers_file'])}`).")
    if notes:
        md.append("\n## Protocols and sources\n")
        md += [f"{i + 1}. {n}" for i, n in enumerate(notes)]
    md.append("\nChart: `accuracy_vs_time.png`, one panel per task: each row's headline metric "
              "against its training time (log-log), one colour per model family and loss; a dashed line "
              "at the peer's published number on the same metric.")
    return "\n".join(md) + "\n"


def draw(doc, path):
    """One panel per task (its headline metric differs from task to task): each row's headline
    against its training time, log-log, one colour per model family and loss."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    tasks = sweep_report.ordered(r["task"] for r in doc["rows"])
    cols = min(3, len(tasks))
    rows_n = (len(tasks) + cols - 1) // cols
    # The title wraps to the figure's width and adds to its height.
    heading = sweep_report.title_lines("accuracy against training time (mean ± standard error "
                                       "over seeds; dashed: the peer's published number for that "
                                       "family)", 4.2 * cols)
    height = 3.4 * rows_n + 0.2 * len(heading)
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, height), squeeze=False)
    colours = {}
    for ax, task in zip(axes.flat, tasks):
        headline = title = None
        for r in doc["rows"]:
            if r["task"] != task:
                continue
            headline = headline or r["headline"]
            title = title or row_label(r)[0]
            y, x = r["metrics"].get(r["headline"]), r["metrics"].get(TIME_KEY)
            if not y or not x or y["mean"] <= 0 or x["mean"] <= 0:
                continue
            family = r["model"] + ("" if r["loss"] == "derivative" else f" ({r['loss']} loss)")
            colours.setdefault(family, f"C{len(colours) % 10}")
            ax.errorbar([x["mean"]], [y["mean"]],
                        yerr=[[min(y["se"] or 0, y["mean"] * 0.999)], [y["se"] or 0]],
                        xerr=[[min(x["se"] or 0, x["mean"] * 0.999)], [x["se"] or 0]],
                        marker="o", color=colours[family], capsize=3, linestyle="none")
            for line in r["lines"]:  # the peer's number on the same metric: a dashed line
                p = line["peer"]
                if line["metric"] == r["headline"] and p and p["value"] > 0:
                    ax.axhline(p["value"], color=colours[family], linestyle="--", linewidth=0.8)
        if ax.has_data():
            ax.set_xscale("log")
            ax.set_yscale("log")
            sweep_report.readable_log_ticks(ax)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("train_seconds (s)", fontsize=8)
        ax.set_ylabel(headline or "", fontsize=8)
        ax.tick_params(which="both", labelsize=7)
    for ax in list(axes.flat)[len(tasks):]:
        ax.axis("off")
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color=c, marker="o", linestyle="none", label=f)
               for f, c in colours.items()]
    legend_cols = max(1, min(len(handles), 2 * cols))
    legend_rows = -(-len(handles) // legend_cols)
    fig.legend(handles=handles, fontsize=8, loc="lower center", ncol=legend_cols, frameon=False)
    fig.suptitle("\n".join(heading), fontsize=10)
    fig.tight_layout(rect=(0, (0.1 + 0.2 * legend_rows) / height, 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write(plan, table):
    """OUT/compare.json, OUT/compare.md and OUT/accuracy_vs_time.png; returns their paths."""
    out = plan["out"]
    doc = build(plan, table)
    paths = [os.path.join(out, "compare.json"), os.path.join(out, "compare.md")]
    sweep_report.write_atomic(paths[0], json.dumps(doc, indent=1) + "\n")
    sweep_report.write_atomic(paths[1], markdown(doc))
    chart = os.path.join(out, "accuracy_vs_time.png")
    try:
        draw(doc, chart)
        paths.append(chart)
    except ImportError:
        print("hnn compare: the chart needs matplotlib (Debian: python3-matplotlib)", flush=True)
    return paths
