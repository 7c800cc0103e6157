"""A real two-node Ray cluster on this machine, for the tests: ``ray start --head`` and a second
``ray start --address`` node, each with its own temporary folder (``--temp-dir`` and ``TMPDIR``), so the
nodes share no working folder.

Every port is a free one picked here (GCS, node and object managers, dashboard and its agent,
runtime-env agent, metrics), so that two clusters (two engineers, two CI jobs) do not collide.
Every process of the cluster carries an environment marker (``SCENARIO_TEST_CLUSTER``, one value per
node): the test finds a node's Ray workers by it, and :meth:`Cluster.stop` kills every process that
carries it, whatever it became (a worker's engine child in its own process group included), and
checks that none is left. ``ray stop`` is not used: it stops every Ray process of the user on the
machine, another cluster included.

The folders are short ones under /tmp (Ray's socket paths must fit in 107 bytes; pytest's ``tmp_path``
does not), removed by :meth:`Cluster.stop`.

Readiness is event-driven: a node is up when its ``ray start --block`` prints its last line, "will now
block forever" (after "Ray runtime started" and the address to join; read line by line from its
pipe); the cluster is up when the GCS lists both nodes alive.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

MARKER = "SCENARIO_TEST_CLUSTER"
READY = "will now block forever"  # `ray start --block`'s last line once the node is up
RAY = Path(sys.executable).with_name("ray")


def free_ports(n: int) -> list[int]:
    """``n`` distinct ports free now (bound then released together, so they differ)."""
    socks = []
    try:
        for _ in range(n):
            s = socket.socket()
            s.bind(("127.0.0.1", 0))
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def marked(value: str) -> list[int]:
    """Processes (this user's) whose environment carries ``MARKER=value``."""
    needle = f"{MARKER}={value}".encode()
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        with contextlib.suppress(OSError):
            if needle in (entry / "environ").read_bytes().split(b"\0"):
                found.append(int(entry.name))
    return found


def title(pid: int) -> str:
    with contextlib.suppress(OSError):
        return (Path("/proc") / str(pid) / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    return ""


def parent(pid: int) -> int:
    with contextlib.suppress(OSError, ValueError, IndexError):
        return int((Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[1])
    return 0


def workers_running(marker: str, function: str) -> list[int]:
    """The Ray worker processes of the node marked ``marker`` executing ``function`` now (a Ray worker's
    title is ``ray::<function>`` while it runs a task; the children it starts are not counted)."""
    pids = marked(marker)
    return [p for p in pids if title(p).startswith(f"ray::{function}") and "raylet" in title(parent(p))]


@dataclass
class Node:
    name: str
    marker: str
    process: subprocess.Popen[str]
    lines: list[str] = field(default_factory=list)
    ready: threading.Event = field(default_factory=threading.Event)

    def read(self) -> None:
        """Reads the node's output (in a thread) and sets ``ready`` when it says so, or when it ends."""
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line)
            if READY in line:  # printed last, after "Ray runtime started" and the address to join
                self.ready.set()
        self.ready.set()  # it ended: whoever waits sees that it is not running

    def workers_running(self, function: str) -> list[int]:
        return workers_running(self.marker, function)


class Cluster:
    """See the module docstring. ``address`` is the head's GCS address (``host:port``)."""

    def __init__(self, cpus_per_node: int = 1) -> None:
        self.root = Path(tempfile.mkdtemp(prefix="scn-ray-", dir="/tmp"))
        self.cpus = cpus_per_node
        self.tag = secrets.token_hex(6)
        self.env = {**os.environ, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32),
                    "RAY_USAGE_STATS_ENABLED": "0"}  # fmt: skip
        self.nodes: list[Node] = []
        self.address = ""

    def _start(self, name: str, *args: str, timeout: float) -> Node:
        folder = self.root / name
        (folder / "tmp").mkdir(parents=True)
        marker = f"{self.tag}-{name}"
        env = {**self.env, MARKER: marker, "TMPDIR": str(folder / "tmp")}
        cmd = [str(RAY), "start", "--block", f"--temp-dir={folder}", f"--num-cpus={self.cpus}",
               "--disable-usage-stats", *args]  # fmt: skip
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                start_new_session=True)  # fmt: skip
        node = Node(name, marker, proc)
        self.nodes.append(node)
        threading.Thread(target=node.read, daemon=True).start()
        if not node.ready.wait(timeout) or proc.poll() is not None:
            raise RuntimeError(f"Ray node `{name}` did not start in {timeout:g} s:\n{''.join(node.lines[-30:])}")
        return node

    def start(self, timeout: float = 90.0) -> None:
        gcs, dash, *rest = free_ports(2 + 2 * 6)
        head = self._ports(rest[:6]) + [f"--port={gcs}", f"--dashboard-port={dash}", "--include-dashboard=false"]
        node = self._start("head", "--head", *head, timeout=timeout)
        # the address the head gives other nodes (its own IP, which Ray picks; the GCS listens there)
        found = re.search(r"ray start --address='([^']+)'", "".join(node.lines))
        if found is None:
            raise RuntimeError(f"the Ray head did not print its address:\n{''.join(node.lines[-30:])}")
        self.address = found.group(1)
        self._start("worker", f"--address={self.address}", *self._ports(rest[6:]), timeout=timeout)

    @staticmethod
    def _ports(ports: list[int]) -> list[str]:
        names = ["node-manager-port", "object-manager-port", "dashboard-agent-listen-port",
                 "dashboard-agent-grpc-port", "runtime-env-agent-port", "metrics-export-port"]  # fmt: skip
        return [f"--{n}={p}" for n, p in zip(names, ports, strict=True)]

    def wait_for_nodes(self, timeout: float = 60.0) -> None:
        """Until the GCS lists every node alive: ``ray status`` asked once (it waits for the GCS), then
        polled (Ray has no call that waits for a number of nodes)."""
        deadline = time.monotonic() + timeout
        while True:
            status = subprocess.run([str(RAY), "status", f"--address={self.address}"], env=self.env,
                                    capture_output=True, text=True, timeout=timeout)  # fmt: skip
            if status.stdout.count("node_") >= len(self.nodes) and "Pending:" in status.stdout:
                return
            if time.monotonic() > deadline:
                raise RuntimeError(f"the Ray cluster has not got {len(self.nodes)} nodes after {timeout:g} s:\n"
                                   f"{status.stdout}{status.stderr}")  # fmt: skip
            time.sleep(0.5)

    def leftovers(self) -> list[int]:
        return [p for node in self.nodes for p in marked(node.marker)]

    def stop(self, timeout: float = 30.0) -> list[int]:
        """Kill every process of the cluster (the worker node first) and reap ours; the pids still alive
        after ``timeout`` (should be none)."""
        for node in reversed(self.nodes):
            with contextlib.suppress(ProcessLookupError):
                os.killpg(node.process.pid, signal.SIGKILL)
            for pid in marked(node.marker):  # what left the group (engine children set their own)
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            node.process.wait()
        deadline = time.monotonic() + timeout
        while self.leftovers() and time.monotonic() < deadline:
            for pid in self.leftovers():
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            time.sleep(0.1)
        left = self.leftovers()
        if not left:
            shutil.rmtree(self.root, ignore_errors=True)
        return left
