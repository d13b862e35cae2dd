"""The control API's /docs and /redoc pages load without the internet: no external URL,
assets served (tests/client/test_docs_browser.py renders them in Chromium)."""

from __future__ import annotations

import re

import httpx
import pytest
from fastapi import FastAPI

from pymotoros.runtime.docs_page import install_offline_docs

MIN_BUNDLE_BYTES = 100_000
"""swagger-ui's bundle is about a megabyte; a stub or an error page is far smaller."""


async def _only_local_assets(api: httpx.AsyncClient, page_url: str) -> list[str]:
    """The page at ``page_url`` loads nothing from another host, and every file it names
    is served; returns those URLs."""
    page = await api.get(page_url)
    assert page.status_code == 200
    policy = page.headers["content-security-policy"]
    assert "default-src 'self'" in policy
    assert "img-src 'self' data:" in policy
    urls = re.findall(r"""(?:src|href|url)\s*[:=]\s*['"]([^'"]+)['"]""", page.text)
    assert urls, page.text
    external = [u for u in urls if re.match(r"(?i)(https?:)?//", u)]
    assert external == []
    assert not re.search(r"(?i)https?://", page.text)
    assert "cdn" not in page.text.lower()
    for url in urls:
        response = await api.get(url)
        assert response.status_code == 200, url
    return urls


@pytest.mark.parametrize(
    ("page", "script"),
    [("/docs", "swagger-ui-bundle.js"), ("/redoc", "redoc.standalone.js")],
)
async def test_docs_pages_reference_only_local_assets(
    api: httpx.AsyncClient, page: str, script: str
) -> None:
    urls = await _only_local_assets(api, page)
    assert f"/docs/assets/{script}" in urls
    bundle = await api.get(f"/docs/assets/{script}")
    assert len(bundle.content) > MIN_BUNDLE_BYTES
    assert "javascript" in bundle.headers["content-type"]


async def test_swagger_ui_reads_openapi_3_1(api: httpx.AsyncClient) -> None:
    """swagger-ui 4 refuses FastAPI's OpenAPI 3.1 ("does not specify a valid version
    field"); the served bundle is swagger-ui 5 (the browser test shows it rendering)."""
    schema = (await api.get("/openapi.json")).json()
    assert schema["openapi"].startswith("3.1")
    bundle = (await api.get("/docs/assets/swagger-ui-bundle.js")).text
    assert "isOAS31" in bundle  # swagger-ui 5's OpenAPI 3.1 plugin (absent from 4.x)
    css = await api.get("/docs/assets/swagger-ui.css")
    assert "text/css" in css.headers["content-type"]


def test_an_app_with_fastapis_cdn_pages_is_refused() -> None:
    with pytest.raises(ValueError, match="redoc_url=None"):
        install_offline_docs(FastAPI(docs_url=None))
    with pytest.raises(ValueError, match="docs_url=None"):
        install_offline_docs(FastAPI(redoc_url=None))
