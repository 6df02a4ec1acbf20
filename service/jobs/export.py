"""The export job: a mechanism's solver as a C99 library (service.export), written by a worker
into a temporary folder and stored as the job's one point: the manifest and the folder as a
.tar.gz archive (base64 text). A point is a row of the store, so the archive survives restarts
on SQLite and PostgreSQL alike and is read back by its owner only, as every result is.

spec:
  document, model, overrides   as for /v1/solve (Newton `options` are refused: the library's own
                               iteration is max_iterations, tolerance, line_search_halvings)
  name, inputs, outputs, ranges, target {output, equals, by}, max_iterations, tolerance,
  line_search_halvings         service.export.plan.ExportOptions
The result (GET /v1/jobs/{id}/result) is the manifest and the archive's file name, size and
SHA-256; the archive's bytes are GET /v1/jobs/{id}/archive (this kind's `archive`).
"""

from __future__ import annotations

import base64
import hashlib
import re
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.fields import MAX_POINTER_CHARS
from flexmech.service.costs import Limits, check_export_build, check_export_iteration, check_export_unknowns
from flexmech.service.deadline import stop_scope
from flexmech.service.jobs.base import JSON, JobOptions, Plan, StoredJob, read_spec
from flexmech.service.jobs.control import TaskControl
from flexmech.service.requests import compile_request, escape_pointer_part
from flexmech.service.solvers.reports import plain

if TYPE_CHECKING:  # the export's code generation is imported when a job is prepared or run
    from flexmech.service.export.plan import ExportOptions, ExportPlan

Pointer = Annotated[str, Field(pattern=r"^/", max_length=MAX_POINTER_CHARS)]
OutputName = Annotated[str, Field(min_length=1, max_length=128)]
AS_IN_THE_DOCUMENT = "as in the document"  # the manifest's model when the request names none


class ExportTarget(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    output: str = Field(min_length=1, max_length=128, description="the output the target task brings to `equals`")
    equals: float = Field(description="the output's goal, in its unit (the document's units)")
    by: str = Field(
        pattern=r"^/",
        max_length=MAX_POINTER_CHARS,
        description="the exported input (JSON pointer) the target task solves for",
        examples=["/loads/actuation/force/1"],
    )


class ExportJobOptions(JobOptions):
    name: str = Field(
        "",
        max_length=64,
        description="C prefix of the library's functions and files, made a C identifier of at most 40 characters "
        "(default: from the document's name); refused when it has no ASCII letter or digit or is a name of the "
        "build's own (main, bench, check, all, test, m, math, ...)",
    )
    inputs: list[Pointer] = Field(
        default_factory=list,
        max_length=64,
        description="numeric fields of the document a caller of the library sets, by JSON pointer (default: every "
        "load and prescribed motion)",
        examples=[["/loads/actuation/force/1"]],
    )
    outputs: list[OutputName] = Field(
        default_factory=list,
        max_length=64,
        description="outputs the library returns, by name (default: the document's named outputs)",
        examples=[["end_effector.x", "end_effector.y"]],
    )
    ranges: dict[Pointer, tuple[float, float]] = Field(
        default_factory=dict,
        max_length=64,
        description="per input (JSON pointer): [low, high] in the document's units; outside it a call returns "
        "OUT_OF_RANGE (default: the field's own checks)",
    )
    target: ExportTarget | None = Field(
        None, description="the target task: an input solved for an output's goal (default: the document's sweep until)"
    )
    contact: Literal["auto", "yes", "no"] = Field(
        "auto",
        description="the contact state task of a contact document: auto (exported when it can be, else the manifest's "
        "contact.note says why), yes (the job fails saying why when it cannot), no",
    )
    contact_outputs: list[OutputName] = Field(
        default_factory=list,
        max_length=64,
        description="outputs of the contact task, by name (default: the document's contact path outputs)",
    )
    max_iterations: int = Field(30, ge=1, le=1000, description="Newton steps per call of the library, at most")
    tolerance: float = Field(1e-12, gt=0, lt=1e-3, description="converged when the nondimensional |R|_inf is below it")
    line_search_halvings: int = Field(6, ge=0, le=30, description="halvings of a Newton step that does not lower |R|")


class ExportSpec(StoredJob, ExportJobOptions):
    model_config = ConfigDict(extra="ignore")


EXAMPLES = [
    {
        "example": "gripper",
        "model": "partial_nonlinear",
        "inputs": ["/loads/actuation/force/1"],
        "outputs": ["end_effector.x", "end_effector.y"],
        "ranges": {"/loads/actuation/force/1": [-100, 100]},
    },
]

_OWN_FIELDS = {
    "name",
    "inputs",
    "outputs",
    "contact",
    "contact_outputs",
    "max_iterations",
    "tolerance",
    "line_search_halvings",
}


def _in_request(pointer: str, spec: ExportSpec) -> str:
    """The request's field an export problem names: the export's own fields as they are (a
    range's input pointer escaped as one part; the target's input is `by`), the document's under
    /document (the target taken from the document's sweep: /document/sweep; an output of the
    document's when the request chose none: /document/outputs/<name>)."""
    first = pointer.split("/")[1] if pointer.count("/") else ""
    if first == "ranges":
        return "/ranges/" + escape_pointer_part(pointer.removeprefix("/ranges/"))
    if first == "target":
        if spec.target is None:
            return "/document/sweep/until"
        return "/target/by" if pointer == "/target/input" else pointer
    if first == "outputs" and not (spec.outputs and re.fullmatch(r"/outputs(/\d+)?", pointer)):
        return "/document" + pointer
    return pointer if first in _OWN_FIELDS else "/document" + pointer


def export_options(spec: ExportJobOptions) -> ExportOptions:
    """The request's service.export.plan.ExportOptions."""
    from flexmech.service.export.plan import ExportOptions

    target = spec.target
    return ExportOptions(
        name=spec.name,
        inputs=tuple(spec.inputs),
        outputs=tuple(spec.outputs),
        ranges={pointer: (low, high) for pointer, (low, high) in spec.ranges.items()},
        target=None if target is None else (target.output, target.equals, target.by),
        contact=spec.contact,
        contact_outputs=tuple(spec.contact_outputs),
        max_iterations=spec.max_iterations,
        tolerance=spec.tolerance,
        line_search_halvings=spec.line_search_halvings,
    )


def _checked(spec: ExportSpec, mech: Mechanism, limits: Limits) -> ExportPlan:
    """The export's plan (service.export.plan.ExportPlan), or MechanismError naming the request's field."""
    from flexmech.service.export.plan import export_plan

    if mech.n_free == 0:
        raise MechanismError("/document/bodies", "nothing moves: every body is fixed or prescribed, nothing to export")
    check_export_unknowns(mech.n_free, limits)
    check_export_build(mech)
    try:
        plan = export_plan(mech, spec.model or AS_IN_THE_DOCUMENT, export_options(spec))
        check_export_iteration(
            mech.n_free, spec.max_iterations, spec.line_search_halvings, spec.tolerance, bool(plan.contact_outputs)
        )
        return plan
    except MechanismError as exc:
        fields = {p: _in_request(p, spec) for p, _ in exc.problems} | {exc.pointer: _in_request(exc.pointer, spec)}

        def said(message: str) -> str:  # another field a message names, "(/outputs/tip)", as the request's too
            for plan_field, request_field in fields.items():
                message = message.replace(f"({plan_field})", f"({request_field})")
            return message

        problems = tuple((fields[p], said(m)) for p, m in exc.problems)
        raise MechanismError(fields[exc.pointer], said(exc.problem), problems) from None


def _mechanism(spec: ExportSpec, limits: Limits = Limits()) -> Mechanism:
    if spec.options:
        raise MechanismError(
            "/options",
            "an export's iteration is its own (max_iterations, tolerance, line_search_halvings): give no Newton options",
        )
    return compile_request(spec.document, spec.model, spec.overrides, limits)


def export_point(spec: ExportSpec) -> JSON:
    """The export written into a temporary folder (named as the library) and archived: the
    manifest and the archive as stored (its bytes base64). The spec was checked when the job
    was created (ExportJob.prepare)."""
    from flexmech.service.export.library import archive, export_library

    mech = _mechanism(spec)
    with tempfile.TemporaryDirectory(prefix="flexmech-export-") as scratch:
        written = Path(scratch) / "export"
        manifest = export_library(mech, written, spec.model or AS_IN_THE_DOCUMENT, export_options(spec))
        folder = written.rename(Path(scratch) / manifest["name"])
        data = archive(folder)
    return {
        "manifest": plain(manifest),
        "archive": {
            "file": f"{manifest['name']}.tar.gz",
            "bytes": len(data),
            "sha256": hashlib.sha256(data).hexdigest(),
            "base64": base64.b64encode(data).decode("ascii"),
        },
    }


def archive_of(point: JSON) -> tuple[str, bytes]:
    """(file name, bytes) of a stored export point."""
    packed = point["archive"]
    return packed["file"], base64.b64decode(packed["base64"])


class ExportJob:
    name = "export"
    paged = False
    Options = ExportJobOptions
    route, operation_id, request_name = "exports", "create_export", "ExportRequest"
    title = "Start an export of the mechanism's solver as a C99 library"
    summary = "A job: the mechanism's solver as dependency-free C99 for controllers, as a .tar.gz archive."
    description = (
        "The library (equilibrium, tangent stiffness and target tasks; header, manifest.json, Makefile, "
        "CMakeLists.txt, example, benchmark, checks, ctypes loader) is generated in a worker. The result (at "
        "/v1/jobs/{id}/result) is the manifest and the archive's name, size and SHA-256; the archive is at "
        "/v1/jobs/{id}/archive. Nothing is compiled on the server: build it with make."
    )
    examples = EXAMPLES

    def prepare(self, stored: JSON, limits: Limits) -> Plan:
        spec = read_spec(ExportSpec, stored)
        plan = _checked(spec, _mechanism(spec, limits), limits)
        return Plan(1, {"name": plan.name})

    def tasks(self, spec: JSON, plan: JSON, finished: Mapping[int, JSON], chunk_size: int) -> list[JSON]:
        return [] if 0 in finished else [{"indices": [0]}]

    def follow_up(
        self, spec: JSON, plan: JSON, task: JSON, finished: Mapping[int, JSON], chunk_size: int
    ) -> list[JSON]:
        return []

    def run(self, stored: JSON, task: JSON) -> list[tuple[int, JSON]]:
        control = TaskControl(task)
        if control.between_points():  # cancelled, or asked to yield before it began: it runs later
            return []
        # Asked to yield while it runs, it ends like a cancelled one and runs again later, whole.
        with stop_scope(control.stop_or_yield):
            try:
                point = export_point(read_spec(ExportSpec, stored))
            except MechanismError:
                if control.interrupted:  # its check was cut short: no finding of the export's
                    return []
                raise
        return [] if control.interrupted or control.should_stop() else [(0, point)]  # cut short: not stored

    def failed(self, point: JSON) -> bool:
        return False  # an export that cannot be written fails its task, and so its job

    def result(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> JSON:
        point = finished.get(0)
        if point is None:
            return {"status": "pending", "manifest": None, "archive": None}  # not stored (yet)
        described = {k: v for k, v in point["archive"].items() if k != "base64"}
        return {"status": "exported", "manifest": point["manifest"], "archive": described}

    def archive(self, stored: JSON, plan: JSON, finished: Mapping[int, JSON]) -> tuple[str, bytes] | None:
        """(file name, bytes) of the job's .tar.gz, None until it is stored."""
        point = finished.get(0)
        return None if point is None else archive_of(point)


EXPORT = ExportJob()
