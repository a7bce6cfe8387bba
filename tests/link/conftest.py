import pytest

from plcbuilder.controller.controller import Controller
from plcbuilder.link.client import Client
from plcbuilder.link.pacing import Simulation
from plcbuilder.link.server import ControllerServer
from plcbuilder.link.service import Service
from tests.link.linkkit import compile_programs, image_of


@pytest.fixture(autouse=True)
def _private_runtime_file(tmp_path, monkeypatch):
    """Never touch the user's own runtime file."""
    monkeypatch.setenv("PLCBUILDER_CONTROLLER_FILE", str(tmp_path / "rt" / "controller.json"))


@pytest.fixture(scope="session")
def programs():
    return compile_programs()


@pytest.fixture(scope="session")
def image(programs):
    return image_of(programs)


@pytest.fixture
def paused(image):
    """A service over a paused simulation thread (time moves only by 'step')."""
    sim = Simulation(Controller(), "pause")
    svc = Service(sim, controller_factory=Controller)
    svc.load_image(image)
    sim.start()
    yield svc
    sim.stop()


@pytest.fixture
def server(image):
    """A served controller with the image loaded, 50x real time, short timeouts."""
    srv = ControllerServer(port=0, speed="factor", factor=50.0, image=image,
                           frame_timeout=0.2, hello_timeout=1.0, max_clients=200)
    srv.sim.batch = 0.001
    srv.start()
    yield srv
    srv.close()


@pytest.fixture
def client(server):
    c = Client.connect(*server.address, server.token, timeout=10.0)
    yield c
    c.close()
