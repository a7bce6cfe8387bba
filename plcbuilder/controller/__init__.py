"""The simulated controller. The ABI tables it runs by (``abi``: register
addresses, axes, codes) are re-exported for the stages that drive it (link)."""

from plcbuilder.bytecode import abi

__all__ = ["abi"]
