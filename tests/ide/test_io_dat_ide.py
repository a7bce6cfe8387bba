"""A project's IO.DAT in the IDE: the project tree lists it, and the embedded
controller the IDE starts gets it (SPEC §9, "physical inputs preset from an
`IO.DAT` file in the project")."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from tests.ide.test_main_window import (make_project, make_window, prompts,  # noqa: E402,F401
                                        settings, settle)


def test_tree_lists_io_dat_and_the_controller_gets_it(make_window, tmp_path, qtbot):  # noqa: F811
    """SPEC §9: "physical inputs preset from an `IO.DAT` file in the project" —
    the IDE shows the file and passes it to the controller it starts."""
    root = make_project(tmp_path / "proj")
    win = make_window()
    assert win.open_project(root)
    settle(qtbot, win)
    texts = {it.text(0) for it in win.tree._all_items()}
    assert "Input presets  ·  IO.DAT" not in texts
    # passed all the same: the controller generates a missing IO.DAT ("File IO.DAT is
    # generated automatically if it does not exist on the flash disk", the softMC seed)
    args = win.run_actions.controller_args()
    assert args[args.index("--io-dat") + 1] == str(root / "IO.DAT")

    (root / "IO.DAT").write_text("INP=0x01\nDIP=0x00\n", encoding="ascii")
    win.tree.refresh()
    settle(qtbot, win)
    qtbot.waitUntil(lambda: "Input presets  ·  IO.DAT" in
                    {it.text(0) for it in win.tree._all_items()}, timeout=5000)
    args = win.run_actions.controller_args()
    assert args[args.index("--io-dat") + 1] == str(root / "IO.DAT")
