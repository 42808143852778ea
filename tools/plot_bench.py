#!/usr/bin/python3
"""Plots penumbra_bench JSON: run time against error, one panel per block. Usage (Debian's python3 has matplotlib):
    penumbra_bench --benchmark_format=json > bench.json      (or --benchmark_out=bench.json)
    /usr/bin/python3 tools/plot_bench.py bench.json [more.json ...] -o bench.png   # one PNG, a panel per block
    /usr/bin/python3 tools/plot_bench.py bench.json -o plots/                       # a folder: one PNG per block

A block is a benchmark family, the name before its first '/' (BM_SoftShadows, BM_Pcss, BM_HardShadows,
BM_LutLookup ...). Each entry is one point: its time (the counter `ms` when present, the median of
penumbra's interleaved timing, else real_time in the JSON's time_unit) against its main error
counter, the first present of err_visibility_rmse, err_mismatched_bits, err_mismatch, err_bits,
err_words, else its first err_* counter in name order. Entries that time other methods in the same
run (counters ms_<m>) add a point per method whose error is <main>_<m> or err_<m>, labelled [m]
(one label for the same method's points that several entries put within 5 % of each other).
With --benchmark_repetitions the median aggregate is plotted (else the mean, else the average of the
iterations); entries that report an error are left out with a note. Errors of 0 are drawn on a
dotted line below the smallest nonzero one when the error axis is logarithmic."""
import argparse
import json
import math
import os
import re
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:  # ctest reports exit code 77 as skipped
    print("plot_bench: matplotlib is missing (apt-get install python3-matplotlib)")
    sys.exit(77)

MAIN_ERRORS = ("err_visibility_rmse", "err_mismatched_bits", "err_mismatch", "err_bits", "err_words")
TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
# Google Benchmark's per-run suffixes, not part of the entry's name.
SUFFIX = re.compile(r"/(iterations:\d+|repeats:\d+|min_time:[^/]+|manual_time|real_time|process_time|threads:\d+)(?=/|$)")


def load(path):
    """One penumbra_bench JSON document; tolerates text before it (e.g. a log captured with it)."""
    with open(path) as handle:
        text = handle.read()
    start = text.find("{")
    if start < 0:
        raise ValueError(f"{path}: no JSON object")
    return json.JSONDecoder().raw_decode(text[start:])[0]


def entries(doc, source):
    """(name, time_ms, counters) per entry: the median aggregate, else the mean, else the iterations' average."""
    rows = {}
    order = []
    for b in doc.get("benchmarks", []):
        name = SUFFIX.sub("", b.get("run_name", b["name"]))
        if name not in rows:
            rows[name] = {"iteration": [], "median": None, "mean": None}
            order.append(name)
        if b.get("error_occurred"):
            print(f"plot_bench: {source}: {name} reported an error ({b.get('error_message', '?')}): left out")
            rows[name]["error"] = True
            continue
        if b.get("run_type") == "aggregate":
            if b.get("aggregate_name") in ("median", "mean"):
                rows[name][b["aggregate_name"]] = b
        else:
            rows[name]["iteration"].append(b)
    for name in order:
        r = rows[name]
        if r.get("error"):
            continue
        chosen = [r["median"]] if r["median"] else [r["mean"]] if r["mean"] else r["iteration"]
        if not chosen:
            continue
        counters = {}
        keys = {k for b in chosen for k, v in b.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
        for k in keys:
            values = [b[k] for b in chosen if k in b]
            counters[k] = sum(values) / len(values)
        unit = TO_MS.get(chosen[0].get("time_unit", "ns"), 1e-6)
        time_ms = counters["ms"] if "ms" in counters else counters.get("real_time", float("nan")) * unit
        yield name, time_ms, counters


def main_error(counters):
    for key in MAIN_ERRORS:
        if key in counters:
            return key
    errs = sorted(k for k in counters if k.startswith("err_"))
    return errs[0] if errs else None


def points(name, time_ms, counters):
    """(label, time_ms, error, error_name, is_method) for the entry and the methods it timed."""
    key = main_error(counters)
    if key is None:
        return []
    rest = name.split("/", 1)[1] if "/" in name else ""
    out = [(rest or name, time_ms, counters[key], key, False)]
    for counter in sorted(counters):
        if not counter.startswith("ms_"):
            continue
        method = counter[3:]
        for err in (f"{key}_{method}", f"err_{method}"):
            if err in counters:
                out.append((f"{rest} [{method}]".strip(), counters[counter], counters[err], err, True))
                break
    return out


def near(a, b):
    """Two positive values within 5 % of each other (equal zeros too)."""
    if a == b:
        return True
    return a > 0 and b > 0 and abs(math.log(a / b)) < 0.05


def labels(chosen, xs, ys, is_method):
    """(text, x, y) per label. The same method timed again in several entries of a block (e.g. ours
    beside every map size) lands on nearly one spot: those points get one label, '[m] (k entries)'."""
    if not is_method:
        return [(p[0], x, y) for p, x, y in zip(chosen, xs, ys)]
    groups = []  # [method, x, y, texts]
    for p, x, y in zip(chosen, xs, ys):
        method = p[0][p[0].rfind("["):] if "[" in p[0] else p[0]
        for g in groups:
            if g[0] == method and near(g[1], x) and near(g[2], y):
                g[3].append(p[0])
                break
        else:
            groups.append([method, x, y, [p[0]]])
    return [(g[3][0] if len(g[3]) == 1 else f"{g[0]} ({len(g[3])} entries)", g[1], g[2]) for g in groups]


def draw(ax, block, series):
    """series: [(source_label, [points])]."""
    markers = "os^Dv<>p*h"
    all_t = [p[1] for _, pts in series for p in pts if p[1] > 0 and math.isfinite(p[1])]
    all_e = [p[2] for _, pts in series for p in pts if math.isfinite(p[2])]
    positive = [e for e in all_e if e > 0]
    log_t = bool(all_t) and max(all_t) / min(all_t) > 20
    log_e = len(positive) >= 2 and max(positive) / min(positive) > 10
    floor = None
    if log_e and any(e == 0 for e in all_e):
        floor = min(positive) / 4
        ax.axhline(floor, color="0.6", linestyle=":", linewidth=1)
        ax.annotate("error = 0", (0.01, floor), xycoords=("axes fraction", "data"), fontsize=7, color="0.4",
                    va="bottom")
    error_names = sorted({p[3] for _, pts in series for p in pts})
    for s, (source, pts) in enumerate(series):
        for is_method in (False, True):
            chosen = [p for p in pts if p[4] == is_method and math.isfinite(p[1]) and math.isfinite(p[2])]
            if not chosen:
                continue
            xs = [p[1] for p in chosen]
            ys = [floor if (floor is not None and p[2] == 0) else p[2] for p in chosen]
            kind = "methods timed in the same entry" if is_method else "entries"
            label = f"{source}: {kind}" if source else kind
            ax.scatter(xs, ys, marker=markers[(2 * s + is_method) % len(markers)], s=28, label=label, zorder=3)
            for text, x, y in labels(chosen, xs, ys, is_method):
                ax.annotate(text, (x, y), textcoords="offset points", xytext=(4, 3), fontsize=6.5)
    if log_t:
        ax.set_xscale("log")
    if log_e:
        ax.set_yscale("log")
    elif all_e and min(all_e) >= 0:  # errors are never negative: start the axis at 0
        top = max(all_e)
        ax.set_ylim(-0.04 * (top if top > 0 else 1.0), 1.1 * top if top > 0 else 1.0)
        if top == 0:
            ax.annotate("every error = 0", (0.5, 0.5), xycoords="axes fraction", ha="center", fontsize=9, color="0.4")
    ax.set_xlabel("run time (ms)")
    ax.set_ylabel(", ".join(error_names) if len(error_names) <= 2 else "error (each point's main err_* counter)",
                  fontsize=8)
    ax.set_title(block, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    with open(path, "rb") as handle:
        if handle.read(8) != b"\x89PNG\r\n\x1a\n":
            print(f"plot_bench: {path} is not a PNG")
            sys.exit(1)
    print(f"wrote {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="+", help="penumbra_bench JSON files")
    parser.add_argument("-o", "--out", default="bench.png",
                        help="a .png file (one panel per block) or a folder (one PNG per block; ends with / or exists)")
    parser.add_argument("--filter", default="", help="regular expression: plot only entries whose name matches")
    args = parser.parse_args()

    pattern = re.compile(args.filter) if args.filter else None
    blocks = {}  # block -> [(source, [points])]
    for path in args.inputs:
        source = os.path.splitext(os.path.basename(path))[0] if len(args.inputs) > 1 else ""
        try:
            doc = load(path)
        except (OSError, ValueError) as e:
            print(f"plot_bench: cannot read {path}: {e}")
            return 1
        for name, time_ms, counters in entries(doc, path):
            if pattern and not pattern.search(name):
                continue
            pts = points(name, time_ms, counters)
            if not pts:
                print(f"plot_bench: {name} has no err_* counter: left out")
                continue
            block = name.split("/", 1)[0]
            per_source = blocks.setdefault(block, [])
            if not per_source or per_source[-1][0] != source:
                per_source.append((source, []))
            per_source[-1][1].extend(pts)
    if not blocks:
        print("plot_bench: nothing to plot (no entry with an err_* counter)")
        return 1

    to_folder = args.out.endswith(os.sep) or args.out.endswith("/") or os.path.isdir(args.out)
    if to_folder:
        os.makedirs(args.out, exist_ok=True)
        for block, series in blocks.items():
            fig, ax = plt.subplots(figsize=(7, 5))
            draw(ax, block, series)
            save(fig, os.path.join(args.out, re.sub(r"[^A-Za-z0-9_.-]", "_", block) + ".png"))
    else:
        columns = min(3, len(blocks))
        rows = (len(blocks) + columns - 1) // columns
        fig, axes = plt.subplots(rows, columns, figsize=(6.5 * columns, 4.8 * rows), squeeze=False)
        for ax, (block, series) in zip(axes.flat, blocks.items()):
            draw(ax, block, series)
        for ax in list(axes.flat)[len(blocks):]:
            ax.set_visible(False)
        save(fig, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
