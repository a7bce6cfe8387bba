"""The IDE's run panels: live plots, inputs, watch and log of a controller.

``RunPanels(main_window, connection)`` makes the docks; the main window places
them (``.docks()``), passes pin names from the project's pins.h
(``.set_pin_names(inputs, outputs)``) and listens to ``sig_open_location``.
"""

from plcbuilder.ide.panels.runpanels import (RunPanels, default_pin_names,
                                             pin_names_from_defines, pin_names_from_header)

__all__ = ["RunPanels", "pin_names_from_defines", "pin_names_from_header", "default_pin_names"]
