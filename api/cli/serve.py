"""`flexmech serve`: the HTTP API under uvicorn."""

from __future__ import annotations

from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import EXIT_ERROR, consoles, print_error


@app.command()
def serve(
    host: Annotated[
        str | None, typer.Option("--host", help="Address to listen on (default FLEXMECH_HOST or 127.0.0.1).")
    ] = None,
    port: Annotated[int | None, typer.Option("--port", help="Port (default FLEXMECH_PORT or 8000).")] = None,
) -> None:
    """Run the HTTP API with uvicorn. Settings come from FLEXMECH_* environment variables
    (database, Dask address, API keys, limits); by default an SQLite file and a process pool."""
    import uvicorn
    from pydantic import ValidationError

    from flexmech.service.settings import Settings

    _, err = consoles()
    try:
        settings = Settings()
    except ValidationError as exc:
        first = exc.errors()[0]
        where = "FLEXMECH_" + str(first["loc"][0]).upper() if first["loc"] else "settings"
        print_error(err, f"{where}: {first['msg']}")
        raise typer.Exit(EXIT_ERROR) from None
    # The app is named by import string so that the service layer never imports the api package.
    # The protocol adds a deadline for a request's headers (api.protocol), which uvicorn lacks.
    uvicorn.run(
        "flexmech.api.app:create_app",
        factory=True,
        host=host or settings.host,
        port=port or settings.port,
        log_level=settings.log_level,
        http="flexmech.api.protocol:HeaderTimeoutProtocol",
    )
