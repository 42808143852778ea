#!/usr/bin/python3
"""Plots light_lut_error's JSON: wrong bits (seed mode) and uncertain bits (certified mode) against
the LUT resolution, one line per N, log-log. Usage (Debian's python3 has matplotlib):
    /usr/bin/python3 tools/plot_lut_error.py lut.json [more.json ...] -o lut_error.png
Each file is one (shape, mapping, symmetry) series; several files overlay as separate styles."""
import argparse
import json
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:  # ctest reports exit code 77 as skipped
    print("plot_lut_error: matplotlib is missing (apt-get install python3-matplotlib)")
    sys.exit(77)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="+")
    parser.add_argument("-o", "--out", default="lut_error.png")
    args = parser.parse_args()
    fig, ax = plt.subplots(figsize=(7.5, 5))
    markers = "osd^v<>"
    for f, path in enumerate(args.inputs):
        with open(path) as handle:
            doc = json.load(handle)
        label = f"{doc['shape']}, {doc['mapping']}{'' if doc['symmetric'] else ', d in [-1,1]'}"
        by_n = {}
        for row in doc["rows"]:
            by_n.setdefault(row["samples"], []).append(row)
        for n, rows in sorted(by_n.items()):
            rows.sort(key=lambda r: r["resolution"])
            res = [r["resolution"] for r in rows]
            cut = [max(r["cut_bits"], 1) for r in rows]
            wrong = [r["wrong_bits"] / c for r, c in zip(rows, cut)]
            unc = [r["uncertain_bits"] / c for r, c in zip(rows, cut)]
            m = markers[f % len(markers)]
            ax.plot(res, unc, "-" + m, label=f"uncertain (certified), N={n}, {label}")
            ax.plot(res, wrong, "--" + m, label=f"wrong (seed), N={n}, {label}")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("resolution R (R^3 texels per 128 samples)")
    ax.set_ylabel("fraction of sample bits, planes cutting the light")
    ax.set_title("light-sample LUT vs the exact test (0 wrong certain bits)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
