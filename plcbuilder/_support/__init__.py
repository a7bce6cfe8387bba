"""Helpers every layer may use: standard library only, nothing of ours.

    files        read_bounded (a regular file, at most N bytes), atomic_write (replace a
                 regular file all at once), FileRefused (what both refuse)
    lazy         lazy_names (a package's names loaded from its modules on first use, PEP 562)
    package_data data_folder (a folder of the package's data: a Path on disk, quickly)
    numbers      parse_int_in (a whole number in a range, never wrapped), INT32, WORD32
    procs        pid_alive (does a process still run)
    strictjson   strict_json_loads (no repeated keys, no NaN)
    toml_errors  where a TOML key or a parse error is (line numbers for messages)
"""
