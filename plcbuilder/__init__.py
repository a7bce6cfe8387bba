"""PLC Builder: an IDE, compiler and simulated controller for myCNC PLC procedures."""

__version__ = "0.1.0"
