"""How the store counts bytes and keeps documents once: the queries quotas and deletion share.

A value's bytes are those of its JSON text (UTF-8, no blanks); a packed point's, those of its
compressed text. A key's usage counts its jobs' bytes and, once each, the documents they use.
"""

from __future__ import annotations

import hashlib
import json
import zlib
from datetime import datetime
from typing import Any

from sqlalchemy import case, delete, exists, func, select
from sqlalchemy.orm import Session

from flexmech.service.jobs.quotas import Usage
from flexmech.service.jobs.store_schema import ACTIVE, NAME_CHARS, DocumentRow, JobRow

PACK_BYTES = 32_768  # a point whose JSON is longer is stored zlib-compressed (an export's archive)


def json_text(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def json_bytes(value: Any) -> int:
    return len(json_text(value).encode("utf-8"))


def abridged(name: str) -> str:
    """A name as listings show it: at most NAME_CHARS characters, then '...'."""
    return name if len(name) <= NAME_CHARS else name[:NAME_CHARS] + "..."


def document_row(document: dict, now: datetime) -> DocumentRow:
    """The document's row, keyed by the SHA-256 of its JSON text as sent (key order kept, so a
    job reads back the very document it was given)."""
    encoded = json_text(document).encode("utf-8")
    name = document.get("name")
    return DocumentRow(
        digest=hashlib.sha256(encoded).hexdigest(),
        body=document,
        name=abridged(name if isinstance(name, str) else ""),
        bytes=len(encoded),
        created_at=now,
    )


def packed_point(data: dict) -> tuple[dict, bytes | None, int]:
    """(data, packed, bytes) of a point as stored: a large one compressed into `packed`."""
    encoded = json_text(data).encode("utf-8")
    if len(encoded) <= PACK_BYTES:
        return data, None, len(encoded)
    packed = zlib.compress(encoded, 6)
    return {}, packed, len(packed)


def unpacked_point(data: dict, packed: bytes | None) -> dict:
    return data if packed is None else json.loads(zlib.decompress(packed))


def job_counts(s: Session, *where) -> tuple[int, int, int]:
    """(jobs, those queued or running, the bytes the jobs hold) of the jobs `where` selects
    (all without a condition); their documents' bytes are apart."""
    jobs, running, job_bytes = s.execute(
        select(
            func.count(JobRow.id),
            func.coalesce(func.sum(case((JobRow.status.in_(ACTIVE), 1), else_=0)), 0),
            func.coalesce(func.sum(JobRow.bytes), 0),
        ).where(*where)
    ).one()
    return int(jobs), int(running), int(job_bytes)


def usage_of(s: Session, owner: str) -> Usage:
    """The owner's jobs, those queued or running, and its bytes (each document once)."""
    jobs, running, job_bytes = job_counts(s, JobRow.owner == owner)
    document_bytes = s.scalar(
        select(func.coalesce(func.sum(DocumentRow.bytes), 0)).where(
            DocumentRow.digest.in_(select(JobRow.document).where(JobRow.owner == owner))
        )
    )
    return Usage(jobs, running, job_bytes + int(document_bytes or 0))


def owner_uses_document(s: Session, owner: str, digest: str) -> bool:
    return bool(s.scalar(select(exists().where(JobRow.owner == owner, JobRow.document == digest))))


def drop_unused_documents(s: Session, digests: set[str]) -> None:
    """Delete those of the documents no job uses any more."""
    for digest in digests:
        s.execute(delete(DocumentRow).where(DocumentRow.digest == digest, ~exists().where(JobRow.document == digest)))
