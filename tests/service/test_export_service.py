"""The export job over real HTTP (issue 29): POST /v1/exports makes a job whose result is the C
library's manifest and whose archive (GET /v1/jobs/{id}/archive) is the library as .tar.gz;
only its key downloads it; bad fields are 422 naming them; and `flexmech batch --export` writes
a library per document. Nothing is compiled here (the export's own tests build the C)."""

from __future__ import annotations

import hashlib
import io
import json
import tarfile

import httpx
import pytest
from conftest import ACTUATION, EXAMPLES, sqlite_server
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.client import Client, FlexmechError

KEYS = ("export-first-key-0123", "export-second-key-0123")
CLOSING_FORCE = 77.0346  # uN: the gripper's target (end_effector.x = 0), solved at export


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    server = sqlite_server(tmp_path_factory, "export-api", workers=1, keys=KEYS)
    yield server
    server.stop()


@pytest.fixture(scope="module")
def gripper() -> dict:
    return json.loads((EXAMPLES / "gripper.json").read_text())


def unpacked(data: bytes) -> dict[str, bytes]:
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
        return {member.name: tar.extractfile(member).read() for member in tar.getmembers() if member.isfile()}


def test_an_export_job_gives_the_library_as_an_archive_to_its_key_only(server, gripper):
    with Client(server.url, api_key=KEYS[0]) as owner, Client(server.url, api_key=KEYS[1]) as other:
        job = owner.export(
            document=gripper, model="partial_nonlinear", name="gripper", inputs=[ACTUATION], outputs=["end_effector.x"]
        )
        assert job.kind == "export" and job.progress.total == 1
        assert job.links.archive == f"/v1/jobs/{job.id}/archive"
        data = owner.export_archive(job.id, timeout=120)
        result = owner.result(job.id).result
        with pytest.raises(FlexmechError) as refused:
            other.archive(job.id)
    assert refused.value.status == 404 and refused.value.message == f"no job '{job.id}'"
    files = unpacked(data)
    assert {"gripper/gripper.h", "gripper/gripper_kernels.c", "gripper/Makefile"} <= set(files)
    manifest = json.loads(files["gripper/manifest.json"])
    assert result["status"] == "exported" and result["manifest"] == manifest
    assert result["archive"] == {
        "file": "gripper.tar.gz",
        "bytes": len(data),
        "sha256": hashlib.sha256(data).hexdigest(),
    }
    assert [(i["name"], i["pointer"], i["unit"]) for i in manifest["inputs"]] == [
        ("actuation_force_y", ACTUATION, "uN")
    ]
    assert [(o["name"], o["output"], o["unit"]) for o in manifest["outputs"]] == [
        ("end_effector_x", "end_effector.x", "mm")
    ]
    assert manifest["model"] == "partial_nonlinear" and manifest["target"]["output"] == "end_effector.x"
    (swept,) = manifest["example_path"]["inputs"]  # the example's sweep runs to the target, solved at export
    assert swept["name"] == "actuation_force_y" and swept["stop"] == pytest.approx(CLOSING_FORCE, abs=1e-4)
    answer = httpx.get(f"{server.url}/v1/jobs/{job.id}/archive", headers={"X-API-Key": KEYS[0]})
    assert answer.headers["content-type"] == "application/gzip"
    assert answer.headers["content-disposition"] == 'attachment; filename="gripper.tar.gz"'


@pytest.mark.parametrize(
    ("fields", "pointer", "words"),
    [
        ({"outputs": ["end_effector.x", "closing"]}, "/outputs/1", "unknown output 'closing'"),
        ({"ranges": {ACTUATION: [5, 1]}}, "/ranges/~1loads~1actuation~1force~11", "expected low < high"),
        ({"target": {"output": "end_effector.x", "equals": 0, "by": "/loads/actuation/force/0"}}, "/target/by", ""),
        ({"max_iterations": 0}, "/max_iterations", "greater than or equal to 1"),
    ],
)
def test_a_bad_export_field_is_422_naming_it(server, gripper, fields, pointer, words):
    with Client(server.url, api_key=KEYS[0]) as client, pytest.raises(FlexmechError) as refused:
        client.export(document=gripper, inputs=[ACTUATION], **fields)
    assert refused.value.status == 422 and refused.value.pointer == pointer and words in refused.value.message


def test_batch_exports_each_document_into_its_own_folder(tmp_path):
    docs, out = tmp_path / "in", tmp_path / "out"
    docs.mkdir()
    (docs / "gripper.json").write_text((EXAMPLES / "gripper.json").read_text())
    options = json.dumps({"inputs": [ACTUATION], "outputs": ["end_effector.x"]})
    done = CliRunner().invoke(
        app, ["batch", str(docs), "--out", str(out), "--export", "--options", options], env={"NO_COLOR": "1"}
    )
    assert done.exit_code == 0, done.output
    row = json.loads((out / "summary.json").read_text())["results"][0]
    assert (row["analysis"], row["status"], row["succeeded"]) == ("export", "exported", True)
    library = out / "c" / "gripper"
    assert (library / "gripper.h").is_file() and (library / "gripper_kernels.c").is_file()
    manifest = json.loads((library / "manifest.json").read_text())
    assert json.loads((out / "gripper.json").read_text())["manifest"] == manifest
    assert [o["output"] for o in manifest["outputs"]] == ["end_effector.x"]
