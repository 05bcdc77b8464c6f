#!/usr/bin/python3
"""cwloc-serve under load, against cwloc-localize on the same queries (docs/benchmarks.md, "Service").

Two workloads from a data set of ../shared/data's layout: its query photos, sent as the bare
body (`curl --data-binary`), and their SIFT features from database.db in the binary layout with
the query's camera (multipart, docs/serve.md), as a device that extracts on board sends them.

  pinning      on a machine of 2 cores or more the server and the peer run on core 0
               (taskset), this script and its load generators on core 1: the client never
               takes the server's core (--no-pin to share them)
  peer         cwloc-localize --threads N on the same queries repeated, about 20 s of them (the
               photos by --image-list, the features from the database by --query-list with
               their cameras): queries per second
  throughput   wrk -c 2N for --seconds against cwloc-serve --threads N (warmed by 3 s of the
               same): requests per second, median and p99 latency; --rounds times, alternating
               with the peer, and the ratio of the medians (the rate the 80 % and 200 % loads
               and the soak take, in this run)
  80 %         an open-loop client (cwloc-load-bench: requests at fixed times whatever the
               answers' latency, latency from each one's time) at 80 % of that throughput,
               against a warmed server: median and p99 latency, their ratio
  overload     the same at 200 %, with --budget-ms: answers by status, answers later than the
               budget plus 0.5 s, localized queries per second against the throughput
  soak         80 % for --soak-seconds (features; photos with --soak-photos): errors, and
               cwloc-serve's RSS 30 s in and at the end
  limits       a request announcing a 1 GB body: time to its 413 (median of 5), and a features
               query's time right after; fast clients (2 connections sending features without
               pause) alone and beside 300 slow clients that send their bodies a byte a second:
               the fast clients' rate with them over the rate without

    bench/serve_benchmark.py WORKDIR [--data herz_jesu_p25] [--threads 1] [--seconds 20] [--rounds 4]
                             [--soak-seconds 600] [--no-pin]
Localhost only. Needs wrk and hyperfine (tools/install-deps.sh) and build/bin/cwloc-load-bench.
"""
import argparse
import http.client
import json
import os
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

    def __init__(self, name, bodies, cli_args, count, work):
        self.name, self.bodies, self.cli_args = name, bodies, cli_args  # bodies: (headers, bytes)
        self.count = count  # the queries cwloc-localize runs
        # The bodies as files, for wrk and cwloc-load-bench, written once.
        self.body_paths = [os.path.join(work, f"{name}-{i}.body") for i in range(len(bodies))]
        for path, (_, body) in zip(self.body_paths, bodies):
            open(path, "wb").write(body)


def multipart(parts):
    boundary = "cwlocbenchboundary"
    out = b""
    for name, content_type, data in parts:
        out += (f"--{boundary}\r\nContent-Disposition: form-data; name=\"{name}\"; "
                f"filename=\"{name}\"\r\nContent-Type: {content_type}\r\n\r\n").encode() + data + b"\r\n"
    return {"Content-Type": f"multipart/form-data; boundary={boundary}"}, out + f"--{boundary}--\r\n".encode()


def workloads(data, work, photo_repeats, feature_repeats):
    rig = load_rig_benchmark()
    import sqlite3
    names = [line.split()[0] for line in open(os.path.join(data, "queries_with_intrinsics.txt"))
             if line.strip()]
    cameras = {line.split()[0]: " ".join(line.split()[1:])
               for line in open(os.path.join(data, "queries_with_intrinsics.txt")) if line.strip()}
    photos = [open(os.path.join(data, "query_images", n), "rb").read() for n in names]
    with open(os.path.join(work, "photos.txt"), "w") as out:
        out.write("".join(n + "\n" for n in names) * photo_repeats)
    db = sqlite3.connect(os.path.join(data, "database.db"))
    features = []
    for name in names:
        xy, d = rig.database_features(db, name)
        binary = b"CWLF" + struct.pack("<II", 1, len(xy)) + xy.astype("<f4").tobytes() + d.tobytes()
        options = json.dumps({"camera": cameras[name], "name": name}).encode()
        features.append(multipart([("features", "application/octet-stream", binary),
                                   ("options", "application/json", options)]))
    with open(os.path.join(work, "features.txt"), "w") as out:
        out.write("".join(f"{n} {cameras[n]}\n" for n in names) * feature_repeats)
    photo_bodies = [({"Content-Type": "image/jpeg"}, p) for p in photos]
    return [
        Workload("photos", photo_bodies,
                 ["--image-list", os.path.join(work, "photos.txt"),
                  "--image-dir", os.path.join(data, "query_images")], len(names) * photo_repeats,
                 work),
        Workload("features", features,
                 ["--database", os.path.join(data, "database.db"),
                  "--query-list", os.path.join(work, "features.txt")], len(names) * feature_repeats,
                 work),
    ]


SERVER_CORE = []  # ["taskset", "-c", "0"] when pinned (main)


def peer_rate(index, workload, threads):
    command = " ".join(SERVER_CORE + [os.path.join(BIN, "cwloc-localize"), "--index", index,
                                      "--threads", str(threads), "-q", "-o", "/dev/null"] +
                       workload.cli_args)
    report = os.path.join(tempfile.mkdtemp(), "hyperfine.json")
    run(["hyperfine", "--runs", "1", "-i", "--export-json", report, command])
    seconds = statistics.median(json.load(open(report))["results"][0]["times"])
    return workload.count / seconds


class Server:
    def __init__(self, index, threads, extra=()):
        self.process = subprocess.Popen(
            SERVER_CORE + [os.path.join(BIN, "cwloc-serve"), "--index", index, "--listen", "127.0.0.1:0",
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


def warm_server(index, threads, workload, work, extra=()):
    """A server that has answered 3 s of the workload: its first answers fault in the index's
    pages and the allocator's arenas, tens of ms that would queue the loads behind them."""
    server = Server(index, threads, extra)
    wrk(server.port, workload, 3, 2 * threads, work)
    return server


def wrk(port, workload, seconds, connections, work):
    """wrk's requests per second and latency percentiles (ms), the bodies sent in turn."""
    script = os.path.join(work, f"{workload.name}.lua")
    with open(script, "w") as out:
        out.write("local bodies, headers, n = {}, {}, 0\n")
        for i, ((headers, _), path) in enumerate(zip(workload.bodies, workload.body_paths)):
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


def open_loop(port, workload, rate, seconds):
    """Requests at fixed times (rate per second) whatever the answers' latency (cwloc-load-bench,
    compiled: this script's own pauses would show as the server's); per answer its status,
    latency from its scheduled time (s), whether it localized, and when it came (s from the
    first request's time). A connection per 0.25 s of requests: at 200 % with a budget of
    seconds, the answers in flight never wait for a free connection on the client's side."""
    bodies = []
    for (headers, _), path in zip(workload.bodies, workload.body_paths):
        bodies += ["--body", f"{path}:{headers['Content-Type']}"]
    out = run([os.path.join(BIN, "cwloc-load-bench"), "--port", str(port), "--rate", str(rate),
               "--seconds", str(seconds), "--connections", str(min(256, max(16, int(rate * 4)))),
               *bodies])
    return [(int(s), float(l), l_ok == "1", float(t))
            for s, l, l_ok, t in (line.split() for line in out.splitlines())]


def announced_gigabyte(port):
    """Milliseconds from sending a request that announces a 1 GB body (and its first 64 KiB) to
    reading its answer's status line; the status."""
    sock = socket.create_connection(("127.0.0.1", port))
    head = (b"POST /v1/localize HTTP/1.1\r\nHost: bench\r\nContent-Type: image/jpeg\r\n"
            b"Content-Length: 1000000000\r\n\r\n")
    start = time.monotonic()
    sock.sendall(head + b"\0" * 65536)
    answer = b""
    while b"\r\n" not in answer:
        chunk = sock.recv(4096)
        if not chunk:
            break
        answer += chunk
    elapsed = (time.monotonic() - start) * 1e3
    sock.close()
    return elapsed, int(answer.split()[1]) if answer else 0


def closed_loop(port, workload, seconds, connections=2):
    """Clients sending without pause over keep-alive: answers 200 per second."""
    stop = time.monotonic() + seconds
    counts = []

    def client():
        connection, done, n = None, 0, 0
        while time.monotonic() < stop:
            headers, body = workload.bodies[n % len(workload.bodies)]
            n += 1
            try:
                if connection is None:
                    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                connection.request("POST", "/v1/localize", body, headers)
                response = connection.getresponse()
                response.read()
                done += response.status == 200
            except (http.client.HTTPException, OSError):
                connection = None
        counts.append(done)

    threads = [threading.Thread(target=client) for _ in range(connections)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return sum(counts) / seconds


class SlowClients:
    """`count` connections that each announce a 100 kB body and send it a byte a second; one
    the server ends (408) is opened again."""

    def __init__(self, port, count):
        self.port, self.count = port, count
        self.stop = threading.Event()
        self.ended = 0
        self.thread = threading.Thread(target=self.run)

    def open(self):
        sock = socket.create_connection(("127.0.0.1", self.port))
        sock.setblocking(False)
        sock.send(b"POST /v1/localize HTTP/1.1\r\nHost: slow\r\nContent-Type: image/jpeg\r\n"
                  b"Content-Length: 100000\r\n\r\n")
        return sock

    def run(self):
        sockets = [self.open() for _ in range(self.count)]
        while not self.stop.wait(1.0):
            for i, sock in enumerate(sockets):
                try:
                    sock.send(b"x")
                    if sock.recv(4096, socket.MSG_PEEK):  # answered (408): ended
                        raise OSError
                except BlockingIOError:
                    pass
                except OSError:
                    sock.close()
                    self.ended += 1
                    sockets[i] = self.open()
        for sock in sockets:
            sock.close()

    def __enter__(self):
        self.thread.start()
        time.sleep(2)
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()


def limits_rows(index, threads, features, seconds):
    rows = []
    server = Server(index, threads)
    closed_loop(server.port, features, 2)  # warm
    answers = [announced_gigabyte(server.port) for _ in range(5)]
    alone_status = closed_loop(server.port, features, 1, connections=1)
    ms = statistics.median(a for a, _ in answers)
    rows.append(("limits", "1 GB announced", f"{', '.join(str(s) for _, s in answers)}",
                 f"413 in {ms:.1f} ms (median of 5)",
                 f"then {alone_status:.1f} features/s at once", ""))
    alone = closed_loop(server.port, features, seconds)
    with SlowClients(server.port, 300) as slow:
        beside = closed_loop(server.port, features, seconds)
    server.stop()
    rows.append(("limits", "300 slow clients", f"{alone:.1f}/s alone",
                 f"{beside:.1f}/s beside them", f"{beside / alone:.2f} of the rate alone",
                 f"{slow.ended} slow connections ended (408) and reopened"))
    return rows


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
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--no-pin", action="store_true",
                        help="let the server, the peer and the clients share every core")
    parser.add_argument("--seconds", type=int, default=20)
    parser.add_argument("--soak-seconds", type=int, default=600)
    parser.add_argument("--soak-photos", action="store_true")
    parser.add_argument("--rounds", type=int, default=4,
                        help="throughput measurements, alternating the server and the peer")
    parser.add_argument("--photo-repeats", type=int, default=8,
                        help="the peer's passes over the photos (about 20 s)")
    parser.add_argument("--feature-repeats", type=int, default=400,
                        help="the peer's passes over the features (about 20 s)")
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
    pinned = not args.no_pin and os.cpu_count() >= 2
    if pinned:  # the server and the peer on core 0, this script and what it starts on core 1
        SERVER_CORE.extend(["taskset", "-c", "0"])
        os.sched_setaffinity(0, {1})
    print(f"cwloc-serve benchmark: {data}, {os.cpu_count()} cores ({cpu}), --threads {args.threads}"
          f", {'server and peer on core 0, clients on core 1' if pinned else 'cores shared'}")
    loads = workloads(data, args.work, args.photo_repeats, args.feature_repeats)
    rows = []
    soak_load = None
    for load in loads:
        peers, rates = [], []
        peer_rate(index, load, args.threads)  # the page cache
        for _ in range(args.rounds):  # alternating, so that a drift of the machine touches both
            peers.append(peer_rate(index, load, args.threads))
            server = warm_server(index, args.threads, load, args.work)
            measured = wrk(server.port, load, args.seconds, 2 * args.threads, args.work)
            server.stop()
            rates.append(measured)
        peer = statistics.median(peers)
        rate = statistics.median(r[0] for r in rates)
        p50 = statistics.median(r[1] for r in rates)
        p99 = statistics.median(r[2] for r in rates)
        errors = sum(r[3] for r in rates)
        rows.append((load.name, "throughput", f"{rate:.1f}/s ({', '.join(f'{r[0]:.1f}' for r in rates)})",
                     f"{rate / peer:.2f} of cwloc-localize's {peer:.1f}/s "
                     f"({', '.join(f'{p:.1f}' for p in peers)})",
                     f"p50 {p50:.1f} ms, p99 {p99:.1f} ms", f"{errors} errors"))

        server = warm_server(index, args.threads, load, args.work)
        steady = open_loop(server.port, load, 0.8 * rate, args.seconds)
        server.stop()
        latencies = [l for s, l, _, _ in steady if s == 200]
        p50, p99 = percentile(latencies, 50), percentile(latencies, 99)
        rows.append((load.name, "80 %", f"{0.8 * rate:.1f}/s", statuses_text(steady),
                     f"p50 {p50 * 1e3:.1f} ms, p99 {p99 * 1e3:.1f} ms",
                     f"p99/p50 {p99 / p50:.2f}"))

        budget_ms = max(200, int(4 * 1e3 * args.threads / rate))
        server = warm_server(index, args.threads, load, args.work, ["--budget-ms", str(budget_ms)])
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

    rows += limits_rows(index, args.threads, loads[1], args.seconds)

    if args.soak_seconds > 0:
        server = warm_server(index, args.threads, soak_load, args.work)
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
