"""Hostile PLC sources of a given size (issue 24 item 1): deep nesting, long
runs of one token, thousands of errors; and an ordinary procedure of the same
size to measure them against. ``scripts/bench_hostile.py`` times them,
``scripts/attack_sources.py`` runs them through the command line.

    hostile(size) -> {name: source text of about ``size`` characters}
    ordinary(size) -> a valid hardware procedure of about ``size`` characters
"""

from __future__ import annotations


def ordinary(size: int) -> str:
    """Helper procedures with statements, conditions, loops and comments (the
    shape of scripts/bench_large_file.py's), each called from main: every
    stage runs on all of it, and it prints one line, that the code is larger
    than a procedure may be (no warning per procedure)."""
    parts = ["// an ordinary generated procedure\n#include pins.h\n"]
    n = len(parts[0])
    i = 0
    while n < size:
        block = (f"step{i}()\n{{\n"
                 f"  a{i % 7} = gvarget({6000 + i % 50}) + {i};   // read and adjust\n"
                 f"  if (a{i % 7} > 3) {{ portset(OUTPUT_SPINDLE); }} else {{ a{i % 7}--; }};\n"
                 f"  timer = {i % 9}; do {{ timer--; }} while (timer > 0);\n}};\n")
        call = f"  step{i}();\n"
        parts.append(block)
        n += len(block) + len(call)
        i += 1
    parts.append("main()\n{\n" + "".join(f"  step{k}();\n" for k in range(i))
                 + "  exit(99);\n};\n")
    return "".join(parts)


def _fill(head: str, unit: str, tail: str, size: int) -> str:
    return head + unit * max(1, (size - len(head) - len(tail)) // len(unit)) + tail


def hostile(size: int) -> dict[str, str]:
    half = size // 2
    return {
        # deep nesting
        "braces { x N, } x N": "{" * half + "}" * half,
        "main(){ x= then ( x N": _fill("main(){ x=", "(", "", size),
        "( x N then ) x N in an expression": "main(){ x=" + "(" * (half - 8) + ")" * (half - 8),
        "blocks {{{ in a procedure, unclosed": _fill("main(){", "{", "", size),
        "unary - x N": _fill("main(){ x=", "- ", "1;}", size),
        "unary - x N, no operand": _fill("main(){ x=", "- ", "", size),
        "if (1) x N": _fill("main(){ ", "if(1)", ";}", size),
        "else if chain": _fill("main(){ x=1; ", "if(x)x=1;else ", "x=2;}", size),
        "do x N": _fill("main(){ ", "do ", "", size),
        "call f(f(f(…": _fill("main(){ x=", "f(", "", size),
        "index a[a[a[…": _fill("main(){ x=", "a[", "", size),
        # long runs of one token
        "; x N": ";" * size,
        "} x N": "}" * size,
        ") x N in a procedure": _fill("main(){ x=1", ")", "}", size),
        "names x N": _fill("", "x ", "", size),
        "numbers x N in a procedure": _fill("main(){ ", "1 ", "}", size),
        "+ x N in an expression": _fill("main(){ x=1", "+1", ";}", size),
        "bad characters @ x N": _fill("main(){ ", "@ ", "}", size),
        "main() x N": _fill("", "main()", "", size),
        # thousands of errors
        "x = ; x N": _fill("main(){ ", "x = ;", "}", size),
        "missing ; x N": _fill("main(){ ", "x=1\n", "}", size),
        "for loops x N": _fill("main(){ ", "for(i=0;i<3;i++){x=1;}\n", "}", size),
        "stray ) per statement": _fill("main(){ ", "x=1);\n", "}", size),
        "statements outside procedures": _fill("", "x=1;\n", "main(){exit(99);};", size),
        "duplicate procedures": _fill("", "p(){x=1;};\n", "main(){p();exit(99);};", size),
        "unknown procedures called": "main(){\n" + "".join(
            f"q{i}();\n" for i in range(size // 8)) + "exit(99);\n};\n",
        "arguments f(1,1,1,…)": _fill("main(){ x=gvarget(", "1,", "1);}", size),
    }
