#!/usr/bin/env python3
"""cwloc-serve as an operator runs it: Debian's nginx with TLS (a self-signed certificate) in
front of two replicas, configured by deploy/nginx-cwloc.conf. Checks that

  - a photo's pose through the proxy equals the CLI's (--expected-json, a cwloc-localize record);
  - a rolling restart of the replicas (each stopped with SIGTERM and started again while clients
    send photos without pause) fails no request, and every answer has the CLI's pose;
  - a replica killed with SIGKILL under the same load fails no request: the other answers;
  - a session's frames go on through the restarts (a replica that never held it opens it again).

Prints a table of what it measured and exits 0 when all held, 1 when one failed, 77 when nginx or
openssl is missing. Run by ServeTest.NginxWithTlsInFrontOfTwoReplicas (serve_test.cc).
"""
import argparse
import http.client
import json
import os
import re
import shutil
import signal
import socket
import ssl
import subprocess
import sys
import threading
import time
import uuid


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Replica:
    def __init__(self, serve, index, port, log_dir):
        self.args = [serve, "--index", index, "--listen", f"127.0.0.1:{port}", "--threads", "1"]
        self.port = port
        self.log = os.path.join(log_dir, f"replica-{port}.log")
        self.process = None

    def start(self):
        with open(self.log, "a") as log:
            self.process = subprocess.Popen(self.args, stdout=log, stderr=log)
        deadline = time.time() + 30
        while time.time() < deadline:
            try:
                connection = http.client.HTTPConnection("127.0.0.1", self.port, timeout=2)
                connection.request("GET", "/healthz")
                if connection.getresponse().status == 200:
                    return
            except OSError:
                pass
            if self.process.poll() is not None:
                break
            time.sleep(0.05)
        raise RuntimeError(f"replica on {self.port} did not start: " + open(self.log).read())

    def stop(self, how=signal.SIGTERM):
        self.process.send_signal(how)
        self.process.wait(timeout=120)


def nginx_config(site_template, work, proxy_port, ports, cert, key):
    site = open(site_template).read()
    site = site.replace("127.0.0.1:8081", f"127.0.0.1:{ports[0]}")
    site = site.replace("127.0.0.1:8082", f"127.0.0.1:{ports[1]}")
    site = re.sub(r"listen 443 ssl http2;", f"listen 127.0.0.1:{proxy_port} ssl http2;", site)
    site = site.replace("/etc/ssl/certs/cwloc.pem", cert)
    site = site.replace("/etc/ssl/private/cwloc.key", key)
    for line in ("127.0.0.1:8081", "127.0.0.1:8082", "/etc/ssl"):
        assert line not in site, f"{site_template} changed: the test no longer rewrites {line}"
    temp = os.path.join(work, "temp")
    os.makedirs(temp, exist_ok=True)
    user = "user root;\n" if os.geteuid() == 0 else ""
    return (f"{user}worker_processes 1;\ndaemon off;\npid {work}/nginx.pid;\n"
            f"error_log {work}/error.log warn;\nevents {{ worker_connections 256; }}\n"
            f"http {{\n  access_log {work}/access.log;\n"
            f"  client_body_temp_path {temp}/body;\n  proxy_temp_path {temp}/proxy;\n"
            f"  fastcgi_temp_path {temp}/fastcgi;\n  uwsgi_temp_path {temp}/uwsgi;\n"
            f"  scgi_temp_path {temp}/scgi;\n{site}\n}}\n")


class Proxy:
    """HTTPS requests to nginx, checked against the certificate made for it."""

    def __init__(self, port, cert):
        self.port = port
        self.context = ssl.create_default_context(cafile=cert)

    def request(self, method, path, body=None, headers=None):
        connection = http.client.HTTPSConnection("localhost", self.port, context=self.context,
                                                 timeout=120)
        try:
            connection.request(method, path, body=body, headers=headers or {})
            response = connection.getresponse()
            return response.status, dict(response.getheaders()), response.read()
        finally:
            connection.close()

    def photo(self, path, photo_bytes, name):
        boundary = uuid.uuid4().hex
        body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"image\"; "
                f"filename=\"{name}\"\r\nContent-Type: image/jpeg\r\n\r\n").encode()
        body += photo_bytes + f"\r\n--{boundary}--\r\n".encode()
        return self.request("POST", path, body,
                            {"Content-Type": f"multipart/form-data; boundary={boundary}"})


class Load:
    """Clients sending the photo without pause; every answer must be 200 with the CLI's pose."""

    def __init__(self, proxy, photo_bytes, name, expected_pose, clients=3):
        self.proxy, self.photo_bytes, self.name = proxy, photo_bytes, name
        self.expected_pose = expected_pose
        self.answers, self.failures = 0, []
        self.lock = threading.Lock()
        self.running = True
        self.threads = [threading.Thread(target=self.client) for _ in range(clients)]

    def client(self):
        while self.running:
            try:
                status, _, body = self.proxy.photo("/v1/localize", self.photo_bytes, self.name)
                ok = status == 200 and json.loads(body).get("pose") == self.expected_pose
                failure = None if ok else f"{status} {body[:200]!r}"
            except Exception as error:  # a dropped connection is a failed request
                failure = repr(error)
            with self.lock:
                self.answers += 1
                if failure:
                    self.failures.append(failure)

    def __enter__(self):
        for thread in self.threads:
            thread.start()
        return self

    def __exit__(self, *exc):
        self.running = False
        for thread in self.threads:
            thread.join()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--serve", required=True)
    parser.add_argument("--index", required=True)
    parser.add_argument("--photo", required=True)
    parser.add_argument("--expected-json", required=True)
    parser.add_argument("--config", required=True, help="deploy/nginx-cwloc.conf")
    parser.add_argument("--work", required=True, help="an empty folder for the run's files")
    args = parser.parse_args()
    nginx, openssl = shutil.which("nginx") or "/usr/sbin/nginx", shutil.which("openssl")
    if not os.path.exists(nginx) or not openssl:
        print("skipped: nginx or openssl is not installed (tools/install-deps.sh installs them)")
        return 77

    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    cert, key = os.path.join(work, "cert.pem"), os.path.join(work, "key.pem")
    subprocess.run([openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2",
                    "-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost",
                    "-keyout", key, "-out", cert], check=True, capture_output=True)
    ports = [free_port(), free_port()]
    proxy_port = free_port()
    replicas = [Replica(args.serve, args.index, port, work) for port in ports]
    for replica in replicas:
        replica.start()
    config = os.path.join(work, "nginx.conf")
    with open(config, "w") as out:
        out.write(nginx_config(args.config, work, proxy_port, ports, cert, key))
    test = subprocess.run([nginx, "-t", "-p", work, "-c", config, "-e", f"{work}/error.log"],
                          capture_output=True, text=True)
    if test.returncode != 0:
        print("nginx -t refused the configuration:\n" + test.stderr)
        return 1
    proxy_process = subprocess.Popen([nginx, "-p", work, "-c", config, "-e", f"{work}/error.log"])
    proxy = Proxy(proxy_port, cert)
    try:
        return run_checks(args, proxy, replicas)
    finally:
        proxy_process.terminate()
        proxy_process.wait(timeout=30)
        for replica in replicas:
            if replica.process.poll() is None:
                replica.stop()


def run_checks(args, proxy, replicas):
    deadline = time.time() + 30
    while True:
        try:
            if proxy.request("GET", "/healthz")[0] == 200:
                break
        except OSError:
            pass
        if time.time() > deadline:
            print("nginx did not answer")
            return 1
        time.sleep(0.05)
    expected = json.load(open(args.expected_json))
    photo_bytes = open(args.photo, "rb").read()
    name = os.path.basename(args.photo)
    rows, failed = [], False

    status, _, body = proxy.photo("/v1/localize", photo_bytes, name)
    same = status == 200 and json.loads(body)["pose"] == expected["pose"]
    rows.append(("a photo through nginx (TLS)", "1 request", "the CLI's pose" if same else
                 f"{status}, a different answer"))
    failed |= not same

    status, _, body = proxy.request("POST", "/v1/sessions", b'{"max-image-size": 800}',
                                    {"Content-Type": "application/json"})
    session = json.loads(body)["session"] if status == 201 else None
    frames = []

    def frame():
        status, headers, body = proxy.photo(f"/v1/sessions/{session}/frames", photo_bytes, name)
        frames.append((status, headers.get("X-Cwloc-Session", "")))

    frame()
    with Load(proxy, photo_bytes, name, expected["pose"]) as load:
        for replica in replicas:  # a rolling restart
            time.sleep(1.0)
            replica.stop(signal.SIGTERM)
            replica.start()
        time.sleep(1.0)
    frame()
    rows.append(("rolling restart of 2 replicas", f"{load.answers} requests",
                 f"{len(load.failures)} failed"))
    failed |= bool(load.failures) or load.answers == 0

    with Load(proxy, photo_bytes, name, expected["pose"]) as killed:
        time.sleep(1.0)
        replicas[0].stop(signal.SIGKILL)
        time.sleep(3.0)
    replicas[0].start()
    frame()
    rows.append(("one replica killed (SIGKILL)", f"{killed.answers} requests",
                 f"{len(killed.failures)} failed"))
    failed |= bool(killed.failures) or killed.answers == 0

    frames_ok = session is not None and all(status == 200 for status, _ in frames)
    reopened = sum(1 for _, header in frames if header == "reopened")
    rows.append(("a session's frames across both", f"{len(frames)} frames",
                 f"{'all' if frames_ok else 'not all'} 200, {reopened} reopened"))
    failed |= not frames_ok

    width = max(len(row[0]) for row in rows)
    print(f"{'check':<{width}}  {'load':>14}  result")
    for check, load_text, result in rows:
        print(f"{check:<{width}}  {load_text:>14}  {result}")
    for failure in (load.failures + killed.failures)[:5]:
        print("failure:", failure)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
