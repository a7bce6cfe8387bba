"""The IDE's run panels: live plots, inputs, watch and log of a controller.

``RunPanels(main_window, connection)`` makes the docks; the main window places
them (``.docks()``), passes pin names from the project's pins.h
(``.set_pin_names(inputs, outputs)``) and listens to ``sig_open_location``.

The names load on first use (PEP 562): importing one light panel of this
package (the Outline, the disassembly) does not load pyqtgraph and numpy, which
the IDE needs only once its window is painted.
"""

from __future__ import annotations

from plcbuilder._support.lazy import lazy_names

__all__ = ["RunPanels", "pin_names_from_defines", "pin_names_from_header", "default_pin_names"]

__getattr__ = lazy_names(__name__, {name: "runpanels" for name in __all__})
