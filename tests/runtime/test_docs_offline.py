"""The control API's /docs page loads without the internet: no external URL, assets served."""

from __future__ import annotations

import re

import httpx
import pytest
from fastapi import FastAPI

from pymotoros.runtime.docs_page import install_offline_docs

MIN_BUNDLE_BYTES = 100_000
"""swagger-ui's bundle is about a megabyte; a stub or an error page is far smaller."""


async def test_docs_page_references_only_local_assets(api: httpx.AsyncClient) -> None:
    page = await api.get("/docs")
    assert page.status_code == 200
    urls = re.findall(r"""(?:src|href|url)\s*[:=]\s*['"]([^'"]+)['"]""", page.text)
    assert urls, page.text
    external = [u for u in urls if re.match(r"(?i)(https?:)?//", u)]
    assert external == []
    assert not re.search(r"(?i)https?://", page.text)
    for url in urls:
        response = await api.get(url)
        assert response.status_code == 200, url
    bundle = await api.get("/docs/assets/swagger-ui-bundle.js")
    assert len(bundle.content) > MIN_BUNDLE_BYTES
    assert "javascript" in bundle.headers["content-type"]
    css = await api.get("/docs/assets/swagger-ui.css")
    assert "text/css" in css.headers["content-type"]


async def test_redoc_is_not_served_from_a_cdn_but_leads_to_the_offline_docs(
    api: httpx.AsyncClient,
) -> None:
    """FastAPI's ReDoc page loads its script from a CDN (blank offline): /redoc sends the
    reader to /docs instead."""
    response = await api.get("/redoc")
    assert response.status_code == 307
    assert response.headers["location"] == "/docs"
    assert "cdn" not in (await api.get("/docs")).text.lower()


def test_an_app_with_fastapis_cdn_pages_is_refused() -> None:
    with pytest.raises(ValueError, match="redoc_url=None"):
        install_offline_docs(FastAPI(docs_url=None))
    with pytest.raises(ValueError, match="docs_url=None"):
        install_offline_docs(FastAPI(redoc_url=None))
