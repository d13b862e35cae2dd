"""Fixtures of the motion tests: the HC10 on a YRC1000 (x87) and on an FS100."""

from __future__ import annotations

import pytest

from pymotoros.motion import GroupAxes

from .helpers import axes_for


@pytest.fixture
def hc10() -> GroupAxes:
    return axes_for()


@pytest.fixture
def hc10_fs100() -> GroupAxes:
    return axes_for(controller="fs100")
