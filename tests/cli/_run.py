"""What the command-line tests share: the command run in this process."""

from __future__ import annotations

from plcbuilder.cli.main import main


def run_cli(capsys, *argv) -> tuple[int, str, str]:
    """``plcbuilder ARGV`` in-process: (exit status, stdout, stderr). Each
    argument is passed as str; argparse's own usage errors (SystemExit) give
    their exit status like any other."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err
