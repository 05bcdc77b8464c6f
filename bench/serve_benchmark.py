#!/usr/bin/python3
"""cwloc-serve under load, against cwloc-localize on the same queries (docs/benchmarks.md, "Service").

Two workloads from a data set of ../shared/data's layout: its query photos, sent as the bare
body (`curl --data-binary`), and their SIFT features from database.db in the binary layout with
the query's camera (multipart, docs/serve.md), as a device that extracts on board sends them.

  peer         cwloc-localize --threads N on the same queries repeated (the photos by
               --image-list, the features from the database by --query-list with their
               cameras): queries per second, hyperfine's median of 3 runs
  throughput   wrk -c 2N for --seconds against cwloc-serve --threads N: requests per second
               (and its ratio to the peer's), median and p99 latency
  80 %         an open-loop client (requests at fixed times, whatever the answers' latency) at
               80 % of that throughput: median and p99 latency, their ratio
  overload     the same at 200 %, with --budget-ms: answers by status, answers later than the
               budget plus 0.5 s, localized queries per second against the throughput
  soak         80 % for --soak-seconds (features; photos with --soak-photos): errors, and
               cwloc-serve's RSS 30 s in and at the end

    bench/serve_benchmark.py WORKDIR [--data herz_jesu_p25] [--threads 2] [--seconds 20]
                             [--soak-seconds 600]
Localhost only. Needs wrk and hyperfine (tools/install-deps.sh).
"""
import argparse
import http.client
import json
import os
import queue
import re
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("CWLOC_BIN", os.path.join(TOP, "build", "bin"))
SHARED = os.path.join(TOP, "..", "shared", "data")


def load_rig_benchmark():
    import importlib.util
    spec = importlib.util.spec_from_file_location(
        "rig_benchmark", os.path.join(TOP, "bench", "rig_benchmark.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run(args):
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode not in (0, 1):
        sys.exit(f"{' '.join(args)}: exit {done.returncode}\n{done.stderr}")
    return done.stdout


class Workload:
    """The bodies one kind of query sends, and the cwloc-localize command for the same queries."""

    def __init__(self, name, bodies, cli_args):
        self.name, self.bodies, self.cli_args = name, bodies, cli_args  # bodies: (headers, bytes)


def multipart(parts):
    boundary = "cwlocbenchboundary"
    out = b""
    for name, content_type, data in parts:
        out += (f"--{boundary}\r\nContent-Disposition: form-data; name=\"{name}\"; "
                f"filename=\"{name}\"\r\nContent-Type: {content_type}\r\n\r\n").encode() + data + b"\r\n"
    return {"Content-Type": f"multipart/form-data; boundary={boundary}"}, out + f"--{boundary}--\r\n".encode()


def workloads(data, work, repeats):
    rig = load_rig_benchmark()
    import sqlite3
    names = [line.split()[0] for line in open(os.path.join(data, "queries_with_intrinsics.txt"))
             if line.strip()]
    cameras = {line.split()[0]: " ".join(line.split()[1:])
               for line in open(os.path.join(data, "queries_with_intrinsics.txt")) if line.strip()}
    photos = [open(os.path.join(data, "query_images", n), "rb").read() for n in names]
    with open(os.path.join(work, "photos.txt"), "w") as out:
        out.write("".join(n + "\n" for n in names) * repeats)
    db = sqlite3.connect(os.path.join(data, "database.db"))
    features = []
    for name in names:
        xy, d = rig.database_features(db, name)
        binary = b"CWLF" + struct.pack("<II", 1, len(xy)) + xy.astype("<f4").tobytes() + d.tobytes()
        options = json.dumps({"camera": cameras[name], "name": name}).encode()
        features.append(multipart([("features", "application/octet-stream", binary),
                                   ("options", "application/json", options)]))
    with open(os.path.join(work, "features.txt"), "w") as out:
        out.write("".join(f"{n} {cameras[n]}\n" for n in names) * repeats)
    photo_bodies = [({"Content-Type": "image/jpeg"}, p) for p in photos]
    return [
        Workload("photos", photo_bodies,
                 ["--image-list", os.path.join(work, "photos.txt"),
                  "--image-dir", os.path.join(data, "query_images")]),
        Workload("features", features,
                 ["--database", os.path.join(data, "database.db"),
                  "--query-list", os.path.join(work, "features.txt")]),
    ], len(names) * repeats


def peer_rate(index, workload, count, threads):
    command = " ".join([os.path.join(BIN, "cwloc-localize"), "--index", index, "--threads",
                        str(threads), "-q", "-o", "/dev/null"] + workload.cli_args)
    report = os.path.join(tempfile.mkdtemp(), "hyperfine.json")
    run(["hyperfine", "--runs", "3", "--warmup", "1", "-i", "--export-json", report, command])
    seconds = statistics.median(json.load(open(report))["results"][0]["times"])
    return count / seconds


class Server:
    def __init__(self, index, threads, extra=()):
        self.process = subprocess.Popen(
            [os.path.join(BIN, "cwloc-serve"), "--index", index, "--listen", "127.0.0.1:0",
             "--threads", str(threads), "-q", *extra], stderr=subprocess.PIPE, text=True)
        line = self.process.stderr.readline()
        match = re.search(r"127\.0\.0\.1:(\d+)/", line)
        if not match:
            sys.exit(f"cwloc-serve did not start: {line}")
        self.port = int(match.group(1))

    def rss_kib(self):
        for line in open(f"/proc/{self.process.pid}/status"):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        return 0

    def stop(self):
        self.process.terminate()
        self.process.wait()


def wrk(port, workload, seconds, connections, work):
    """wrk's requests per second and latency percentiles (ms), the bodies sent in turn."""
    for i, (headers, body) in enumerate(workload.bodies):
        open(os.path.join(work, f"{workload.name}-{i}.body"), "wb").write(body)
    script = os.path.join(work, f"{workload.name}.lua")
    with open(script, "w") as out:
        out.write("local bodies, headers, n = {}, {}, 0\n")
        for i, (headers, _) in enumerate(workload.bodies):
            path = os.path.join(work, f"{workload.name}-{i}.body")
            out.write(f"do local f = io.open('{path}', 'rb'); bodies[{i + 1}] = f:read('*all'); "
                      f"f:close() end\n")
            out.write(f"headers[{i + 1}] = {{['Content-Type'] = '{headers['Content-Type']}'}}\n")
        out.write("request = function()\n  n = n % #bodies + 1\n"
                  "  return wrk.format('POST', '/v1/localize', headers[n], bodies[n])\nend\n"
                  "done = function(summary, latency, requests)\n"
                  "  io.write(string.format('RESULT %d %d %d %d %d %d\\n', summary.requests,"
                  " summary.duration, summary.errors.status + summary.errors.connect +"
                  " summary.errors.read + summary.errors.write + summary.errors.timeout,"
                  " latency:percentile(50), latency:percentile(99), latency.max))\nend\n")
    out = run(["wrk", "-t1", f"-c{connections}", f"-d{seconds}s", "--timeout", "30s", "-s", script,
               f"http://127.0.0.1:{port}"])
    requests, duration_us, errors, p50, p99, _ = map(int, out.split("RESULT")[1].split())
    return requests / (duration_us / 1e6), p50 / 1e3, p99 / 1e3, errors


def open_loop(port, workload, rate, seconds, deadline_s=None):
    """Requests at fixed times (rate per second) whatever the answers' latency; per answer its
    status, latency from its scheduled time (s), whether it localized, and when it came (s from
    the first request's time)."""
    jobs = queue.Queue()
    results, lock = [], threading.Lock()
    start = time.monotonic() + 0.2

    def client():
        connection = None
        while True:
            job = jobs.get()
            if job is None:
                return
            when, (headers, body) = job
            time.sleep(max(0.0, when - time.monotonic()))
            for attempt in range(2):  # a keep-alive connection the server closed: reconnect once
                try:
                    if connection is None:
                        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                    connection.request("POST", "/v1/localize", body, headers)
                    response = connection.getresponse()
                    answer = response.read()
                    status = response.status
                    localized = status == 200 and b'"success":true' in answer
                    break
                except (http.client.HTTPException, OSError):
                    connection, status, localized = None, 0, False
            with lock:
                results.append((status, time.monotonic() - when, localized, time.monotonic() - start))

    total = int(rate * seconds)
    threads = [threading.Thread(target=client) for _ in range(min(64, max(4, int(rate) * 2)))]
    for thread in threads:
        thread.start()
    for i in range(total):
        jobs.put((start + i / rate, workload.bodies[i % len(workload.bodies)]))
    for _ in threads:
        jobs.put(None)
    for thread in threads:
        thread.join()
    return results


def statuses_text(results):
    """"200: N 503: M ..." (0: no answer: the connection failed)."""
    counts = {}
    for status, _, _, _ in results:
        counts[status] = counts.get(status, 0) + 1
    return " ".join(f"{s}: {n}" for s, n in sorted(counts.items()))


def percentile(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(p / 100 * len(values)))] if values else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("work")
    parser.add_argument("--data", default="herz_jesu_p25")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seconds", type=int, default=20)
    parser.add_argument("--soak-seconds", type=int, default=600)
    parser.add_argument("--soak-photos", action="store_true")
    parser.add_argument("--repeats", type=int, default=8, help="the peer's passes over the queries")
    args = parser.parse_args()
    data = args.data if os.path.isdir(args.data) else os.path.join(SHARED, args.data)
    os.makedirs(args.work, exist_ok=True)
    index = os.path.join(args.work, "index.cwl")
    if not os.path.exists(index):
        run([os.path.join(BIN, "cwloc-index"), "build", "--model",
             os.path.join(data, "mapping_model", "bin"), "--database",
             os.path.join(data, "database.db"), "-o", index])
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
                if l.startswith("model name")), "?")
    print(f"cwloc-serve benchmark: {data}, {os.cpu_count()} cores ({cpu}), --threads {args.threads}")
    loads, count = workloads(data, args.work, args.repeats)
    rows = []
    soak_load = None
    for load in loads:
        peer = peer_rate(index, load, count, args.threads)
        server = Server(index, args.threads)
        wrk(server.port, load, 3, 2 * args.threads, args.work)  # warm the page cache
        rate, p50, p99, errors = wrk(server.port, load, args.seconds, 2 * args.threads, args.work)
        server.stop()
        rows.append((load.name, "throughput", f"{rate:.1f}/s", f"{rate / peer:.2f} of "
                     f"cwloc-localize's {peer:.1f}/s", f"p50 {p50:.1f} ms, p99 {p99:.1f} ms",
                     f"{errors} errors"))

        server = Server(index, args.threads)
        steady = open_loop(server.port, load, 0.8 * rate, args.seconds)
        server.stop()
        latencies = [l for s, l, _, _ in steady if s == 200]
        p50, p99 = percentile(latencies, 50), percentile(latencies, 99)
        rows.append((load.name, "80 %", f"{0.8 * rate:.1f}/s", statuses_text(steady),
                     f"p50 {p50 * 1e3:.1f} ms, p99 {p99 * 1e3:.1f} ms",
                     f"p99/p50 {p99 / p50:.2f}"))

        budget_ms = max(200, int(4 * 1e3 * args.threads / rate))
        server = Server(index, args.threads, ["--budget-ms", str(budget_ms)])
        over = open_loop(server.port, load, 2 * rate, args.seconds)
        server.stop()
        late = sum(1 for s, l, _, _ in over if l > budget_ms / 1e3 + 0.5)
        localized = sum(1 for _, _, ok, _ in over if ok) / max(t for _, _, _, t in over)
        rows.append((load.name, "200 %", f"{2 * rate:.1f}/s, --budget-ms {budget_ms}",
                     statuses_text(over),
                     f"{late} later than the budget + 0.5 s",
                     f"{localized:.1f} localized/s ({localized / rate:.2f} of throughput)"))
        if (load.name == "photos") == args.soak_photos:
            soak_load, soak_rate = load, 0.8 * rate

    if args.soak_seconds > 0:
        server = Server(index, args.threads)
        rss, stop = [], threading.Event()

        def sample():  # every 30 s: the first after the warm-up, the trend after
            while not stop.wait(30):
                rss.append(server.rss_kib())

        sampler = threading.Thread(target=sample)
        sampler.start()
        soak = open_loop(server.port, soak_load, soak_rate, args.soak_seconds)
        stop.set()
        sampler.join()
        rss = {"start": rss[0] if rss else server.rss_kib(), "end": server.rss_kib(), "all": rss}
        server.stop()
        rows.append((soak_load.name, f"soak {args.soak_seconds} s", f"{soak_rate:.1f}/s",
                     statuses_text(soak),
                     f"RSS {rss.get('start', 0) / 1024:.1f} -> {rss['end'] / 1024:.1f} MiB",
                     f"{100 * (rss['end'] / rss.get('start', rss['end']) - 1):+.1f} %"))

    widths = [max(len(str(r[i])) for r in rows) for i in range(6)]
    for row in rows:
        print("  ".join(str(c).ljust(w) for c, w in zip(row, widths)))
    if args.soak_seconds > 0:
        print("soak RSS every 30 s (MiB): " + " ".join(f"{k / 1024:.1f}" for k in rss["all"]))


if __name__ == "__main__":
    main()
