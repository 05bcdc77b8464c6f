"""cwloc-plot trajectory: a sequence's poses over the map, from cwloc-localize's JSON lines.

Part of cwloc-plot (cwloc_plot.py), which imports it from the same folder and passes itself for its
error type and output helpers. See docs/plot.md.
"""
import json
import math
import os
import sys

plot = None  # the cwloc-plot module, set by run(): its error types and output helpers

MODE_COLOURS = {"tracked": "#2a9d4b", "relocalized": "#e08a1e"}


def _rotation(q):
    """The rotation matrix (rows) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = q
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def _read_lines(path):
    """The lines of a UTF-8 text file; InputError naming it when it cannot be read."""
    try:
        with open(path, encoding="utf-8") as f:
            return f.read().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise plot.InputError(f"{path}: cannot read ({getattr(e, 'strerror', None) or 'not UTF-8 text'})") from None


def _read_frames(path):
    """[(name, mode, centre, camera_from_world rotation)] of a cwloc-localize --sequence output;
    mode is tracked, relocalized or lost (centre None), or localized for a record of a run
    without --sequence."""
    lines = _read_lines(path)
    frames = []
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as e:
            raise plot.InputError(f"{path}:{number}: not a JSON line ({e.msg}); expected cwloc-localize's -o output") \
                from None
        if not isinstance(record, dict) or not isinstance(record.get("name"), str):
            raise plot.InputError(f"{path}:{number}: not a cwloc-localize result (no \"name\")")
        if "error" in record:
            continue  # bad input: no frame
        mode = (record.get("tracking") or {}).get("mode", "localized" if record.get("success") else "lost")
        centre = rotation = None
        if record.get("success"):
            pose = record.get("pose")
            try:
                centre = [float(v) for v in pose["center"]]
                rotation = _rotation([float(v) for v in pose["qvec"]])
            except (TypeError, KeyError, ValueError):
                raise plot.InputError(f"{path}:{number}: a localized record without pose.center and pose.qvec") from None
            if len(centre) != 3:
                raise plot.InputError(f"{path}:{number}: pose.center: expected 3 numbers")
        frames.append((record["name"], mode, centre, rotation))
    if not any(centre for _, _, centre, _ in frames):
        raise plot.InputError(f"{path}: no frame with a pose to draw")
    return frames


def _read_truth(path):
    """{name: centre} of a ground truth file, 'NAME QW QX QY QZ TX TY TZ ...' (camera_from_world)."""
    truth = {}
    lines = _read_lines(path)
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        try:
            q, t = [float(v) for v in fields[1:5]], [float(v) for v in fields[5:8]]
        except ValueError:
            q = t = []
        if len(q) != 4 or len(t) != 3:
            raise plot.InputError(f"{path}:{number}: expected 'NAME QW QX QY QZ TX TY TZ'")
        r = _rotation(q)
        truth[fields[0]] = [-sum(r[k][i] * t[k] for k in range(3)) for i in range(3)]  # -R^T t
    return truth


def _read_points(model):
    """The 3D points (x, y, z) of a COLMAP model folder: points3D.bin, else points3D.txt."""
    import struct
    binary, text = os.path.join(model, "points3D.bin"), os.path.join(model, "points3D.txt")
    points = []
    if os.path.isfile(binary):
        try:
            with open(binary, "rb") as f:
                data = f.read()
            (count,), at = struct.unpack_from("<Q", data, 0), 8
            for _ in range(count):
                x, y, z = struct.unpack_from("<3d", data, at + 8)
                (track,) = struct.unpack_from("<Q", data, at + 43)
                points.append((x, y, z))
                at += 51 + 8 * track
        except OSError as e:
            raise plot.InputError(f"{binary}: cannot read ({e.strerror})") from None
        except struct.error:
            raise plot.InputError(f"{binary}: truncated (not COLMAP's points3D.bin)") from None
        return points
    if not os.path.isfile(text):
        raise plot.InputError(f"{model}: no points3D.bin or points3D.txt (expected a COLMAP model folder)")
    for number, line in enumerate(_read_lines(text), 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        try:
            points.append(tuple(float(v) for v in fields[1:4]))
        except ValueError:
            raise plot.InputError(f"{text}:{number}: expected 'POINT3D_ID X Y Z ...'") from None
    return points


def _top_view_axes(frames):
    """Two horizontal unit axes. Up is the normal of the plane the camera centres lie near (a
    camera carried at about one height), or, when the centres lie along a line, the mean of the
    frames' camera up (-y) directions (cameras held about upright); its sign is the cameras' up.
    The first axis is the centres' widest direction across up."""
    try:
        import numpy
    except ImportError as e:
        raise plot.MissingDependency(f"numpy is not available to {sys.executable} ({e}); install Debian's "
                                     "python3-matplotlib (tools/install-deps.sh)") from None
    centres = numpy.array([c for _, _, c, _ in frames if c])
    camera_up = -numpy.array([r[1] for _, _, c, r in frames if c]).sum(axis=0)  # row 1: camera y
    camera_up /= numpy.linalg.norm(camera_up) or 1.0
    spread = centres - centres.mean(axis=0)
    values, vectors = numpy.linalg.eigh(spread.T @ spread)  # ascending
    up = camera_up
    if len(centres) >= 3 and values[1] > 0.05 * values[2]:
        up = vectors[:, 0] * (1.0 if vectors[:, 0] @ camera_up >= 0 else -1.0)
    first = vectors[:, 2] - (vectors[:, 2] @ up) * up
    if numpy.linalg.norm(first) < 1e-9:
        first = numpy.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
    first /= numpy.linalg.norm(first)
    return list(first), list(numpy.cross(up, first))


def run(args, cwloc_plot):
    """Draws the figure; `cwloc_plot` is the cwloc-plot module."""
    global plot
    plot = cwloc_plot
    frames = _read_frames(args.results)
    truth = _read_truth(args.truth) if args.truth else {}
    points = _read_points(args.model) if args.model else []
    counts = {}
    for _, mode, _, _ in frames:
        counts[mode] = counts.get(mode, 0) + 1
    rows = [["frames", "with a pose"] + sorted(counts)]
    rows.append([str(len(frames)), str(sum(1 for f in frames if f[2]))] + [str(counts[m]) for m in sorted(counts)])
    print(f"{plot.TOOL} trajectory: {args.results}")
    sys.stdout.write(plot._columns(rows))

    first, second = _top_view_axes(frames)

    def xy(p):
        return sum(a * b for a, b in zip(p, first)), sum(a * b for a, b in zip(p, second))

    fig = plot._matplotlib_figure(args.size)
    ax = fig.subplots()
    # The frames, the true path and the middle 80 % of the map on each axis (what they look at).
    drawn = [xy(c) for _, _, c, _ in frames if c] + [xy(c) for c in truth.values()]
    seen = [xy(p) for p in points[::max(1, len(points) // 200000)]]
    xs, ys = [p[0] for p in drawn], [p[1] for p in drawn]
    if seen:
        for values, out in ((sorted(q[0] for q in seen), xs), (sorted(q[1] for q in seen), ys)):
            out += [values[int(0.1 * (len(values) - 1))], values[int(0.9 * (len(values) - 1))]]
    margin = 0.1 * max(max(xs) - min(xs), max(ys) - min(ys), 1e-9)
    box = (min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin)
    if points:
        near = [q for q in seen if box[0] <= q[0] <= box[1] and box[2] <= q[1] <= box[3]]
        ax.scatter([q[0] for q in near], [q[1] for q in near], s=0.4, color="0.72", linewidths=0,
                   label=f"map points ({len(points)})", rasterized=True)
    named_truth = [xy(truth[name]) for name, _, _, _ in frames if name in truth]
    if named_truth:
        ax.plot([q[0] for q in named_truth], [q[1] for q in named_truth], color="0.15", linewidth=1.0,
                linestyle="--", label="ground truth")
    posed = [xy(c) for _, _, c, _ in frames if c]
    ax.plot([q[0] for q in posed], [q[1] for q in posed], color="0.45", linewidth=0.9)
    for mode in sorted({m for _, m, c, _ in frames if c}):
        where = [xy(c) for _, m, c, _ in frames if c and m == mode]
        ax.scatter([q[0] for q in where], [q[1] for q in where], s=22, zorder=3,
                   color=MODE_COLOURS.get(mode, "#3b6fb6"), label=f"{mode} ({len(where)})")
    if counts.get("lost"):
        ax.plot([], [], " ", label=f"lost ({counts['lost']}, no pose)")
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("model units (seen from above)")
    ax.legend(loc="best", fontsize=9, framealpha=0.9, markerscale=1.5)
    ax.grid(True, color="0.92")
    fig.suptitle(args.title or f"Trajectory: {os.path.basename(args.results)}")
    plot._save_png(fig, args.output)
    print(f"{plot.TOOL}: wrote {args.output} ({plot._count(len(frames), 'frame')})", file=sys.stderr)
    return plot.EXIT_OK

