"""The control API's ``/docs`` page, served without the internet.

FastAPI's default ``/docs`` page loads swagger-ui's script and style from a CDN, so on a
shop-floor network without internet it stays blank. The same swagger-ui files ship in
the ``swagger-ui-bundle`` package; they are served from ``/docs/assets`` and the page
points there.

FastAPI's other page, ReDoc at ``/redoc``, loads its script from a CDN too and no package
worth a dependency ships it, so it is not served: ``/redoc`` redirects to ``/docs``,
which shows the same OpenAPI schema, so an old bookmark lands on a page that works.
"""

from __future__ import annotations

from typing import Final

from fastapi import FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from swagger_ui_bundle import swagger_ui_path

DOCS_URL: Final = "/docs"
ASSETS_URL: Final = "/docs/assets"
REDOC_URL: Final = "/redoc"


def install_offline_docs(app: FastAPI) -> None:
    """Serve ``/docs`` with swagger-ui from the installed package, and redirect
    ``/redoc`` there (create the app with ``docs_url=None, redoc_url=None`` so that
    FastAPI does not add its CDN pages)."""
    for name in ("docs_url", "redoc_url"):
        if getattr(app, name) is not None:
            raise ValueError(
                f"create the FastAPI app with {name}=None: FastAPI's page at "
                f"{getattr(app, name)} loads its scripts from a CDN (blank offline)"
            )
    app.mount(ASSETS_URL, StaticFiles(directory=swagger_ui_path), name="swagger-ui")
    openapi_url = app.openapi_url or "/openapi.json"

    @app.get(DOCS_URL, include_in_schema=False)
    async def docs() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=openapi_url,
            title=f"{app.title} - docs",
            swagger_js_url=f"{ASSETS_URL}/swagger-ui-bundle.js",
            swagger_css_url=f"{ASSETS_URL}/swagger-ui.css",
            swagger_favicon_url=f"{ASSETS_URL}/favicon-32x32.png",
        )

    @app.get(REDOC_URL, include_in_schema=False)
    async def redoc() -> RedirectResponse:
        return RedirectResponse(DOCS_URL)


__all__ = ["ASSETS_URL", "DOCS_URL", "REDOC_URL", "install_offline_docs"]
