#!/usr/bin/python3
"""cwloc-plot: PNG figures from cwloc-eval --json reports. See docs/plot.md.

CMake copies this file to build/bin/cwloc-plot and fills in the version. It needs Python 3 and
matplotlib (Debian: python3-matplotlib, installed by tools/install-deps.sh); reports are read and
checked before matplotlib is imported, so bad input is reported without it.

Exit codes, as for every cwloc tool: 0 figure written; 2 bad input or usage (the message names
the file and the problem); 3 matplotlib missing or an internal error.
"""
import argparse
import json
import logging
import math
import os
import statistics
import sys
import tempfile

VERSION = "@PROJECT_VERSION@"  # filled in by CMake's configure_file
TOOL = "cwloc-plot"
STAGES = ("forward_knn", "ratio_test", "query_tree", "back_matching", "pose", "total")
DPI = 120
DEFAULT_SIZE = (960, 600)

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3


class InputError(Exception):
    """Bad input at a trust boundary (a file, an option): exit 2 with the message."""


class MissingDependency(Exception):
    """matplotlib is not importable: exit 3 with the message."""


# ---------------------------------------------------------------------------------------------
# Reading and checking cwloc-eval --json reports (schemas/eval-report.schema.json)


def _kind(value):
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "an array"
    return "an object"


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class Report:
    """One cwloc-eval --json report; checks fields as the plots ask for them."""

    def __init__(self, path):
        self.path = path
        self.doc = _read_json(path)
        if not isinstance(self.doc, dict) or self.doc.get("tool") != "cwloc-eval":
            raise InputError(f'{path}: not a cwloc-eval --json report (no "tool": "cwloc-eval")')
        self.unit = self._field(self.doc, "unit", "unit", "string")
        if self.unit not in ("m", "model units"):
            raise InputError(f'{path}: unit: expected "m" or "model units", got "{self.unit}"')
        self.thresholds = []
        for t, threshold in enumerate(self._field(self.doc, "thresholds", "thresholds", "array")):
            where = f"thresholds[{t}]"
            if not isinstance(threshold, dict):
                raise InputError(f"{path}: {where}: expected an object, got {_kind(threshold)}")
            self.thresholds.append(self._number(threshold, "position", f"{where}.position", positive=True))
        self.runs = self._field(self.doc, "runs", "runs", "array")
        if not self.runs:
            raise InputError(f"{path}: runs: empty (a report has at least one run)")
        for r, run in enumerate(self.runs):
            if not isinstance(run, dict):
                raise InputError(f"{path}: runs[{r}]: expected an object, got {_kind(run)}")
            self._field(run, "label", f"runs[{r}].label", "string")
            queries = self._field(run, "queries", f"runs[{r}].queries", "integer")
            if queries < 1:
                raise InputError(f"{path}: runs[{r}].queries: expected at least 1, got {queries}")

    # Field access with messages that name the file and the JSON path.
    def _field(self, obj, key, where, kind):
        if key not in obj:
            raise InputError(f"{self.path}: {where}: missing")
        value = obj[key]
        ok = {
            "string": isinstance(value, str),
            "array": isinstance(value, list),
            "object": isinstance(value, dict),
            "integer": isinstance(value, int) and not isinstance(value, bool),
            "number": _is_number(value),
        }[kind]
        if not ok:
            article = "an" if kind[0] in "aeiou" else "a"
            raise InputError(f"{self.path}: {where}: expected {article} {kind}, got {_kind(value)}")
        return value

    def _number(self, obj, key, where, positive=False):
        value = self._field(obj, key, where, "number")
        if value < 0 or (positive and value == 0):
            raise InputError(f"{self.path}: {where}: expected a {'positive' if positive else 'non-negative'} "
                             f"number, got {value}")
        return float(value)

    def label(self, r):
        return self.runs[r]["label"]

    def queries(self, r):
        return self.runs[r]["queries"]

    def localized_share(self, r):
        share = self._number(self.runs[r], "localized_share", f"runs[{r}].localized_share")
        if share > 1:
            raise InputError(f"{self.path}: runs[{r}].localized_share: expected at most 1, got {share}")
        return share

    def position_errors(self, r):
        """Sorted position errors of the localized queries of run r, and the localized count."""
        per_query = self._field(self.runs[r], "per_query", f"runs[{r}].per_query", "array")
        if len(per_query) != self.queries(r):
            raise InputError(f"{self.path}: runs[{r}].per_query: {len(per_query)} entries for "
                             f"{self.queries(r)} ground-truth queries")
        errors = []
        for q, entry in enumerate(per_query):
            where = f"runs[{r}].per_query[{q}]"
            if not isinstance(entry, dict):
                raise InputError(f"{self.path}: {where}: expected an object, got {_kind(entry)}")
            if self._field(entry, "status", f"{where}.status", "string") == "localized":
                errors.append(self._number(entry, "position_error", f"{where}.position_error"))
        return sorted(errors)

    def stage_times(self, r, stage, quantile):
        """times_ms.<stage>.<quantile> of run r, in milliseconds."""
        run = self.runs[r]
        if run.get("times_ms", "missing") is None:
            raise InputError(f'{self.path}: runs[{r}].times_ms: null (run "{run["label"]}" has no stage times: '
                             "it was a poses file; evaluate cwloc-localize JSON lines)")
        times = self._field(run, "times_ms", f"runs[{r}].times_ms", "object")
        stage_times = self._field(times, stage, f"runs[{r}].times_ms.{stage}", "object")
        if quantile == "p90" and "p90" not in stage_times:
            raise InputError(f"{self.path}: runs[{r}].times_ms.{stage}.p90: missing (the report is from a "
                             "cwloc-eval without p90; evaluate again)")
        return self._number(stage_times, quantile, f"runs[{r}].times_ms.{stage}.{quantile}")


def _read_json(path):
    try:
        with open(path, "rb") as f:
            data = f.read()
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, expected a file") from None
    except OSError as e:
        raise InputError(f"{path}: cannot open ({e.strerror})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not valid JSON (not UTF-8 text)") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        if e.msg == "Extra data":
            raise InputError(f"{path}:{e.lineno}: a second JSON value; expected one cwloc-eval --json report "
                             "(JSON lines are cwloc-localize results: evaluate them with cwloc-eval --json)") from None
        raise InputError(f"{path}:{e.lineno}: not valid JSON ({e.msg})") from None


# ---------------------------------------------------------------------------------------------
# Output


def _matplotlib_figure(size):
    """A Figure of exactly size = (width, height) pixels on the Agg backend (no display)."""
    # matplotlib logs warnings (e.g. an unwritable cache directory) straight to stderr; the
    # tool's output is its figure and its own messages.
    logging.getLogger("matplotlib").setLevel(logging.ERROR)
    try:
        import matplotlib
        matplotlib.use("Agg")
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as e:
        raise MissingDependency(f"matplotlib is not available to {sys.executable} ({e}); install Debian's "
                                "python3-matplotlib (tools/install-deps.sh)") from None
    width, height = size
    # Agg truncates width * dpi / dpi to whole pixels; half a pixel more keeps the exact size.
    fig = Figure(figsize=((width + 0.5) / DPI, (height + 0.5) / DPI), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)  # attaches itself: text extents for label placement, PNG output
    return fig


def _save_png(fig, output):
    """Writes the figure as PNG to a temporary file next to output, then renames it into place."""
    if os.path.isdir(output):
        raise InputError(f"{output}: is a directory, expected a PNG file name")
    directory = os.path.dirname(os.path.abspath(output))
    try:
        fd, temp = tempfile.mkstemp(prefix=".cwloc-plot-", suffix=".png.tmp", dir=directory)
    except OSError as e:
        raise InputError(f"{output}: cannot write ({e.strerror})") from None
    try:
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, format="png", dpi=DPI)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temp, 0o666 & ~umask)  # mkstemp's 0600 would make the figure private
        os.replace(temp, output)
    except OSError as e:
        _remove_quietly(temp)
        raise InputError(f"{output}: cannot write ({e.strerror})") from None
    except BaseException:
        _remove_quietly(temp)
        raise


def _remove_quietly(path):
    try:
        os.unlink(path)
    except OSError:
        pass


def _number_text(value):
    """cwloc-eval's table format: enough digits for milliseconds and millimetres alike."""
    magnitude = abs(value)
    if magnitude != 0 and magnitude < 0.01:
        return f"{value:.2g}"
    if magnitude < 10:
        return f"{value:.3f}"
    if magnitude < 1000:
        return f"{value:.1f}"
    return f"{value:.0f}"


def _columns(rows):
    widths = [max(len(row[c]) for row in rows) for c in range(len(rows[0]))]
    return "".join("  " + "  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() + "\n" for row in rows)


def _count(n, noun):
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _unit_text(unit):
    return "m" if unit == "m" else "model units"


def _common_unit(reports):
    units = sorted({r.unit for r in reports})
    if len(units) > 1:
        detail = ", ".join(f"{r.path} in {r.unit}" for r in reports)
        raise InputError(f"reports differ in unit ({detail}); evaluate all with --scale or all without")
    return units[0]


def _unique_labels(entries):
    """entries: (report, run label); a label that occurs twice gets its report's file name."""
    counts = {}
    for _, label in entries:
        counts[label] = counts.get(label, 0) + 1
    return [label if counts[label] == 1 else f"{label} ({os.path.basename(report.path)})" for report, label in entries]


def _plain_log_labels(axis):
    """Decade ticks of a log axis as 0.01, 0.1, 1, 10 rather than powers of ten."""
    from matplotlib.ticker import FuncFormatter
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))


def _overlap(a, b):
    return max(0.0, min(a.x1, b.x1) - max(a.x0, b.x0)) * max(0.0, min(a.y1, b.y1) - max(a.y0, b.y0))


def _place_labels(fig, ax, labels):
    """Annotates points: labels = [(x, y, text, colour)]. Each text goes to the first spot around
    its point (right, left, above, below, further out) that overlaps no marker, no label placed
    before and not the axes' edge; failing that, to the spot that overlaps least."""
    from matplotlib.transforms import Bbox
    fig.draw_without_rendering()  # the final layout, so display coordinates hold
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    legend = ax.get_legend()
    taken = [legend.get_window_extent(renderer)] if legend else []
    for x, y, _, _ in labels:
        px, py = ax.transData.transform((x, y))
        taken.append(Bbox.from_extents(px - 5, py - 5, px + 5, py + 5))
    spots = [(6, 4, "left", "bottom"), (6, -4, "left", "top"), (-6, 4, "right", "bottom"), (-6, -4, "right", "top"),
             (0, 8, "center", "bottom"), (0, -8, "center", "top"), (6, 14, "left", "bottom"),
             (6, -14, "left", "top"), (-6, 14, "right", "bottom"), (-6, -14, "right", "top"),
             (0, 22, "center", "bottom"), (0, -22, "center", "top")]
    for x, y, text, colour in labels:
        best = None
        for dx, dy, ha, va in spots:
            annotation = ax.annotate(text, xy=(x, y), xytext=(dx, dy), textcoords="offset points", ha=ha, va=va,
                                     fontsize=8, color=colour)
            box = annotation.get_window_extent(renderer)
            cost = sum(_overlap(box, other) for other in taken) + 4 * (box.width * box.height - _overlap(box, frame))
            if best is None or cost < best[0]:
                if best is not None:
                    best[1].remove()
                best = (cost, annotation, box)
            else:
                annotation.remove()
            if cost == 0:
                break
        taken.append(best[2])


# ---------------------------------------------------------------------------------------------
# errors: cumulative position-error curves


def cmd_errors(args):
    reports = [Report(path) for path in args.report]
    unit = _common_unit(reports)
    curves = []  # (report, label, sorted errors, queries)
    for report in reports:
        for r in range(len(report.runs)):
            curves.append((report, report.label(r), report.position_errors(r), report.queries(r)))
    thresholds = sorted({t for report in reports for t in report.thresholds})

    all_errors = [e for _, _, errors, _ in curves for e in errors]
    positive = [e for e in all_errors + thresholds if e > 0]
    hi = args.max_error if args.max_error else 1.5 * max(all_errors + thresholds + [1e-9])
    if args.x_scale == "log":
        lo = min(positive) / 2 if positive else hi / 1000
        if lo >= hi:
            lo = hi / 1000
    else:
        lo = 0.0

    fig = _matplotlib_figure(args.size)
    ax = fig.subplots()
    labels = _unique_labels([(report, label) for report, label, _, _ in curves])
    for (report, _, errors, queries), label in zip(curves, labels):
        # A step up of 100 / queries at each localized query's error; unlocalized queries never
        # arrive, so the curve ends at the localized share.
        xs = [lo] + [max(e, lo) for e in errors] + [max([hi] + errors)]
        ys = [0.0] + [100.0 * (k + 1) / queries for k in range(len(errors))]
        ys.append(ys[-1])
        ax.step(xs, ys, where="post", linewidth=1.8, label=f"{label}: {len(errors)}/{queries} localized")
    unit_text = _unit_text(unit)
    for t in thresholds:
        if lo < t < hi:
            # vlines rather than axvline: a collection, which the legend's "best" placement does
            # not try to avoid (it should avoid the curves, not these).
            ax.vlines(t, 0, 1, transform=ax.get_xaxis_transform(), colors="0.55", linewidth=0.8, linestyles=":",
                      zorder=0)
            ax.annotate(f"{t:g} m" if unit == "m" else f"{t:g}", xy=(t, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(0, 2), textcoords="offset points", ha="center", va="bottom", fontsize=8,
                        color="0.4")
    ax.set_xscale(args.x_scale)
    if args.x_scale == "log":
        _plain_log_labels(ax.xaxis)
    ax.set_xlim(lo, hi)
    ax.set_ylim(0, 103)  # a curve at 100% stays visible above the frame's top
    ax.set_yticks(range(0, 101, 20))
    ax.set_xlabel(f"position error ({unit_text})")
    ax.set_ylabel("queries localized within the error (% of all)")
    ax.grid(True, which="major", color="0.9")
    ax.set_title(args.title or "Cumulative position error", pad=14)
    ax.legend(loc="best", fontsize=9, framealpha=0.9)
    _save_png(fig, args.output)
    print(f"{TOOL}: wrote {args.output} ({_count(len(curves), 'curve')})", file=sys.stderr)
    return EXIT_OK


# ---------------------------------------------------------------------------------------------
# anytime: localized share against time per query, one series per report


def cmd_anytime(args):
    if args.series and len(args.series) != len(args.report):
        raise InputError(f"got {len(args.series)} --series for {len(args.report)} --report; give one per report "
                         "or none")
    reports = [Report(path) for path in args.report]
    names = args.series or [os.path.splitext(os.path.basename(path))[0] for path in args.report]
    series = []  # (name, [(ms, share %, run label)])
    for name, report in zip(names, reports):
        points = [(report.stage_times(r, args.stage, "median"), 100.0 * report.localized_share(r), report.label(r))
                  for r in range(len(report.runs))]
        series.append((name, points))

    fig = _matplotlib_figure(args.size)
    ax = fig.subplots()
    labels = []  # (x, y, run label, colour)
    for name, points in series:
        xs = [p[0] for p in points]
        ys = [p[1] for p in points]
        line, = ax.plot(xs, ys, marker="o", linewidth=1.6, markersize=5, label=name)
        labels += [(x, y, label, line.get_color()) for x, y, label in points]
    shares = [p[1] for _, points in series for p in points]
    pad = max(2.0, 0.1 * (max(shares) - min(shares)))
    ax.set_ylim(max(0.0, min(shares) - pad), min(102.0, max(shares) + pad))
    ax.set_xscale(args.x_scale)
    ax.margins(x=0.08)
    if args.x_scale == "linear":
        ax.set_xlim(left=0)
    ax.set_xlabel(f"median time per query, {args.stage} (ms)")
    ax.set_ylabel("localized queries (%)")
    ax.grid(True, color="0.9")
    ax.set_title(args.title or "Localized queries against time per query", pad=10)
    ax.legend(loc="best", fontsize=9, framealpha=0.9)
    _place_labels(fig, ax, labels)
    _save_png(fig, args.output)
    print(f"{TOOL}: wrote {args.output} ({len(series)} series)", file=sys.stderr)
    return EXIT_OK


# ---------------------------------------------------------------------------------------------
# scale: time per query against model size


def _point(text):
    views, sep, path = text.partition(":")
    try:
        number = float(views)
    except ValueError:
        number = None
    if not sep or not path or number is None or not math.isfinite(number) or number <= 0:
        raise argparse.ArgumentTypeError(f"'{text}': expected VIEWS:REPORT with VIEWS a positive number of views "
                                         "(e.g. 100000:eval.json)")
    return number, path


def _views_text(views):
    return f"{views:.0f}" if views == int(views) else f"{views:g}"


def _views_short(views):
    for factor, suffix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if views >= factor:
            return f"{views / factor:.3g}{suffix}"
    return f"{views:.3g}"


def growth_exponent(views, times):
    """Least-squares slope of log(time) against log(views); None without two sizes or with a zero time."""
    if len(set(views)) < 2 or min(times) <= 0:
        return None
    xs = [math.log(v) for v in views]
    ys = [math.log(t) for t in times]
    mx = sum(xs) / len(xs)
    my = sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def cmd_scale(args):
    points = []  # (views, report, run index)
    for views, path in args.point:
        report = Report(path)
        r = 0
        if args.run is not None:
            labels = [report.label(i) for i in range(len(report.runs))]
            if args.run not in labels:
                raise InputError(f"{path}: no run labelled \"{args.run}\" (runs: {', '.join(labels)})")
            r = labels.index(args.run)
        points.append((views, report, r))
    points.sort(key=lambda p: p[0])
    views = [p[0] for p in points]
    medians = {stage: [report.stage_times(r, stage, "median") for _, report, r in points] for stage in STAGES}
    p90 = [report.stage_times(r, "total", "p90") for _, report, r in points]
    series_label = args.series_label or points[0][1].label(points[0][2])
    exponent = growth_exponent(views, medians["total"])

    rows = [["views", "median total ms", "p90 total ms"]]
    rows += [[_views_text(v), _number_text(m), _number_text(p)] for v, m, p in zip(views, medians["total"], p90)]
    print(f"{TOOL} scale: {series_label}, time per query by model size")
    sys.stdout.write(_columns(rows))
    if exponent is None:
        print("growth exponent: - (needs two or more model sizes and non-zero times)")
    else:
        print(f"growth exponent: {exponent:.3f} (median total time ~ views^{exponent:.3f}; least-squares slope of "
              f"log time against log views over {len(views)} reports)")

    fig = _matplotlib_figure(args.size)
    ax = fig.subplots()
    for stage in STAGES:
        if stage == "total":
            ax.plot(views, medians[stage], color="black", linewidth=2.2, marker="o", label="total (median)")
        else:
            ax.plot(views, medians[stage], linewidth=1.4, marker="o", markersize=4, label=f"{stage} (median)")
    ax.plot(views, p90, color="black", linewidth=1.4, linestyle="--", marker="o", markersize=4,
            label="total (p90)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    _plain_log_labels(ax.yaxis)
    if len(set(views)) <= 8:  # few sizes: tick exactly at them, a decade may not even show
        from matplotlib.ticker import NullLocator
        ax.set_xticks(sorted(set(views)), [_views_short(v) for v in sorted(set(views))])
        ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlabel("model size (views)")
    ax.set_ylabel("time per query (ms)")
    ax.grid(True, which="major", color="0.88")
    ax.grid(True, which="minor", color="0.95")
    title = args.title or f"Time per query against model size: {series_label}"
    if exponent is not None:
        title += f" (total ~ views^{exponent:.2f})"
    ax.set_title(title)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, borderaxespad=0)
    _save_png(fig, args.output)
    print(f"{TOOL}: wrote {args.output} ({_count(len(points), 'model size')})", file=sys.stderr)
    return EXIT_OK


# ---------------------------------------------------------------------------------------------
# compact: the compact index's trade-off, error and localized share against bytes per view


def _compact_point(text):
    parts = text.split(":", 2)
    try:
        number = float(parts[1]) if len(parts) == 3 else None
    except ValueError:
        number = None
    if len(parts) != 3 or not parts[0] or not parts[2] or number is None or not math.isfinite(number) \
            or number <= 0:
        raise argparse.ArgumentTypeError(f"'{text}': expected DATASET:BYTES_PER_VIEW:REPORT with a positive "
                                         "number of bytes (e.g. herz:25.3:eval.json)")
    return parts[0], number, parts[2]


def cmd_compact(args):
    series = {}  # data set -> [(bytes per view, median error, localized share)]
    for name, bytes_per_view, path in args.point:
        report = Report(path)
        errors = report.position_errors(0)
        median = statistics.median(errors) if errors else None
        series.setdefault(name, []).append((bytes_per_view, median, 100.0 * report.localized_share(0)))
    rows = [["data set", "bytes / view", "median error", "vs largest", "localized %"]]
    for name, points in series.items():
        points.sort()
        reference = points[-1][1]  # the largest index of the data set: the full one
        for b, median, share in points:
            ratio = median / reference if median is not None and reference else None
            rows.append([name, _number_text(b), _number_text(median), _number_text(ratio), _number_text(share)])
    print(f"{TOOL} compact: median position error and localized share by bytes per view")
    sys.stdout.write(_columns(rows))

    fig = _matplotlib_figure(args.size)
    error_ax, share_ax = fig.subplots(1, 2)
    for name, points in series.items():
        reference = points[-1][1]
        xs = [b for b, median, _ in points if median is not None and reference]
        ys = [median / reference for _, median, _ in points if median is not None and reference]
        error_ax.plot(xs, ys, marker="o", linewidth=1.6, label=name)
        share_ax.plot([b for b, _, _ in points], [share for _, _, share in points], marker="o", linewidth=1.6,
                      label=name)
    for ax in (error_ax, share_ax):
        ax.set_xscale("log")
        _plain_log_labels(ax.xaxis)
        ax.set_xlabel("index bytes per view")
        ax.grid(True, which="major", color="0.88")
        ax.axvline(32, color="0.55", linewidth=0.8, linestyle=":")
    error_ax.axhline(1.1, color="0.55", linewidth=0.8, linestyle=":")
    error_ax.set_ylabel("median position error / the full index's")
    share_ax.set_ylabel("queries localized (%)")
    share_ax.set_ylim(0, 103)
    error_ax.legend(loc="best", fontsize=9, framealpha=0.9)
    fig.suptitle(args.title or "Compact index: accuracy against size")
    _save_png(fig, args.output)
    print(f"{TOOL}: wrote {args.output} ({_count(len(series), 'data set')})", file=sys.stderr)
    return EXIT_OK



def cmd_trajectory(args):
    """cwloc-plot trajectory, in cwloc_plot_trajectory.py next to this script."""
    sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
    import cwloc_plot_trajectory
    return cwloc_plot_trajectory.run(args, sys.modules[__name__])

# ---------------------------------------------------------------------------------------------
# Command line


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        sys.stderr.write(f"{TOOL}: error: {message}\nRun '{self.prog} --help' for usage.\n")
        sys.exit(EXIT_BAD_INPUT)


def _positive_float(text):
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"'{text}': expected a positive number")
    return value


def _size(text):
    width, sep, height = text.lower().partition("x")
    if not sep or not width.isdigit() or not height.isdigit() or not (100 <= int(width) <= 10000) or \
            not (100 <= int(height) <= 10000):
        raise argparse.ArgumentTypeError(f"'{text}': expected WIDTHxHEIGHT in pixels, each 100 to 10000 "
                                         "(e.g. 960x600)")
    return int(width), int(height)


def _version():
    return VERSION if not VERSION.startswith("@") else "(source tree)"


def build_parser():
    formatter = argparse.RawDescriptionHelpFormatter
    parser = _Parser(
        prog=TOOL, formatter_class=formatter,
        description="PNG figures from cwloc-eval --json reports (schemas/eval-report.schema.json).",
        epilog="Exit codes: 0 figure written; 2 bad input or usage; 3 matplotlib missing or an internal error.\n"
               "Run 'cwloc-plot COMMAND --help' for each command's options; see docs/plot.md.")
    parser.add_argument("--version", action="version", version=f"{TOOL} {_version()}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def common(sub):
        sub.add_argument("-o", "--output", required=True, metavar="PNG",
                         help="the figure to write (always PNG; written to a temporary file next to it, then "
                              "renamed)")
        sub.add_argument("--title", help="figure title (default: what the plot shows)")
        sub.add_argument("--size", type=_size, default=DEFAULT_SIZE, metavar="WxH",
                         help="figure size in pixels (default: 960x600)")

    errors = commands.add_parser(
        "errors", formatter_class=formatter, help="cumulative position-error curves, one per run",
        description="Cumulative position error: for every run in every report, the share of ALL ground-truth\n"
                    "queries (%) localized within a position error (unlocalized queries keep the curve below\n"
                    "100%). x is the position error in the reports' unit (m with cwloc-eval --scale, else\n"
                    "model units); faint dotted lines mark the reports' threshold positions (0.25, 0.5, 5).\n"
                    "Reads per_query[].position_error; the reports must share one unit.",
        epilog="example:\n  cwloc-plot errors --report eval.json --report baseline.json -o cdf.png --max-error 10")
    errors.add_argument("--report", action="append", required=True, metavar="JSON",
                        help="a cwloc-eval --json report; repeat to draw the runs of several reports")
    errors.add_argument("--max-error", type=_positive_float, metavar="X",
                        help="right end of the x axis, in the reports' unit (default: 1.5 x the largest error or "
                             "threshold)")
    errors.add_argument("--x-scale", choices=("log", "linear"), default="log",
                        help="x axis scale (default: log; zero errors sit at the left edge)")
    common(errors)
    errors.set_defaults(func=cmd_errors)

    anytime = commands.add_parser(
        "anytime", formatter_class=formatter, help="localized share against time per query, one series per report",
        description="Anytime plot (the paper's Figure 4): each report is one series, e.g. a sweep of runs\n"
                    "with N_F = 50..500; each run is a point at x = median time per query of --stage (ms) and\n"
                    "y = localized share (% of all ground-truth queries), joined in report order and annotated\n"
                    "with the run labels. Reads runs[].times_ms.<stage>.median and localized_share.",
        epilog="example:\n  cwloc-plot anytime --report sweep_cw.json --series cluster-wise \\\n"
               "      --report sweep_global.json --series global-ratio -o anytime.png")
    anytime.add_argument("--report", action="append", required=True, metavar="JSON",
                         help="a cwloc-eval --json report with several runs: one series; repeat for more series")
    anytime.add_argument("--series", action="append", metavar="NAME",
                         help="legend name of each series, one per --report in the same order (default: report "
                              "file name)")
    anytime.add_argument("--stage", choices=STAGES, default="total",
                         help="whose median time is x (default: total)")
    anytime.add_argument("--x-scale", choices=("linear", "log"), default="linear",
                         help="x axis scale (default: linear, from 0)")
    common(anytime)
    anytime.set_defaults(func=cmd_anytime)

    scale = commands.add_parser(
        "scale", formatter_class=formatter, help="time per query against model size",
        description="Time per query against model size: x = views (log), y = ms (log); solid lines for the\n"
                    "median time of each stage (forward_knn, ratio_test, query_tree, back_matching, pose,\n"
                    "total) and a dashed line for the total's p90, from the first run (or --run) of each\n"
                    "report. Prints views, median and p90 total ms, and the growth exponent: the least-\n"
                    "squares slope of log(median total) against log(views), so time ~ views^exponent.",
        epilog="example:\n  cwloc-plot scale --point 100000:eval_100k.json --point 1000000:eval_1m.json \\\n"
               "      --point 10000000:eval_10m.json --run cluster-wise -o scale.png")
    scale.add_argument("--point", action="append", required=True, type=_point, metavar="VIEWS:JSON",
                       help="a model size (number of views, e.g. 1e6 or 1000000) and the cwloc-eval --json report "
                            "of its run; repeat")
    scale.add_argument("--run", metavar="LABEL", help="take the run with this label from each report (default: "
                                                      "the first run)")
    scale.add_argument("--series-label", metavar="NAME",
                       help="name of the series in the title and the printed table (default: the run's label)")
    common(scale)
    scale.set_defaults(func=cmd_scale)

    compact = commands.add_parser(
        "compact", formatter_class=formatter, help="error and localized share against index bytes per view",
        description="The compact index's trade-off (bench/compact_benchmark.sh): x = index bytes per view (log);\n"
                    "left, the median position error over the data set's largest index (the full one);\n"
                    "right, the share of queries localized; one line per data set, from the first run of\n"
                    "each report. Prints the same numbers as a table.",
        epilog="example:\n  cwloc-plot compact --point herz:174.3:full.json --point herz:22.5:c32.json \\\n"
               "      --point herz:18.7:c16.json -o compact.png")
    compact.add_argument("--point", action="append", required=True, type=_compact_point,
                         metavar="DATASET:BYTES:JSON",
                         help="a data set's name, an index's bytes per view and the cwloc-eval --json report "
                              "of its run; repeat")
    common(compact)
    compact.set_defaults(func=cmd_compact)

    trajectory = commands.add_parser(
        "trajectory", formatter_class=formatter, help="a sequence's poses over the map, coloured by tracking mode",
        description="A sequence's camera centres seen from above (up: the frames' mean camera up direction),\n"
                    "joined in frame order and coloured by how each got its pose (tracked, relocalized), over\n"
                    "the COLMAP model's points near them and, with --truth, the true path. Reads cwloc-localize\n"
                    "--sequence (or --video) JSON lines; prints the frames per mode.",
        epilog="example:\n  cwloc-plot trajectory --results frames.jsonl --model sparse/0 \\\n"
               "      --truth queries_gt.txt -o trajectory.png")
    trajectory.add_argument("--results", required=True, metavar="JSONL", help="cwloc-localize's -o output")
    trajectory.add_argument("--model", metavar="DIR", help="a COLMAP model folder whose points3D are drawn")
    trajectory.add_argument("--truth", metavar="FILE",
                            help="true poses, 'NAME QW QX QY QZ TX TY TZ' (camera_from_world) per line")
    common(trajectory)
    trajectory.set_defaults(func=cmd_trajectory)
    return parser


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except InputError as e:
        print(f"{TOOL}: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MissingDependency as e:
        print(f"{TOOL}: error: {e}", file=sys.stderr)
        return EXIT_INTERNAL
    except MemoryError:
        print(f"{TOOL}: error: out of memory", file=sys.stderr)
        return EXIT_INTERNAL
    except KeyboardInterrupt:
        return 130
    except Exception as e:  # a bug in cwloc-plot: one line, as the C++ tools do
        print(f"{TOOL}: internal error: {type(e).__name__}: {e}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
