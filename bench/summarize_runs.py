#!/usr/bin/python3
"""Markdown table of the runs in cwloc-eval --json reports, in the columns of the paper's tables,
with the median RANSAC inliers and inlier ratio read from each run's JSON lines (cwloc-eval
does not report them).

    bench/summarize_runs.py REPORT.json [REPORT.json ...]
"""
import json
import statistics
import sys


def median_inliers(path):
    """Median inlier count and inlier ratio over the run's localized queries."""
    inliers, ratios = [], []
    with open(path) as lines:
        for line in lines:
            if line.strip():
                record = json.loads(line)
                if record.get("success"):
                    inliers.append(record["num_inliers"])
                    ratios.append(record["inlier_ratio"])
    if not inliers:
        return None, None
    return statistics.median(inliers), statistics.median(ratios)


def cell(value, digits=3):
    if value is None:
        return "-"
    return f"{value:.{digits}g}" if isinstance(value, float) else str(value)


def main(paths):
    columns = ["run", "localized", "inliers", "inlier ratio", "position error (m)", "rotation error (°)",
               "(0.25 m, 2°)", "matching / RANSAC ms", "total ms, median / p90", "recognition top-1 / top-5"]
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for path in paths:
        with open(path) as f:
            report = json.load(f)
        unit = report["unit"]
        if unit != "m":
            sys.exit(f"{path}: errors are in {unit}; run cwloc-eval with --scale")
        for run in report["runs"]:
            position = run["position_error"]
            rotation = run["rotation_error_deg"]
            times = run["times_ms"]
            recognition = run.get("recognition")
            inliers, ratio = median_inliers(run["path"]) if run["format"] == "json-lines" else (None, None)
            matching = (times["forward_knn"]["median"] + times["ratio_test"]["median"] + times["query_tree"]["median"]
                        + times["back_matching"]["median"]) if times else None
            row = [
                run["label"],
                f"{run['localized']}/{run['queries']}",
                cell(inliers),
                cell(ratio, 2),
                cell(position["median"]) if position else "-",
                cell(rotation["median"]) if rotation else "-",
                f"{100 * run['within'][0]['share']:.0f} %",
                f"{matching:.1f} / {times['pose']['median']:.1f}" if times else "-",
                f"{times['total']['median']:.1f} / {times['total']['p90']:.1f}" if times else "-",
                (f"{100 * recognition['top']['top1']['share']:.0f} % / {100 * recognition['top']['top5']['share']:.0f} %"
                 if recognition else "-"),
            ]
            print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
