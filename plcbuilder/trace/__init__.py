"""Trace files, CSV and VCD export, and comparison (SPEC §7).

    file      save(trace, path) / load(path): the documented .plctrace format
    export    export(trace, path): CSV (per change or per tick) and VCD
    compare   compare(a, b): the first tick where two traces differ, and in what
"""
