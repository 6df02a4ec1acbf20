"""Parsing request bodies away from the event loop's interpreter.

The strict reader (models.documents.reading: duplicate keys, nesting depth) is Python: a 0.9 MB body of
ten thousand small objects takes 0.26 s of it. On a thread of the server that time is taken
from the event loop in 5 ms slices, so eight clients sending such bodies held /v1/health at a
p99 of 259 ms. A body of LARGE_BODY bytes or more is therefore parsed in a parser process (a
one-worker api.solver_pool: forked by the fork server, ending with the server even on kill -9,
replaced if it dies); only its result comes back (unpickling is C: 16 ms for that body).
Smaller bodies parse on one thread in well under a slice, and so does a large one when the
parser process failed it; small ones (under SMALL_BODY, most requests) parse on the loop itself.
"""

from __future__ import annotations

import asyncio
import logging
from concurrent.futures import ThreadPoolExecutor

from flexmech.api.errors import ApiError
from flexmech.models import MechanismError
from flexmech.models.documents.reading import DuplicateKey, parse_json

log = logging.getLogger("flexmech.bodies")

LARGE_BODY = 128 * 1024  # bytes: from here a body is parsed in the parser process
SMALL_BODY = 16 * 1024  # bytes: below, a body parses on the event loop (about 40 us for a 2 kB gripper
# request, 0.3 ms at most): the hand-off to the parsing thread and back cost more than that
PARSER_NAME = b"flexmech-parser"  # what ps shows for the parser process
PARSE_LIMIT = 30.0  # seconds: a megabyte parses in a third of one

# One parsing thread: parses queue behind each other rather than all contend with the loop for
# the interpreter (the loop then gets its turn at every switch interval, 5 ms).
_thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="flexmech-body-parser")
_parser = None  # the parser process' pool, started by the first large body


def parsed_outcome(body: bytes) -> tuple:
    """("ok", value), ("duplicate_key", key) or ("malformed_json", problem): plain values that
    cross a process boundary."""
    try:
        return "ok", parse_json(body, "the body")
    except MechanismError as exc:
        # the reader raises ours from its own (context kept, not shown): the duplicate's key
        if isinstance(exc.__context__, DuplicateKey):
            return "duplicate_key", exc.__context__.key
        return "malformed_json", exc.problem


async def parse_body(body: bytes) -> tuple:
    """parsed_outcome(body), computed on the parsing thread or, for a large body, in the parser
    process."""
    global _parser
    if len(body) < SMALL_BODY:
        return parsed_outcome(body)
    if len(body) >= LARGE_BODY:
        if _parser is None:
            from flexmech.api.solver_pool import SolverPool

            _parser = SolverPool(1, build_allowance=0.0, name=PARSER_NAME)
        try:
            return await _parser.call(parsed_outcome, body, time_limit=PARSE_LIMIT)
        except ApiError as exc:  # it ended or ran out of time; it is replaced
            log.warning("the body parser failed a %d-byte body (%s); parsing it here", len(body), exc.message)
    return await asyncio.get_running_loop().run_in_executor(_thread, parsed_outcome, body)


def close() -> None:
    """End the parser process (the server stops)."""
    global _parser
    if _parser is not None:
        _parser.close()
        _parser = None
