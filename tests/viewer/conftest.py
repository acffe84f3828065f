import pytest
from tests.viewer.viewer_client import Client, small_scene


def _open(scene, folder):
    from spectrace.viewer import start_view

    live, server = start_view(scene, save_folder=folder)
    return live, server, Client(server.url)


def _close(live, server) -> None:
    server.stop()
    live.close()
    live.session.close()


@pytest.fixture(scope="module")
def viewer(tmp_path_factory):
    """A Cornell box at 32 x 24, 4 spp, rendered to the end: for tests that change nothing."""
    live, server, client = _open(small_scene(), tmp_path_factory.mktemp("saves"))
    client.wait_done()
    yield live, server, client
    _close(live, server)


@pytest.fixture
def fresh_viewer(tmp_path):
    live, server, client = _open(small_scene(), tmp_path)
    client.wait_done()
    yield live, server, client
    _close(live, server)
