# SPDX-License-Identifier: MIT
import pytest

from iec2kmod import container


@pytest.fixture(scope="session")
def build_image() -> str:
    """Tag of the module-build image; FAILS (never skips) with what to do when
    docker or the image is not there."""
    try:
        client = container.docker_client()
        tag = container.image_tag()
        if not container._image_exists(client, tag):
            pytest.fail(f"container image {tag} is missing: run scripts/setup.sh "
                        "(or python -m iec2kmod.container ensure)", pytrace=False)
    except container.ContainerError as e:
        pytest.fail(str(e), pytrace=False)
    return tag
