"""Real servers for the service tests: `flexmech serve` (uvicorn running the app), PostgreSQL, a Dask cluster.

Each is a separate process on loopback, started the way an operator would start it, and
stopped (or killed) as a whole process group.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

REPO = Path(__file__).resolve().parents[1]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Process:
    """A command in its own process group, its output in a log file."""

    def __init__(self, args: list[str], log: Path, env: dict[str, str] | None = None):
        self.args = args
        self.log = log
        self._log_file = open(log, "ab")
        self.proc = subprocess.Popen(
            args,
            stdout=self._log_file,
            stderr=subprocess.STDOUT,
            cwd=REPO,
            env={**os.environ, **(env or {})},
            start_new_session=True,
        )

    def output(self, tail: int | None = 4000) -> str:
        text = self.log.read_text(errors="replace")
        return text[-tail:] if tail else text

    def running(self) -> bool:
        return self.proc.poll() is None

    def _signal(self, sig: int) -> None:
        try:
            os.killpg(self.proc.pid, sig)
        except ProcessLookupError:
            pass

    def stop(self, timeout: float = 15.0) -> None:
        if self.running():
            self._signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.kill()
        self._log_file.close()

    def kill(self) -> None:
        """SIGKILL to the whole group: the server and its worker processes die at once, as in
        a power cut; nothing gets to clean up."""
        self._signal(signal.SIGKILL)
        self.proc.wait(10)
        self._log_file.close()


class ApiServer(Process):
    def __init__(self, env: dict[str, str], log: Path, port: int | None = None, access_log: bool = False):
        self.port = port or free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        level = "info" if access_log else "warning"
        super().__init__(
            [sys.executable, "-m", "flexmech.api.cli", "serve", "--host", "127.0.0.1", "--port", str(self.port)],
            log,
            {"FLEXMECH_LOG_LEVEL": level, **env},
        )
        self.wait_ready()

    def wait_ready(self, timeout: float = 90.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if not self.running():
                raise RuntimeError(f"the server exited with {self.proc.returncode}:\n{self.output()}")
            try:
                if httpx.get(self.url + "/v1/health", timeout=2).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.1)
        self.stop()
        raise RuntimeError(f"the server did not answer /v1/health in {timeout} s:\n{self.output()}")


# --- PostgreSQL -----------------------------------------------------------------------------
def postgres_bin() -> Path | None:
    """The folder of the PostgreSQL server programs (initdb, pg_ctl), if installed."""
    for name in ("pg_ctl", "initdb"):
        found = shutil.which(name)
        if found:
            return Path(found).resolve().parent
    versions = sorted(Path("/usr/lib/postgresql").glob("*/bin"), reverse=True)
    return versions[0] if versions else None


class PostgresServer:
    """A throwaway PostgreSQL cluster in `directory`, listening on 127.0.0.1:port. As root it
    runs as the 'postgres' system user (PostgreSQL refuses to run as root)."""

    def __init__(self, directory: Path, port: int | None = None):
        bindir = postgres_bin()
        if bindir is None:
            raise RuntimeError(
                "PostgreSQL server programs not found: install the Debian package "
                "'postgresql' (.ci/run does), or set FLEXMECH_TEST_POSTGRES_URL"
            )
        self.port = port or free_port()
        self.directory = directory
        self.data = directory / "data"
        self.user = "flexmech"
        as_root = os.geteuid() == 0
        prefix = ["runuser", "-u", "postgres", "--"] if as_root else []
        directory.mkdir(parents=True, exist_ok=True)
        if as_root:
            shutil.chown(directory, "postgres", "postgres")
        self._prefix = prefix
        self._bindir = bindir
        self._run([str(bindir / "initdb"), "-D", str(self.data), "-U", self.user, "--auth=trust", "-E", "UTF8"])
        self._run(
            [
                str(bindir / "pg_ctl"),
                "-D",
                str(self.data),
                "-l",
                str(directory / "server.log"),
                "-w",
                "-o",
                f"-p {self.port} -k {directory} -c listen_addresses=127.0.0.1 -c fsync=off",
                "start",
            ]
        )
        self.url = f"postgresql+psycopg://{self.user}@127.0.0.1:{self.port}/postgres"

    def _run(self, args: list[str]) -> None:
        done = subprocess.run(self._prefix + args, capture_output=True, text=True, cwd=self.directory)
        if done.returncode != 0:
            raise RuntimeError(f"{' '.join(args[:1])} failed: {done.stdout}\n{done.stderr}")

    def stop(self) -> None:
        self._run([str(self._bindir / "pg_ctl"), "-D", str(self.data), "-m", "immediate", "stop"])


def fresh_database(server_url: str, name: str) -> str:
    """Create database `name` on the server of `server_url` (dropping an old one); its URL."""
    from sqlalchemy import create_engine, text
    from sqlalchemy.engine import make_url

    engine = create_engine(server_url, isolation_level="AUTOCOMMIT")
    with engine.connect() as conn:
        conn.execute(text(f'DROP DATABASE IF EXISTS "{name}"'))
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    engine.dispose()
    return make_url(server_url).set(database=name).render_as_string(hide_password=False)


# --- Dask -----------------------------------------------------------------------------------
class DaskCluster:
    """A scheduler and `workers` worker processes (one thread each), started by the dask CLI."""

    def __init__(self, directory: Path, workers: int = 2):
        directory.mkdir(parents=True, exist_ok=True)
        port = free_port()
        self.address = f"tcp://127.0.0.1:{port}"
        dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
        self.scheduler = Process(
            dask + ["--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], directory / "scheduler.log"
        )
        self.workers = [
            Process(
                [
                    sys.executable,
                    "-m",
                    "distributed.cli.dask_worker",
                    self.address,
                    "--nthreads",
                    "1",
                    "--nworkers",
                    "1",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                    "--local-directory",
                    str(directory / f"worker{k}"),
                ],
                directory / f"worker{k}.log",
            )
            for k in range(workers)
        ]
        self._wait_for_workers(workers)

    def _wait_for_workers(self, n: int, timeout: float = 90.0) -> None:
        from distributed import Client

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                with Client(self.address, timeout=5) as client:
                    client.wait_for_workers(n, timeout=max(1.0, deadline - time.monotonic()))
                    return
            except (OSError, TimeoutError):
                time.sleep(0.5)
        raise RuntimeError(f"the Dask cluster at {self.address} did not get {n} workers:\n" + self.scheduler.output())

    def stop(self) -> None:
        for w in self.workers:
            w.stop()
        self.scheduler.stop()
