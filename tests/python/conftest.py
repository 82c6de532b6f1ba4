"""Fixtures the Python tests share: a module's `scene` traced by a Renderer and by the Reference, each made once."""
import pytest

import vkray


@pytest.fixture(scope="module")
def renderer(scene):
    return vkray.Renderer(scene)


@pytest.fixture(scope="module")
def reference(scene):
    return vkray.Reference(scene)

