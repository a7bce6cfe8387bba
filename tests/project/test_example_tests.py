"""The example project (``plcbuilder new``) ships scenario tests of its
procedures, and they pass."""

from __future__ import annotations

from plcbuilder import api


def test_the_example_projects_tests_pass(tmp_path):
    project = api.create_project(tmp_path / "ex")
    tr = api.test(project.root, api.TestOptions(jobs=1))
    assert not tr.errors and tr.built
    failed = [f.text() for r in tr.results for f in r.failures]
    assert not failed, failed
    assert tr.exit_status == 0
    names = " | ".join(r.name for r in tr.results)
    for proc in ("M03", "M05", "M07", "M08", "M09", "M71", "M80", "M81", "LUBE",
                 "__HANDLER_INIT", "plc_exit_plasma_timeout"):
        assert proc in names
    assert len(tr.results) >= 13


def test_the_example_tests_cover_every_hardware_procedure(tmp_path):
    project = api.create_project(tmp_path / "ex")
    tr = api.test(project.root, api.TestOptions(coverage=True, jobs=1))
    cov = {c.name: c for c in tr.run.coverage}
    assert not [n for n, c in cov.items() if c.covered == 0]    # every procedure ran
    assert cov["M71"].percent == 100.0          # arc OK, timeout and no air: every line
    assert cov["M03"].percent == 100.0
