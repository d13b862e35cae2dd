"""The control API's ``/docs`` and ``/redoc`` pages, served without the internet.

FastAPI's own pages load swagger-ui's and ReDoc's scripts from a CDN, so on a shop-floor
network without internet they stay blank. The ``fastapi-offline`` package ships those
files (swagger-ui 5 and ReDoc 2, the first versions that read the OpenAPI 3.1 document
FastAPI writes; the ``swagger-ui-bundle`` package stopped at swagger-ui 4, which shows
"does not specify a valid version field"). Only its static files are used: they are
served from ``/docs/assets`` and the two pages point there, with swagger-ui's online
validator switched off. ReDoc's sidebar still names an image on its maker's CDN, so both
pages are sent with a Content-Security-Policy that allows this server only: the browser
does not even try another host (no hang on a network without internet, no leak on one
with it).
"""

from __future__ import annotations

from collections.abc import Callable
from importlib.resources import files
from pathlib import Path
from typing import Final

from fastapi import FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

DOCS_URL: Final = "/docs"
ASSETS_URL: Final = "/docs/assets"
REDOC_URL: Final = "/redoc"
ASSETS_PACKAGE: Final = "fastapi_offline"
"""The package whose ``static`` folder holds swagger-ui-bundle.js, swagger-ui.css,
redoc.standalone.js and favicon.png."""
CONTENT_SECURITY_POLICY: Final = "; ".join(
    (
        "default-src 'self'",
        "img-src 'self' data:",  # swagger-ui's icons are data: URLs
        "style-src 'self' 'unsafe-inline'",  # both apps style their elements inline
        "script-src 'self' 'unsafe-inline'",  # FastAPI's page starts swagger-ui inline
        "worker-src 'self' blob:",  # ReDoc's search index runs in a blob: worker
        "connect-src 'self'",
        "frame-ancestors 'self'",  # no other site may frame the pages (clickjacking)
    )
)
"""What the two pages may load: from this server only."""
SWAGGER_UI_PARAMETERS: Final = {
    "validatorUrl": None,  # the badge would ask validator.swagger.io about the schema
}


def assets_directory() -> Path:
    """The installed folder of swagger-ui's and ReDoc's files."""
    path = Path(str(files(ASSETS_PACKAGE) / "static"))
    if not (path / "swagger-ui-bundle.js").is_file():
        raise FileNotFoundError(
            f"{path}: swagger-ui-bundle.js is missing; reinstall the docs pages' files "
            "with `python -m pip install --force-reinstall fastapi-offline`"
        )
    return path


def _serve_page(app: FastAPI, url: str, render: Callable[[], HTMLResponse]) -> None:
    """A GET route (outside the schema) answering ``render()`` under our CSP."""

    async def page() -> HTMLResponse:
        response = render()
        response.headers["Content-Security-Policy"] = CONTENT_SECURITY_POLICY
        return response

    app.add_api_route(url, page, methods=["GET"], include_in_schema=False)


def install_offline_docs(app: FastAPI) -> None:
    """Serve ``/docs`` (swagger-ui) and ``/redoc`` (ReDoc) from the installed files
    (create the app with ``docs_url=None, redoc_url=None`` so that FastAPI does not add
    its CDN pages)."""
    for name in ("docs_url", "redoc_url"):
        if getattr(app, name) is not None:
            raise ValueError(
                f"create the FastAPI app with {name}=None: FastAPI's page at "
                f"{getattr(app, name)} loads its scripts from a CDN (blank offline)"
            )
    app.mount(ASSETS_URL, StaticFiles(directory=assets_directory()), name="docs-assets")
    openapi_url = app.openapi_url or "/openapi.json"
    favicon = f"{ASSETS_URL}/favicon.png"

    _serve_page(
        app,
        DOCS_URL,
        lambda: get_swagger_ui_html(
            openapi_url=openapi_url,
            title=f"{app.title} - docs",
            swagger_js_url=f"{ASSETS_URL}/swagger-ui-bundle.js",
            swagger_css_url=f"{ASSETS_URL}/swagger-ui.css",
            swagger_favicon_url=favicon,
            swagger_ui_parameters=dict(SWAGGER_UI_PARAMETERS),
        ),
    )
    _serve_page(
        app,
        REDOC_URL,
        lambda: get_redoc_html(
            openapi_url=openapi_url,
            title=f"{app.title} - ReDoc",
            redoc_js_url=f"{ASSETS_URL}/redoc.standalone.js",
            redoc_favicon_url=favicon,
            with_google_fonts=False,
        ),
    )


__all__ = [
    "ASSETS_URL",
    "CONTENT_SECURITY_POLICY",
    "DOCS_URL",
    "REDOC_URL",
    "assets_directory",
    "install_offline_docs",
]
