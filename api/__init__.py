"""HTTP interface of flexmech (FastAPI app factory, routers, schemas, Python client).

Empty until the service issue lands; the package exists so the distribution's layout is
the one in DESIGN.md and the client can later be installed without CasADi or FastAPI.
"""
