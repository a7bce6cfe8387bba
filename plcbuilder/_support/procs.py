"""Is a process still running?"""

from __future__ import annotations

import os
import sys

_STILL_ACTIVE = 259
_QUERY_LIMITED_INFORMATION = 0x1000
_ACCESS_DENIED = 5


def pid_alive(pid: int) -> bool:
    """Whether a process with id ``pid`` is running now.

    POSIX: signal 0 tells (a process we may not signal still exists). Windows:
    ``os.kill(pid, 0)`` would end the process there, so the process is opened
    for a query and its exit code read (``STILL_ACTIVE`` while it runs; a
    process we may not open exists). Ids 0 and below are never alive."""
    if pid <= 0:
        return False
    if sys.platform == "win32":
        return _windows_alive(pid)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:                     # PermissionError: it exists, it is not ours
        return True
    return True


def _windows_alive(pid: int) -> bool:   # pragma: no cover - exercised on Windows only
    import ctypes
    from ctypes import wintypes

    kernel32 = ctypes.WinDLL("kernel32", use_last_error=True)
    kernel32.OpenProcess.restype = wintypes.HANDLE
    handle = kernel32.OpenProcess(_QUERY_LIMITED_INFORMATION, False, pid)
    if not handle:
        return ctypes.get_last_error() == _ACCESS_DENIED
    try:
        code = wintypes.DWORD()
        if not kernel32.GetExitCodeProcess(handle, ctypes.byref(code)):
            return True
        return code.value == _STILL_ACTIVE
    finally:
        kernel32.CloseHandle(handle)
