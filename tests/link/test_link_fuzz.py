"""A few seconds of hostile traffic against a served controller: it keeps
answering everybody else, and nothing escapes as a traceback."""

import os

from plcbuilder.link.client import Client
from tests.link.fuzzlink import fuzz

SECONDS = float(os.environ.get("PLCB_LINK_FUZZ_SECONDS", "3"))


def test_the_server_survives_hostile_traffic(server, capfd):
    bystander = Client.connect(*server.address, server.token, timeout=5)

    def alive() -> bool:
        try:
            return bool(bystander.ping()["pong"])
        except Exception:  # noqa: BLE001
            return False
    counts = fuzz(server.address, server.token, SECONDS, seed=17, alive=alive)
    assert counts["crashed"] == 0, counts
    assert counts["tried"] >= 20 and counts["refused"] > 0 and counts["accepted"] > 0, counts
    assert alive()
    state = bystander.state()
    assert isinstance(state.t_ms, int)
    bystander.close()
    assert server.server._thread.is_alive() and server.sim.running
    err = capfd.readouterr().err
    assert "Traceback" not in err, err[-2000:]
