"""Shared fixtures: the seed-000 gripper in its example documents."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from flexmech.models import compile_mechanism, load_document

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ACTUATION = "/loads/actuation/force/1"


@pytest.fixture(scope="session")
def examples_dir() -> Path:
    return EXAMPLES


@pytest.fixture(scope="session")
def gripper_dict() -> dict:
    return json.loads((EXAMPLES / "gripper.json").read_text())


@pytest.fixture(scope="session", params=["linear", "partial_nonlinear"])
def gripper(request):
    """The silicon gripper, once per model."""
    return compile_mechanism(load_document(EXAMPLES / "gripper.json"), model=request.param)


@pytest.fixture(scope="session")
def gripper_pnl():
    return compile_mechanism(load_document(EXAMPLES / "gripper.json"), model="partial_nonlinear")


# --- real servers for the service tests (see tests/servers.py) ------------------------------
def _scratch(prefix: str) -> Path:
    """A folder under /tmp that other system users (postgres) can reach, unlike tmp_path."""
    import tempfile

    return Path(tempfile.mkdtemp(prefix=prefix))


@pytest.fixture(scope="session")
def postgres_server_url():
    """A PostgreSQL server: FLEXMECH_TEST_POSTGRES_URL when .ci/run started one, else a cluster
    started here (needs the PostgreSQL server programs installed)."""
    import os

    from servers import PostgresServer

    given = os.environ.get("FLEXMECH_TEST_POSTGRES_URL")
    if given:
        yield given
        return
    folder = _scratch("flexmech-pg-")
    server = PostgresServer(folder)
    yield server.url
    server.stop()
    shutil.rmtree(folder, ignore_errors=True)  # nothing left in the system's temp folder


@pytest.fixture(scope="session")
def dask_address():
    """A real Dask cluster: a scheduler and two worker processes, started by the dask CLI."""
    from servers import DaskCluster

    folder = _scratch("flexmech-dask-")
    cluster = DaskCluster(folder, workers=2)
    yield cluster.address
    cluster.stop()
    shutil.rmtree(folder, ignore_errors=True)


BACKENDS = ("sqlite", "postgresql", "dask")


class Deployment:
    """The settings of one way to run the service; start() runs a uvicorn server with them."""

    def __init__(self, name: str, env: dict[str, str], logs: Path):
        self.name = name
        self.env = env
        self.logs = logs
        self._count = 0

    def start(self, access_log: bool = False, **extra: str):
        from servers import ApiServer

        self._count += 1
        return ApiServer({**self.env, **extra}, self.logs / f"server{self._count}.log", access_log=access_log)


def sqlite_server(tmp_path_factory, name: str, workers: int = 2, keys: tuple[str, ...] = (), **settings: str):
    """A started server on SQLite with a process pool of `workers`, in a directory of its own
    named `name`; `keys` its API keys (none: open), `settings` more FLEXMECH_* variables."""
    tmp = tmp_path_factory.mktemp(name)
    env = {
        "FLEXMECH_DATA_DIR": str(tmp / "data"),
        "FLEXMECH_WORKERS": str(workers),
        "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
        "FLEXMECH_API_KEYS": ",".join(keys),
        **settings,
    }
    return Deployment("sqlite", env, tmp).start()


def make_deployment(backend: str, request, tmp_dir: Path) -> Deployment:
    env = {
        "FLEXMECH_DATA_DIR": str(tmp_dir / "data"),
        "FLEXMECH_WORKERS": "2",
        "FLEXMECH_CHUNK_SIZE": "4",
        "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
        "FLEXMECH_API_KEYS": "",
    }
    if backend in ("postgresql", "dask"):
        from servers import fresh_database

        server_url = request.getfixturevalue("postgres_server_url")
        env["FLEXMECH_DATABASE_URL"] = fresh_database(server_url, f"flexmech_{tmp_dir.name.lower()}"[:60])
    if backend == "dask":
        env["FLEXMECH_DASK_ADDRESS"] = request.getfixturevalue("dask_address")
    return Deployment(backend, env, tmp_dir)


@pytest.fixture(params=BACKENDS)
def deployment(request, tmp_path) -> Deployment:
    """SQLite with a process pool; PostgreSQL with a process pool; PostgreSQL with Dask."""
    return make_deployment(request.param, request, tmp_path)


@pytest.fixture(scope="module")
def api_server(tmp_path_factory):
    """One server (SQLite, process pool, no keys) shared by a test module."""
    tmp = tmp_path_factory.mktemp("api")
    server = Deployment(
        "sqlite",
        {
            "FLEXMECH_DATA_DIR": str(tmp / "data"),
            "FLEXMECH_WORKERS": "2",
            "FLEXMECH_EXAMPLES_DIR": str(EXAMPLES),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_MAX_REQUEST_BYTES": "200000",
            "FLEXMECH_MAX_SWEEP_POINTS": "1000",
        },
        tmp,
    ).start()
    yield server
    server.stop()
