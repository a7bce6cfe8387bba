"""Helpers every layer may use: standard library only, nothing of ours.

    files        atomic_write (replace a file all at once)
    procs        pid_alive (does a process still run)
    strictjson   strict_json_loads (no repeated keys, no NaN)
    toml_errors  where a TOML key or a parse error is (line numbers for messages)
"""
